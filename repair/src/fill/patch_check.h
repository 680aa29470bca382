#pragma once
// Validity of a patch before it is committed to the soup (see fill.h's contract).
#include <string>

#include "fill/patch.h"

namespace s2c::repair::fill {

/// Empty when the patch is a manifold disc attached to its rim (every rim edge used once in the
/// loop's direction, every other patch edge by exactly two patch faces and no mesh face, one
/// fan per touched vertex, Euler characteristic 1), has finite coordinates, no degenerate
/// triangle, and no face pair intersecting within the patch or with the mesh (exact predicates,
/// CGAL's semantics). Otherwise the first reason found.
std::string check_patch(const TriangleSoup& soup, const MeshIndex& index, const Patch& patch);

}  // namespace s2c::repair::fill
