#pragma once
// Private types shared by the hole-filling files: an index of the mesh around holes and the patch
// under construction. Not part of the public API (see s2c/repair/fill.h).
#include <array>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <cstddef>

#include "s2c/core/disjoint_sets.h"
#include "s2c/core/mesh.h"

namespace s2c::repair::fill {

inline std::uint64_t directed_key(int a, int b) {
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}
inline std::uint64_t edge_key(int a, int b) { return undirected_edge_key(a, b); }

/// Groups `faces` (all containing vertex v) into fans: faces joined through an edge at v.
/// `fans` is reset to one set per face; returns how many fans there are.
int fans_at(int v, const std::vector<std::array<int, 3>>& faces, DisjointSets& fans);

/// Adjacency of a soup, kept up to date as patches are appended (so later holes see earlier
/// patches). Built once per fill_holes call: O(#F).
class MeshIndex {
 public:
  explicit MeshIndex(const TriangleSoup& soup);
  /// Indexes the faces soup.faces[first..] (just appended).
  void add_faces(const TriangleSoup& soup, std::size_t first);

  /// Faces using vertex v.
  std::vector<int> faces_of(int v) const;
  /// The face holding the directed edge a→b, or -1 (the first one when the soup is non-manifold).
  int face_with(int a, int b) const;
  /// How many faces use the undirected edge {a, b}.
  int edge_faces(int a, int b) const;
  bool has_edge(int a, int b) const { return edge_faces(a, b) > 0; }
  /// Vertex neighbours of v through its faces (unsorted, unique).
  std::vector<int> neighbours(const TriangleSoup& soup, int v) const;
  /// Faces whose bounding box may overlap the box [lo, hi] (a superset: grid cells), sorted and
  /// unique; appended to `out`. Replaces a scan of every face when validating a patch.
  void faces_near(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, std::vector<int>& out) const;

 private:
  // The input's faces in flat sorted arrays (one sort instead of millions of hash inserts:
  // this index is built once per call and dominated small-hole timings as hash maps), the
  // appended patches' faces in small hash maps.
  std::vector<std::pair<std::uint64_t, int>> directed_;  // (directed_key, face), sorted
  std::vector<int> vf_offset_, vf_faces_;                // vertex → faces (CSR)
  std::unordered_map<std::uint64_t, std::vector<int>> added_directed_;
  std::unordered_map<int, std::vector<int>> added_vertex_faces_;
  // Uniform grid over face bounding boxes (cell ≈ 2 mean edge lengths): (cell key, face) sorted
  // for the input, a hash map for appended faces; faces spanning too many cells are listed apart.
  void grid_insert(const TriangleSoup& soup, int f, bool appended);
  Eigen::Vector3d grid_origin_ = Eigen::Vector3d::Zero();
  double cell_ = 1;
  std::vector<std::pair<std::uint64_t, int>> grid_;
  std::unordered_map<std::uint64_t, std::vector<int>> added_grid_;
  std::vector<int> oversize_;
  std::size_t faces_ = 0;
};

/// A patch under construction. Local vertex l < rim.size() is loop position l (soup vertex
/// rim[l]; a soup vertex may occupy several positions in a nested loop), l ≥ rim.size() is a
/// new vertex that will become soup vertex base + l - rim.size().
struct Patch {
  std::vector<int> rim;                     ///< soup indices in loop order
  std::vector<Eigen::Vector3d> points;      ///< all local vertices, mm
  std::vector<double> sigma;                ///< Liepa's density per local vertex, mm
  std::vector<std::array<int, 3>> faces;    ///< local indices, oriented like the loop
  int base = 0;                             ///< soup index of the first new vertex

  int rim_size() const { return static_cast<int>(rim.size()); }
  int size() const { return static_cast<int>(points.size()); }
  /// The soup index local vertex l has (or will have).
  int global(int l) const { return l < rim_size() ? rim[static_cast<std::size_t>(l)] : base + l - rim_size(); }
};

/// What the method choice and both methods need to know about one hole.
struct HoleShape {
  double edge = 0;              ///< target edge length, mm
  double diameter = 0;          ///< largest rim extent, mm
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  ///< patch side, from the loop's vector area
  double planarity = 0;         ///< max rim distance from the best-fit plane / diameter
  double wall_angle_deg = 0;    ///< mean angle between the rim's mesh faces and the rim plane
  bool planar = false;          ///< rim in one plane (within FillOptions::planar_tolerance)
  bool flat_fill = false;       ///< fill with the rim plane: planar rim on flat ground or a crease
};

/// Unit normal of triangle (a, b, c), or zero when degenerate.
inline Eigen::Vector3d unit_normal(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double l = n.norm();
  return l > 0 ? Eigen::Vector3d(n / l) : Eigen::Vector3d::Zero();
}

}  // namespace s2c::repair::fill
