#pragma once
// Feature lines: chains of mesh edges where two patches meet at a crease (or the mesh ends),
// split at junctions, fitted with line / circle / arc. Where both patches have shapes, a line
// between two planes is their intersection and a rim between a plane and a cylinder or cone is
// their intersection circle: exact on CAD meshes, and free of the zig-zag of noisy creases.
#include <functional>
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

/// A face's normal as trace_lines reads it (the filtered one on a noisy mesh); asked only for the
/// faces along patch borders, so a mapped-back normal need not be stored for every face.
using FaceNormal = std::function<Eigen::Vector3d(int face)>;

/// Chains of edges between patches that meet at a crease, fitted with the patches' exact
/// intersection curve, a line or a circle/arc within `tolerance` (widened on a noisy mesh, whose
/// chains zigzag), else freeform.
std::vector<TracedLine> trace_lines(const MeshArrays& m, const FaceNormal& normal, const Segmentation& seg,
                                    double min_crease_deg, double tolerance, bool noisy);

/// The same with the normals of all faces in an array.
inline std::vector<TracedLine> trace_lines(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals,
                                           const Segmentation& seg, double min_crease_deg, double tolerance,
                                           bool noisy) {
  return trace_lines(m, [&normals](int f) { return normals[f]; }, seg, min_crease_deg, tolerance, noisy);
}

}  // namespace s2c::features
