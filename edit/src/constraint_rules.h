#pragma once
// Per constraint kind: how far two shapes are from satisfying it, and the smallest change of the
// second shape that satisfies it again (greedy propagation, paper §4.3).
#include <optional>

#include "s2c/edit/editor.h"
#include "s2c/features/feature_set.h"
#include "shape_map.h"

namespace s2c::edit {

/// Residual of constraint `kind` (with its `value`, degrees for fixed_angle) between shapes a and b.
/// checked = false for kinds that the shapes cannot express (connected, equal_angle, symmetric;
/// pairs of types the kind does not apply to).
ConstraintResidual pair_residual(features::ConstraintKind kind, std::optional<double> value,
                                 const features::Shape& a, const features::Shape& b);

/// The smallest change of `b` that makes the constraint hold with `a` fixed: a rigid alignment of
/// its direction (pivot: `b_centre`, b's centre), a move onto a's axis / centre / line, a new
/// radius or a stretch along a line. nullopt when changing b cannot satisfy it.
std::optional<ShapeMap> adjustment(features::ConstraintKind kind, std::optional<double> value,
                                   const features::Shape& a, const features::Shape& b,
                                   const Eigen::Vector3d& b_centre);

/// True when `r` is within the tolerances.
inline bool holds(const ConstraintResidual& r, double angle_tol_deg, double length_tol) {
  return !r.checked || (r.angle_deg <= angle_tol_deg && r.length <= length_tol);
}

}  // namespace s2c::edit
