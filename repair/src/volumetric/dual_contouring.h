#pragma once
// Dual contouring from the same Hermite data (crossing points + surface normals): one vertex per
// surface sheet of a cell (per Marching Cubes loop, so the result is as manifold as MC's), placed
// by a truncated-SVD quadric error minimiser so that sharp edges and corners are kept.
#include "s2c/core/distance.h"
#include "s2c/core/mesh.h"
#include "s2c/repair/volumetric.h"
#include "volumetric/sparse_grid.h"

namespace s2c::repair {

/// \param surface the input, for the normals at crossing points.
TriangleSoup dual_contouring(const SparseGrid& grid, const TriangleSoup& surface, const SurfaceQuery& query,
                             Interp interp, VolumetricStats& stats);

}  // namespace s2c::repair
