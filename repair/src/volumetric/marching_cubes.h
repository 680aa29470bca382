#pragma once
// Marching Cubes over the sparse band. Each crossing edge gets one vertex, shared by the four
// cells around it, so the output is a closed manifold wherever the band covers the surface.
#include "s2c/core/mesh.h"
#include "s2c/repair/volumetric.h"
#include "volumetric/sparse_grid.h"

namespace s2c::repair {

/// Consumes the grid: blocks are freed as the sweep (in z) leaves them behind, so that the grid
/// and the growing mesh are not both whole in memory (at 1024³ each is some 500 MB).
TriangleSoup marching_cubes(SparseGrid&& grid, Interp interp, VolumetricStats& stats);

/// The paper's edge point: the parameter λ ∈ [0, 1] of the point of edge V1→V2 closest to the
/// segment A→B (A, B the closest surface points of V1, V2). Returns false when the edge and AB are
/// parallel (no unique point); λ is then untouched.
bool vector_edge_parameter(const Eigen::Vector3d& v1, const Eigen::Vector3d& v2, const Eigen::Vector3d& a,
                           const Eigen::Vector3d& b, double& lambda);

/// Beyond the paper (`Interp::hermite`): the parameter of the point where edge V1→V2 leaves the
/// solid bounded by the tangent planes at A (normal nA) and B (normal nB), both outward — their
/// intersection where each lies below the other's plane (a convex edge), their union where each
/// lies above (concave). Exact on a surface made of the two planes. Returns false, λ untouched,
/// when the planes are one (the paper's λ is exact there), when neither model fits (curved
/// surface, more planes) or when the edge does not go from inside to outside through them.
/// `plane` receives which plane the point is on (0: A's, 1: B's).
bool tangent_plane_edge_parameter(const Eigen::Vector3d& v1, const Eigen::Vector3d& v2, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& na, const Eigen::Vector3d& b, const Eigen::Vector3d& nb,
                                  bool v1_inside, double& lambda, int* plane = nullptr);

}  // namespace s2c::repair
