#pragma once
// What the mesh around a hole looks like, for the RBF fill (rbf.cpp): how noisy it is (the
// paper smooths the rim region, which on clean input only moves correct vertices), and whether
// sharp creases cut it into several smooth surfaces (one RBF over a crease rounds it off, and
// the patch then sags across the hole wherever the crease runs through it).
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

#include "fill/patch.h"

namespace s2c::repair::fill {

/// Vertex positions for the fit: the soup's, or a smoothed copy of some of them.
struct Position {
  const std::vector<Eigen::Vector3d>& base;
  const std::unordered_map<int, Eigen::Vector3d>& moved;
  const Eigen::Vector3d& operator()(int v) const {
    if (!moved.empty()) {
      const auto it = moved.find(v);
      if (it != moved.end()) return it->second;
    }
    return base[static_cast<std::size_t>(v)];
  }
};

/// Unit area-weighted normal of vertex v from its faces at positions `at`, zero when degenerate.
Eigen::Vector3d area_normal(const TriangleSoup& soup, const MeshIndex& index, int v, const Position& at);

/// Noise of the surface around a hole, mm: the median over `vertices` (sorted; rings ≥ 1, each with its
/// mesh neighbours) of how much the normal component of the umbrella vector L(v) = mean(N(v)) - v
/// differs from its mean over the neighbours. On a smooth surface L·n follows the curvature and
/// changes slowly from vertex to vertex (≈ 0, whatever the curvature); noise of σ gives ≈ σ.
/// Vertices in `skip` (sorted: the crease vertices) are left out, or a crease through the rings
/// of a small hole, where they can be most of the vertices, would read as noise.
double surface_noise(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& vertices,
                     const Position& at, const std::vector<int>& skip);

/// One smooth piece of the surface around a hole: its vertices and their normals from the
/// piece's own faces (a crease vertex belongs to every piece it bounds, with each one's normal).
struct SmoothPiece {
  std::vector<int> vertices;
  std::vector<Eigen::Vector3d> normals;
};

/// The faces among `vertices` grown into pieces across edges whose dihedral angle is below
/// `crease_deg`; pieces with fewer than `min_vertices` vertices are dropped. `convex` tells how
/// the pieces meet: every crease between them convex (the solid is the intersection of the
/// pieces' insides) or every one concave (the union). Returns one piece (all of `vertices`)
/// when there is no crease or the creases are mixed, which one implicit surface has to take,
/// and when `crease_deg` is 0.
struct CreaseSplit {
  std::vector<SmoothPiece> pieces;
  bool convex = true;
  std::vector<int> crease_vertices;  ///< ends of the sharp edges found, sorted
};
CreaseSplit split_at_creases(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& vertices,
                             const Position& at, double crease_deg, std::size_t min_vertices);
/// All of `vertices` as one piece, normals from all their faces.
CreaseSplit one_piece(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& vertices,
                      const Position& at);

}  // namespace s2c::repair::fill
