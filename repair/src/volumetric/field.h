#pragma once
// Building the vector-field distance function on the sparse band: block activation around each
// triangle, closest points with bounded Embree point queries, then inside/outside per vertex.
#include "s2c/core/distance.h"
#include "s2c/core/mesh.h"
#include "s2c/repair/volumetric.h"
#include "volumetric/sparse_grid.h"

namespace s2c::repair {

/// Allocates the blocks within `radius` (mm) of any triangle and stores every vertex's closest-point
/// vector when it is within `radius`.
void build_vector_field(const TriangleSoup& soup, const SurfaceQuery& query, double radius, SparseGrid& grid,
                        VolumetricStats& stats);

/// Marks in-band vertices inside (kInside) by the chosen rule. With the winding rule, a band region
/// that connects inside and outside (a hole wider than the band) gets the winding number per vertex,
/// or with `shell` > 0 (mm) becomes a closed shell of that half-thickness around the surface.
void classify_inside(const TriangleSoup& soup, const SurfaceQuery& query, SignMode mode, double shell,
                     SparseGrid& grid, VolumetricStats& stats);

}  // namespace s2c::repair
