#pragma once
/// \file Boundary loops of a mesh and their classification into single holes and continuous
/// nested holes (loops that pass through shared vertices), after
/// ../shared/papers/nested-hole-splitting.txt. Nested holes are split into single holes by the
/// paper's seven steps so that every hole handed to filling is one simple boundary.
#include <cstddef>
#include <vector>

#include "s2c/core/mesh.h"

namespace s2c::repair {

/// One hole to fill: a closed boundary polygon of existing vertex indices (the closing edge
/// loop.back() -> loop.front() is implied). The order is the fill order: triangles
/// (loop[0], loop[i], loop[i+1]) are consistently oriented with the faces around the hole.
/// A vertex may appear more than once only in holes that came out of a nested hole whose inner
/// hole was merged into its outer one (step 6 of the paper).
struct Hole {
  enum class Origin { single, nested };
  std::vector<int> loop;
  Origin origin = Origin::single;
  double perimeter = 0;   ///< mm
  double diameter = 0;    ///< largest distance between two loop vertices, mm
  /// The part's unseen end face, its rim trimmed flush with one plane (trim_end_caps, fill.h):
  /// filled flat in that plane.
  bool end_cap = false;
};

struct HoleStats {
  std::size_t boundary_edges = 0;
  std::size_t single_holes = 0;      ///< boundary components that were simple loops
  std::size_t nested_holes = 0;      ///< boundary components with shared (common) vertices
  std::size_t common_points = 0;     ///< vertices shared by more than one hole line
  std::size_t holes_out = 0;         ///< single holes handed to filling
};

/// Finds every hole of an edge-manifold, consistently oriented soup and splits nested ones.
/// Terminates on any input (bounded by the number of boundary edges). Non-manifold edges are
/// ignored (they are not boundary). \param stats optional, filled when non-null.
std::vector<Hole> find_holes(const TriangleSoup& soup, HoleStats* stats = nullptr);

}  // namespace s2c::repair
