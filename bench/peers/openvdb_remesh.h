#pragma once
// The OpenVDB peer for the volumetric benchmark: meshToLevelSet + volumeToMesh at a voxel size.
#include "s2c/core/mesh.h"

namespace s2c::bench {

struct OpenVdbResult {
  TriangleSoup mesh;
  double seconds_to_volume = 0, seconds_to_mesh = 0;
  std::size_t active_voxels = 0;
  std::size_t bytes = 0;
};

/// Level set of `input` with a narrow band of `half_width` voxels each side, iso-surface at 0.
OpenVdbResult openvdb_remesh(const TriangleSoup& input, double voxel, double half_width);

}  // namespace s2c::bench
