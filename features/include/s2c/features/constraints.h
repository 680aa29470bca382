#pragma once
/// \file Constraint analysis (paper §3.3): every pair of fitted features is tested for the
/// constraint kinds with tight CAD tolerances; redundant constraints are removed (equivalence
/// kinds become one group per class; line constraints are preferred where they imply the
/// patch constraint, as the paper says).
#include <memory>
#include <vector>

#include "s2c/features/feature_set.h"

namespace s2c::features {

struct ConstraintOptions {
  double angle_tol_deg = 2.0;     ///< parallel / perpendicular / fixed_angle / coaxial axis tolerance
  double length_tol = 0.0;        ///< absolute length / position tolerance, mm (0: 0.5% of `diagonal`)
  double diagonal = 1.0;          ///< bounding-box diagonal of the part, mm
  double radius_rel_tol = 0.01;   ///< equal_radius / equal_length relative tolerance
  double area_rel_tol = 0.05;     ///< symmetric: mirrored patches must have areas within this fraction
  int max_mirror_planes = 64;     ///< symmetric: candidate mirror planes tested (largest supporting area first)
  /// Patches smaller than this (mm²) take no part, and when it is > 0 neither do the lines
  /// touching a small or freeform patch: on scan meshes these are the reconstruction's artefacts
  /// (a constriction inside a hole the scanner never saw, leftovers along rounded edges), whose
  /// chance alignments would be stated as constraints. Except a line that is the intersection of
  /// two patches it touches, each of at least 5 × this area: a scan's edge along its rounding.
  /// When it is > 0, lines no longer than the position tolerance (a corner's stub: straight, or
  /// an arc or circle by its curve's length) take no part either, nor straight lines touching
  /// only planes, two or more, in the direction of none of their edges (across a rounded
  /// corner). 0: every patch takes part.
  double min_patch_area = 0.0;
  /// fixed_angle needs the patches to meet at least at this angle (degrees; 0: above the angle
  /// tolerance). On scan meshes the analysis sets it to the smallest crease angle it detects:
  /// pieces of one noisy surface that the fits split (a domed end in sphere and cone zones) meet
  /// at a few degrees along a border that is no crease, and no designed angle is stated there.
  double min_fixed_angle_deg = 0.0;
};

/// Detects constraints among `features` (their patches and lines with shapes; `adjacency`
/// filled) and appends them to `features.groups` as kind "constraint" with ids continuing the
/// existing G numbering. Returns how many were added.
int detect_constraints(FeatureSet& features, const ConstraintOptions& options);

/// detect_constraints in two steps: the search, which reads only the patches, lines and adjacency
/// (so other groups may be added meanwhile, as the analysis adds the components), and then
/// add_to(), which numbers what was found after the groups there are by then.
class ConstraintSearch {
 public:
  ConstraintSearch(const FeatureSet& features, const ConstraintOptions& options);
  ~ConstraintSearch();
  ConstraintSearch(ConstraintSearch&&) noexcept;
  ConstraintSearch& operator=(ConstraintSearch&&) noexcept;
  /// Appends the constraints found to `features` (the one searched) and returns how many.
  int add_to(FeatureSet& features) const;

 private:
  struct Result;
  std::unique_ptr<Result> found_;
};

}  // namespace s2c::features
