#pragma once
// Private types shared by the hole-filling files: an index of the mesh around holes and the patch
// under construction. Not part of the public API (see s2c/repair/fill.h).
#include <array>
#include <cstdint>
#include <limits>
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
/// patches). Built once per fill_holes call: a vertex → faces table, O(#F) with no sort (it is
/// built for every call, and a call often fills one small hole).
class MeshIndex {
 public:
  /// Keeps a reference to `soup`, which must outlive the index (patches are appended to it).
  explicit MeshIndex(const TriangleSoup& soup);
  /// Indexes the faces soup.faces[first..] (just appended to the soup given at construction).
  void add_faces(std::size_t first);

  /// Faces using vertex v.
  std::vector<int> faces_of(int v) const;
  /// visit(f) for every face f using vertex v (no allocation).
  template <class Visit>
  void for_each_face_of(int v, Visit&& visit) const {
    if (v >= 0 && static_cast<std::size_t>(v) + 1 < vf_offset_.size())
      for (int i = vf_offset_[v]; i < vf_offset_[v + 1]; ++i) visit(vf_faces_[static_cast<std::size_t>(i)]);
    // Most vertices have no appended faces: a byte per vertex says so without hashing.
    if (v < 0 || static_cast<std::size_t>(v) >= has_added_.size() || !has_added_[static_cast<std::size_t>(v)]) return;
    const auto it = added_vertex_faces_.find(v);
    if (it != added_vertex_faces_.end())
      for (int f : it->second) visit(f);
  }
  /// The face holding the directed edge a→b, or -1 (the first one when the soup is non-manifold).
  int face_with(int a, int b) const;
  /// How many faces use the undirected edge {a, b}.
  int edge_faces(int a, int b) const;
  bool has_edge(int a, int b) const { return edge_faces(a, b) > 0; }
  /// Vertex neighbours of v through its faces (ascending, unique).
  std::vector<int> neighbours(int v) const;
  /// The same appended to `out` (no allocation when `out` has room).
  void append_neighbours(int v, std::vector<int>& out) const;
  /// Faces whose bounding box overlaps the box [lo, hi] (and faces with non-finite corners),
  /// ascending; appended to `out`. Only faces from index `first` on are considered (those
  /// appended since some point). Safe to call from several threads at once as long as no faces
  /// are added meanwhile.
  /// Two ways, the same answer up to float rounding (a few extra faces, never one less):
  /// - by default one pass over the vertices (their outcodes against the box, as in
  ///   Cohen–Sutherland clipping: a face's box misses [lo, hi] exactly when its three corners
  ///   lie beyond the same side) and one over the faces, O(#V + #F) per query with no set-up:
  ///   best for a call that fills one or two holes;
  /// - after prepare_boxes(), by boxes of blocks of kBlock consecutive faces (built once in
  ///   O(#F), extended as patches are added): a query skips the blocks whose box misses [lo, hi]
  ///   and tests the faces of the others one by one. Meshes list neighbouring faces close together
  ///   (grids, subdivisions, marching cubes, PLY exports), so a query opens few blocks; on a
  ///   shuffled mesh it degrades to a linear scan.
  void faces_near(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, std::vector<int>& out,
                  std::size_t first = 0) const;
  /// Switches faces_near to the block boxes (for calls with many holes). Set before any thread
  /// asks scanning(); then prepare_boxes() builds the boxes (O(#F)) while the holes are planned.
  void use_blocks() const { use_blocks_ = true; }
  void prepare_boxes() const { extend_boxes(); }
  /// Whether every face has its block box (prepare_boxes would do nothing).
  bool boxes_ready() const { return boxed_ >= soup_.faces.size(); }
  /// Whether faces_near scans vertices and faces (no block boxes): then a query costs O(#V + #F).
  bool scanning() const { return !use_blocks_; }

 private:
  void extend_boxes() const;  // boxes for the faces not boxed yet (appended ones included)
  void scan_near(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, std::vector<int>& out, std::size_t first) const;
  const TriangleSoup& soup_;
  std::vector<int> vf_offset_, vf_faces_;                // the input's vertex → faces (CSR)
  std::unordered_map<int, std::vector<int>> added_vertex_faces_;
  std::vector<std::uint8_t> has_added_;                  // v has appended faces (a key above)
  static constexpr std::size_t kBlock = 32;
  struct Box {
    Eigen::Vector3f lo, hi;  // rounded outwards; NaN when a corner is not finite
  };
  mutable std::vector<Box> block_boxes_;
  mutable std::size_t boxed_ = 0;  // faces [0, boxed_) are in block_boxes_
  mutable bool use_blocks_ = false;
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
  /// check_patch_topology passed for these faces (set where it runs early, beside other work;
  /// moving the points keeps it true, changing the faces must reset it).
  bool topology_ok = false;
  /// Mesh faces near [near_lo, near_hi] (MeshIndex::faces_near, ascending), found early like
  /// topology_ok; a full check_patch uses them when that box holds the patch's.
  std::vector<int> near_faces;
  Eigen::Vector3d near_lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
  Eigen::Vector3d near_hi = near_lo;

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
  bool end_cap = false;         ///< the part's unseen end face, trimmed flat (Hole::end_cap)
  bool flat_fill = false;       ///< fill with the rim plane: planar rim on flat ground or a crease
};

/// The rim's plane, size and surroundings: everything the method choice looks at (flat_fill and
/// end_cap are left to the caller). `edge_length` 0: the mean rim edge.
HoleShape analyse_rim(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& loop, double edge_length,
                      double planar_tolerance);

/// Unit normal of triangle (a, b, c), or zero when degenerate.
inline Eigen::Vector3d unit_normal(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d n = (b - a).cross(c - a);
  const double l = n.norm();
  return l > 0 ? Eigen::Vector3d(n / l) : Eigen::Vector3d::Zero();
}

}  // namespace s2c::repair::fill
