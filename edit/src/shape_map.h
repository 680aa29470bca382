#pragma once
// The map an edit applies to a feature's vertices and shape: a similarity (move, rotate, scale,
// and the rigid adjustments of propagation), an anisotropic affine map (a line stretched along
// itself), or a projection onto the same shape with a new radius / half angle.
#include <string>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "s2c/features/shape.h"

namespace s2c::edit {

struct ShapeMap {
  enum class Kind { affine, resize };
  Kind kind = Kind::affine;
  /// affine: x ↦ linear·x + offset. `similarity` says linear = s·R (shapes transform exactly).
  Eigen::Matrix3d linear = Eigen::Matrix3d::Identity();
  Eigen::Vector3d offset = Eigen::Vector3d::Zero();
  bool similarity = true;
  double scale = 1.0;  ///< similarity: the factor s (lengths and radii scale by it)
  /// resize: from `source` to `target`, the same shape with another radius (cylinder, sphere,
  /// circle, arc) or half angle (cone, same apex and axis). Each vertex keeps its offset from the
  /// surface: it moves by the change of the surface under it (exact for a CAD tessellation, whose
  /// vertices lie on the surface; a scan keeps its detail and never folds at a rounded rim).
  features::Shape source, target;

  static ShapeMap translation(const Eigen::Vector3d& by);
  /// Rotation by `degrees` about the line through `pivot` along `axis` (unit).
  static ShapeMap rotation(const Eigen::Vector3d& axis, double degrees, const Eigen::Vector3d& pivot);
  /// The smallest rotation taking unit `from` to unit `to`, about `pivot`.
  static ShapeMap align(const Eigen::Vector3d& from, const Eigen::Vector3d& to, const Eigen::Vector3d& pivot);
  static ShapeMap scaling(double factor, const Eigen::Vector3d& pivot);
  static ShapeMap resize(const features::Shape& source, const features::Shape& target);
  /// this after `first` (affine maps only).
  ShapeMap after(const ShapeMap& first) const;

  Eigen::Vector3d apply(const Eigen::Vector3d& p) const;
  /// The shape after the map; for a non-similarity affine map the caller refits instead.
  features::Shape apply(const features::Shape& s) const;
  bool is_identity(double tol = 1e-12) const;
  /// One line for logs: "moved by [0, 0, 3]", "rotated 15° about [0, 0, 1]", "radius 3 → 4".
  std::string describe(const features::Shape& before) const;
};

/// Where a resize from `source` to `target` takes a vertex whose position before the edit was `p0`
/// and whose position so far in this edit is `current`: onto `target` at `current`, plus p0's
/// signed offset from `source` along the surface normal. With several maps on one vertex (the
/// equator shared by a cylinder and a sphere) the result does not depend on their order.
Eigen::Vector3d resize_point(const features::Shape& source, const features::Shape& target, const Eigen::Vector3d& p0,
                             const Eigen::Vector3d& current);

/// The nearest point of a surface shape (plane, cylinder, sphere, cone) to p; p for other shapes.
Eigen::Vector3d project_onto(const features::Shape& s, const Eigen::Vector3d& p);

/// True when every number of the shape is finite.
bool finite_shape(const features::Shape& s);

/// The direction a constraint on this shape talks about: plane normal, cylinder/cone axis, line
/// direction, circle/arc normal. Zero for spheres and freeform.
Eigen::Vector3d direction_of(const features::Shape& s);
/// The radius of cylinders, spheres, circles, arcs; 0 otherwise.
double radius_of(const features::Shape& s);
/// Angle between two directions as lines (0…90°).
double line_angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

}  // namespace s2c::edit
