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

/// On a noisy mesh, patches under this share of the surface area are crumbs: they take no part in
/// constraints, and a line along them is given the edge of the large patches around them.
constexpr double kMinorAreaShare = 0.002;

/// On a noisy mesh, pieces of one edge are joined across gaps of up to this many median edges
/// where the mesh between them belongs to the edge's patches and crumbs, and a straight edge's end
/// moves to a corner up to this far away (join_lines.h).
constexpr double kMaxEdgeGap = 10.0;

struct TracedLine {
  std::vector<int> vertices;
  bool closed = false;
  int region_a = -1, region_b = -1;  ///< the patches on either side (b = -1 on a mesh boundary)
  /// The two shaped patches whose intersection the fit is (-1 when the fit is not one): region_a
  /// and region_b, or, along a freeform band, the shaped side and the shape across the band.
  int edge_a = -1, edge_b = -1;
  Fit fit;
};

/// The intersection curve of two shapes near the ordered points `pts` when it is a line (two
/// planes, clipped to the points' extent) or a circle (a plane across a cylinder or cone axis;
/// an arc when the points sweep less than a full turn and `closed` is false).
bool intersection_curve(const Shape& a, const Shape& b, const std::vector<Eigen::Vector3d>& pts, bool closed,
                        Shape& out);

/// A face's normal as trace_lines reads it (the filtered one on a noisy mesh); asked only for the
/// faces along patch borders, so a mapped-back normal need not be stored for every face.
using FaceNormal = std::function<Eigen::Vector3d(int face)>;

/// Chains of edges between patches that meet at a crease, fitted with the patches' exact
/// intersection curve, a line or a circle/arc within `tolerance` (widened on a noisy mesh, whose
/// chains zigzag, by half of `border_edge`: the edge length the patches' borders are drawn to,
/// the working mesh's median edge when the segmentation was made on a coarser copy and mapped
/// back; 0 for the mesh's own), else freeform.
std::vector<TracedLine> trace_lines(const MeshArrays& m, const FaceNormal& normal, const Segmentation& seg,
                                    double min_crease_deg, double tolerance, bool noisy, double border_edge = 0);

/// The same with the normals of all faces in an array.
inline std::vector<TracedLine> trace_lines(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals,
                                           const Segmentation& seg, double min_crease_deg, double tolerance,
                                           bool noisy, double border_edge = 0) {
  return trace_lines(m, [&normals](int f) { return normals[f]; }, seg, min_crease_deg, tolerance, noisy, border_edge);
}

}  // namespace s2c::features
