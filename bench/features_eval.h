#pragma once
// Ground-truth evaluation of the features stage (issue 5) against fixtures/parts/NAME.truth.json
// ("scan2cad.truth/1", fixtures/parts/README.md), and the benchmark's inputs (the fixture parts
// refined by longest-edge bisection, with Gaussian noise). Used by s2c-bench-features and by the
// CGAL Efficient RANSAC peer, so that both are measured by the same code on the same meshes.
//
// The evaluation never calls the features stage's own geometry (shape.h's distance/fit): the
// ground truth must not share code with what it judges. It uses the stage's value types, their
// names (constraint_name / constraint_kind) and is_surface only.
#include <cstdint>
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "s2c/core/mesh.h"
#include "s2c/features/feature_set.h"

namespace s2c::bench {

// ---------------------------------------------------------------------------------------------
// Ground truth

/// A primitive (plane/cylinder/sphere/cone) or a line (line/circle) of a truth file, in the
/// features' Shape convention (cylinder: point = axis_point, dir = axis_dir; cone: point = apex;
/// line: point = one end, dir, length; circle: point = centre, dir = normal).
struct TruthFeature {
  std::string id;
  features::Shape shape;
  bool inward = false;  ///< surface normal points towards the axis / centre (holes)
};

struct TruthConstraint {
  features::ConstraintKind kind = features::ConstraintKind::parallel;
  std::vector<std::string> members;
  std::optional<double> value;  ///< fixed_angle: degrees
};

struct Truth {
  std::string part;
  std::vector<TruthFeature> primitives;
  std::vector<TruthFeature> lines;
  std::vector<TruthConstraint> constraints;
  double diagonal = 0;  ///< of the truth bbox, mm
  /// The part's own mesh (the file named by "mesh"), empty when it is missing, and per face
  /// the primitive that claims it (README's rule: three vertices within 0.01 mm of the surface,
  /// normal within 10°), -1 for none. Bounds the infinite primitives for labelling.
  TriangleSoup mesh;
  std::vector<int> mesh_labels;
  /// Primitive pairs (i < j) that meet along a truth-mesh edge, with one point of that edge.
  std::map<std::pair<int, int>, Eigen::Vector3d> primitive_edges;
};

/// Reads a scan2cad.truth/1 file and the mesh it names (relative to the file; optional).
/// \throw InvalidInput naming the file and key, IoError when unreadable.
Truth read_truth(const std::filesystem::path& path);

// ---------------------------------------------------------------------------------------------
// Evaluation

struct Tolerances {
  double angle_deg = 2.0;           ///< axis / normal direction (sign-insensitive), cone half angle
  double radius_rel = 0.02;         ///< radius (and line length for equal_length), relative
  double position_mm = 0.2;         ///< plane offset, axis line, centre, apex, circle centre
  double label_normal_deg = 30.0;   ///< face → truth primitive: face normal vs surface normal
  double label_max_mm = 1.0;        ///< face → truth primitive: farther faces stay unlabelled
  double line_tol_mm = 0.5;         ///< a curve sample is correct within this of the other set
  double line_step_mm = 0.1;        ///< sampling step along curves
  double circle_radius_window = 0.25;  ///< circle radius error: candidates within this relative radius
};

/// A detected surface: its shape and the faces of the evaluated mesh that belong to it.
struct DetectedSurface {
  std::string id;
  features::Shape shape;
  std::vector<int> faces;
};

struct PrimitiveMetrics {
  int truth = 0, detected = 0, matched = 0;
  double recall = 0;
  /// Looser than recall (no shape tolerances): truth primitives of which one detected surface of
  /// the right type covers at least half (by area of the faces labelled with the primitive).
  int found = 0;
  double type_accuracy = 0;   ///< area share of labelled faces whose detected type is the truth type
  double labelled_share = 0;  ///< area share of the mesh's faces that got a truth label
  std::vector<std::pair<std::string, std::string>> matches;  ///< (truth id, detected id)
  std::vector<std::string> missed;                           ///< truth ids without a match
  std::vector<int> surface_truth;  ///< per detected surface: truth primitive it maps to, or -1
};

struct LineMetrics {
  double precision = 0, recall = 0, f1 = 0;
  double detected_length = 0, truth_length = 0;  ///< mm
  int truth_circles = 0, matched_circles = 0;
  double circle_err_mean = 0, circle_err_max = 0;  ///< relative radius error of matched circles
};

struct ConstraintMetrics {
  int detected = 0;   ///< detected constraint groups
  int checked = 0;    ///< of which a checkable kind (all but equal_angle, symmetric)
  int correct = 0;    ///< all members map to truth features and it holds on their truth shapes
  int unmapped = 0;   ///< checked groups with a member that maps to no truth feature
  double precision = 0;                 ///< correct / checked (1 when none was detected)
  int truth_pairs = 0, recalled_pairs = 0;
  double recall = 0;                    ///< recalled / truth implied pairs (1 when none)
  std::vector<std::string> wrong;       ///< why each incorrect group is wrong
  std::vector<std::string> recalled;    ///< truth pairs implied by the detected groups, "kind(a,b)"
  std::vector<std::string> missed;      ///< truth pairs not implied by the detected groups
};

struct FeatureMetrics {
  PrimitiveMetrics primitives;
  LineMetrics lines;
  ConstraintMetrics constraints;
};

/// Per face of `mesh`: the truth primitive nearest to the face's centroid (distance to the part
/// of the truth mesh the primitive claims; to the infinite surface without a truth mesh) among
/// those whose oriented surface normal agrees with the face normal within label_normal_deg; if
/// none agrees, the nearest of all. -1 when the nearest is farther than label_max_mm.
std::vector<int> label_faces(const Mesh& mesh, const Truth& truth, const Tolerances& tol);

/// Primitive recall (one-to-one greedy matching, candidates sorted by the area of the detected
/// surface's faces labelled with the truth primitive, then by normalised shape error; a match
/// needs that overlap > 0, same type and every tolerance) and type accuracy. `labels` from
/// label_faces. Faces in no surface count as wrong.
PrimitiveMetrics evaluate_surfaces(const Mesh& mesh, const std::vector<DetectedSurface>& surfaces,
                                   const Truth& truth, const std::vector<int>& labels,
                                   const Tolerances& tol);

/// Everything: primitives, feature lines (polylines of the lines' vertices), circle radius
/// error, constraints. \throw InvalidInput when the features reference faces or vertices the
/// mesh does not have.
FeatureMetrics evaluate(const Mesh& mesh, const features::FeatureSet& features, const Truth& truth,
                        const Tolerances& tol);

/// Unsigned distance from p to a truth/detected surface shape (infinite plane and cylinder,
/// sphere, single-nappe cone); curves: to the segment / full circle.
double shape_distance(const features::Shape& shape, const Eigen::Vector3d& p);

/// The ground truth as a FeatureSet on the truth mesh (for the self-check): one patch per
/// primitive (its claimed faces), one line per truth curve (the truth-mesh vertices on it, in
/// order), every truth constraint as a group. `mesh` receives the truth mesh.
features::FeatureSet truth_as_features(const Truth& truth, Mesh& mesh);

// ---------------------------------------------------------------------------------------------
// Inputs

/// Longest-edge bisection (globally longest edge first, so every split edge is the longest of
/// both its triangles) until no edge is longer than `max_edge`, with Lawson flips towards Delaunay
/// between coplanar faces (normals within 0.5°) before and after every split: the OpenSCAD
/// triangulation of a flat face is slivers, whose small angles bisection alone would keep.
/// Midpoints stay exactly on the input's facets; sharp and facet edges are never flipped.
Mesh refine_mesh(const Mesh& mesh, double max_edge);
double mean_edge_length(const Mesh& mesh);
/// Adds N(0, sigma²) independently to x, y and z of every vertex (deterministic for a seed);
/// updates the normals.
void add_noise(Mesh& mesh, double sigma, std::uint64_t seed);

struct SweepInput {
  std::string part;
  std::string input;        ///< "OpenSCAD" (the fixture mesh as exported) or "refined"
  double sigma_rel = 0;     ///< noise σ / h
  double h = 0;             ///< mean edge length before noise, mm
  double sigma_mm = 0;
  double line_tol_mm = 0;   ///< the line tolerance used for this input
  Mesh mesh;                ///< normals updated
};

/// The input column of the tables: "OpenSCAD (clean CAD)" or "refined h=0.463".
std::string input_label(const SweepInput& in);

/// The sweep's inputs of one part: the OpenSCAD mesh itself (σ = 0), then the refined mesh
/// (max edge = diagonal / div) with noise σ·h for each sigma (seed + index). The line tolerance
/// is max(0.5 mm, 1.5·h) for refined inputs, 0.5 mm for the OpenSCAD mesh.
std::vector<SweepInput> sweep_inputs(const std::filesystem::path& stl, const std::vector<double>& sigmas,
                                      double div, std::uint64_t seed);

/// Area-uniform samples of a mesh with the normal of the face each lies on (for point-based peers).
struct OrientedSamples {
  std::vector<Eigen::Vector3d> points, normals;
  std::vector<int> faces;
};
OrientedSamples sample_oriented(const Mesh& mesh, std::size_t n, std::uint64_t seed);

/// Points hashed in cubic cells, for radius queries.
class PointGrid {
 public:
  PointGrid(std::vector<Eigen::Vector3d> points, double cell);
  /// Indices of the points within `radius` of p (any radius; cheap when radius ≤ cell).
  std::vector<int> within(const Eigen::Vector3d& p, double radius) const;
  /// Whether any point lies within `radius` of p.
  bool any_within(const Eigen::Vector3d& p, double radius) const;
  const std::vector<Eigen::Vector3d>& points() const { return points_; }

 private:
  std::uint64_t key(long x, long y, long z) const;
  template <class F> bool visit(const Eigen::Vector3d& p, double radius, F&& f) const;
  std::vector<Eigen::Vector3d> points_;
  double cell_;
  std::unordered_map<std::uint64_t, std::vector<int>> cells_;
};

}  // namespace s2c::bench
