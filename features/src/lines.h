#pragma once
// Feature lines: chains of mesh edges where two patches meet at a crease (or the mesh ends),
// split at junctions, fitted with line / circle / arc. Where both patches have shapes, a line
// between two planes is their intersection and a rim between a plane and a cylinder or cone is
// their intersection circle: exact on CAD meshes, and free of the zig-zag of noisy creases.
#include <vector>

#include "mesh_arrays.h"
#include "s2c/features/feature_set.h"
#include "segment.h"

namespace s2c::features {

struct TracedLine {
  std::vector<int> vertices;
  bool closed = false;
  int region_a = -1, region_b = -1;  ///< the patches on either side (b = -1 on a mesh boundary)
  Fit fit;
};

/// Chains of edges between patches that meet at a crease, fitted with the patches' exact
/// intersection curve, a line or a circle/arc within `tolerance` (widened on a noisy mesh, whose
/// chains zigzag), else freeform.
std::vector<TracedLine> trace_lines(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals,
                                    const Segmentation& seg, double min_crease_deg, double tolerance, bool noisy);

}  // namespace s2c::features
