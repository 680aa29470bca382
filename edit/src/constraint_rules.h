#pragma once
// Per constraint kind: how far two shapes are from satisfying it, and the smallest change of the
// second shape that satisfies it again (greedy propagation, paper §4.3).
#include <optional>

#include "s2c/edit/editor.h"
#include "s2c/features/feature_set.h"
#include "shape_map.h"

namespace s2c::edit {

/// A mirror plane (symmetric constraints): a point on it and its unit normal.
struct Mirror {
  Eigen::Vector3d point = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::UnitX();
};

/// One constraint as the rules need it: its kind, its value (degrees for fixed_angle) and, for
/// symmetric, its mirror plane.
struct ConstraintSpec {
  features::ConstraintKind kind = features::ConstraintKind::parallel;
  std::optional<double> value;
  std::optional<Mirror> mirror;
};
/// The spec of a features.json group (mirror from its "mirror" attribute; absent when malformed).
ConstraintSpec spec_of(const features::Group& g);

/// Residual of the constraint between shapes a and b. checked = false for kinds the shapes cannot
/// express (connected, equal_angle; symmetric without a mirror plane; pairs of types the kind
/// does not apply to).
ConstraintResidual pair_residual(const ConstraintSpec& c, const features::Shape& a, const features::Shape& b);

/// The smallest change of `b` that makes the constraint hold with `a` fixed: a rigid alignment of
/// its direction (pivot: `b_centre`, b's centre), a move onto a's axis / centre / line, a new
/// radius or a stretch along a line. nullopt when changing b cannot satisfy it (symmetric: never
/// enforced, see editor.h).
std::optional<ShapeMap> adjustment(const ConstraintSpec& c, const features::Shape& a, const features::Shape& b,
                                   const Eigen::Vector3d& b_centre);

/// True when `r` is within the tolerances.
inline bool holds(const ConstraintResidual& r, double angle_tol_deg, double length_tol) {
  return !r.checked || (r.angle_deg <= angle_tol_deg && r.length <= length_tol);
}

}  // namespace s2c::edit
