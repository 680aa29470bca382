#pragma once
/// \file The geometric shapes of features (DESIGN.md "SHAPE"), their fitting and their distances.
/// Surfaces (patches): plane, cylinder, sphere, cone. Curves (lines): line, circle, arc.
/// Every fit is a robust initial estimate followed by nonlinear least squares (Levenberg–Marquardt
/// on the geometric distance); `rms` is the root-mean-square geometric distance of the samples.
#include <string>
#include <vector>

#include <Eigen/Core>

namespace s2c::features {

enum class ShapeType { freeform, plane, cylinder, sphere, cone, line, circle, arc };

/// "plane", "cylinder", … (the names of features.json).
const char* shape_name(ShapeType type);
/// Inverse of shape_name. \throw InvalidInput for an unknown name.
ShapeType shape_type(const std::string& name);
/// True for plane/cylinder/sphere/cone (a patch shape), false for line/circle/arc.
bool is_surface(ShapeType type);

/// One shape; which fields mean something depends on `type`:
/// - plane:    point (on the surface), dir = unit normal (outward where known)
/// - cylinder: point = a point on the axis, dir = unit axis, radius
/// - sphere:   point = centre, radius
/// - cone:     point = apex, dir = unit axis from the apex into the opening, half_angle_deg
/// - line:     point = one end, dir = unit direction towards the other end, length
/// - circle:   point = centre, dir = unit normal of its plane, radius
/// - arc:      circle fields + start, end (end points) and angle_deg (swept angle); the arc runs
///             counter-clockwise about dir from start to end (fitted arcs and circles: the samples'
///             walking direction)
struct Shape {
  ShapeType type = ShapeType::freeform;
  Eigen::Vector3d point = Eigen::Vector3d::Zero();
  Eigen::Vector3d dir = Eigen::Vector3d::UnitZ();
  double radius = 0.0;
  double half_angle_deg = 0.0;
  double length = 0.0;
  Eigen::Vector3d start = Eigen::Vector3d::Zero(), end = Eigen::Vector3d::Zero();
  double angle_deg = 0.0;
};

/// Unsigned geometric distance from `p` to the shape (surfaces: to the infinite surface;
/// line: to the segment; circle/arc: to the full circle). Freeform: 0.
double distance(const Shape& shape, const Eigen::Vector3d& p);

/// The unit surface normal of a surface shape at (the projection of) `p`, pointing away from
/// the axis / centre / plane side the normal gives. Zero for curves and freeform.
Eigen::Vector3d surface_normal(const Shape& shape, const Eigen::Vector3d& p);

/// distance() and surface_normal() of one shape at many points, with the same results: a cone's
/// cosine and sine of its half angle are taken once, not at every point (they were a tenth of
/// the metrics of a fit). Holds a reference to `shape`.
class ShapeMetric {
 public:
  explicit ShapeMetric(const Shape& shape);
  double distance(const Eigen::Vector3d& p) const;
  Eigen::Vector3d normal(const Eigen::Vector3d& p) const;

 private:
  const Shape* s_;
  double cos_ = 1.0, sin_ = 0.0;  ///< of the cone's half angle
};

/// Points (with their unit normals, when known) a shape is fitted to. `weights` (e.g. areas) may be
/// empty (all 1).
struct Samples {
  std::vector<Eigen::Vector3d> points;
  std::vector<Eigen::Vector3d> normals;  ///< same size as points, or empty (curves)
  std::vector<double> weights;           ///< same size as points, or empty
};

struct Fit {
  Shape shape;
  double rms = 0.0;          ///< RMS geometric distance of the samples (weighted by Samples::weights), mm
  double max_error = 0.0;    ///< largest distance of a sample, mm
  /// RMS angle between sample normals and surface normals (surfaces; weighted; unsigned, so the
  /// inward normals of a hole agree; samples with a zero normal are skipped)
  double normal_rms_deg = 0.0;
  bool ok = false;           ///< false when the samples cannot determine the shape (too few, degenerate)
};

/// Surface fits. The refinement runs on at most ~5000 samples (a deterministic stratified subset);
/// rms, max_error and normal_rms_deg are over all samples. ok is false for NaN/inf input, negative
/// weights, fewer samples of positive weight than parameters, all points equal, collinear points,
/// and when no finite shape results (fit_cone of an exact cylinder has no apex; of a noisy one it
/// gives a tiny half angle and a far apex). A zero normal means
/// "unknown". Plane: dir agrees with the mean sample normal when normals are given.
/// \throw InvalidInput if normals or weights are neither empty nor as many as the points.
Fit fit_plane(const Samples& s);
Fit fit_sphere(const Samples& s);
Fit fit_cylinder(const Samples& s);
Fit fit_cone(const Samples& s);
/// The fit of start.type refined from `start` (a fit of nearly the same samples, e.g. before a
/// region grew) instead of from the robust initial estimates: one Levenberg–Marquardt run, a
/// fraction of the cost. It finds the optimum near `start`, not necessarily the best of the
/// several starts fit_* tries. Plane: fit_plane (already exact). ok false as for fit_*, and for
/// curve or freeform starts.
Fit refit_surface(const Samples& s, const Shape& start);
/// Curves: the samples are polyline vertices in order (normals unused). Line: the PCA line from
/// the projection of the first sample towards that of the last. ok false as for the surfaces
/// (fewer than 2 distinct points for a line; collinear or fewer than 3 for a circle).
Fit fit_line(const Samples& s);
/// Circle through ordered samples; with `closed` false the result is an arc (type arc, with start,
/// end and angle_deg from the first and last sample) unless it sweeps almost 360° (≥ 350°).
Fit fit_circle(const Samples& s, bool closed);

}  // namespace s2c::features
