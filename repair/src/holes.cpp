// Hole detection and the splitting of continuous nested holes
// (../shared/papers/nested-hole-splitting.txt, steps 1-7 of its Fig. 3).
//
// Conventions. A free edge is an unordered vertex pair used by exactly one face. A face (a,b,c)
// holding the free edge a->b contributes the *hole half-edge* b->a: every hole line below is
// traversed with the missing region on its left (seen from the outside of the surface), so the
// fan triangles (loop[0], loop[i], loop[i+1]) have the orientation of the surrounding faces.
// Islands of faces inside a hole are therefore traversed clockwise, outer rims counter-clockwise.
//
// Where the paper is weak we go beyond it (each place says so below):
//  * Step 2 (split the hole line at common points) does not say how to choose, at a common
//    point, which of several outgoing free edges the walk takes. We take the paper's own
//    smallest-angle rule of step 5 there too (measured in the tangent plane at the vertex,
//    clockwise from the incoming edge), so that loops that touch from outside come apart and
//    only inner holes (islands) are split off - the ones step 6 merges back.
//  * Step 3 projects onto one best-fit plane; for a non-planar nested hole the projection need
//    not be injective and point-in-polygon answers are then meaningless. We detect that (a rim
//    face turned away from the plane, projected hole lines crossing, or a nesting depth that
//    contradicts the loop's turning sense) and then decide "inner hole of" locally instead: two
//    loops belong to one hole when, at a common point, the smallest-angle rule leads from one
//    loop into the other. That needs only the tangent plane at the common point.
#include "s2c/repair/holes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <numeric>
#include <string>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include <Eigen/Eigenvalues>

#include "s2c/core/disjoint_sets.h"
#include "s2c/core/errors.h"

namespace s2c::repair {
namespace {

using Eigen::Vector2d;
using Eigen::Vector3d;
constexpr double kPi = 3.14159265358979323846;

std::uint64_t edge_key(int a, int b) { return undirected_edge_key(a, b); }

struct HalfEdge {
  int from = 0, to = 0;  ///< hole direction (reverse of the face's edge)
  int face = 0;
};

/// Hole half-edges of the free edges, in order of first appearance in the face list.
std::vector<HalfEdge> free_half_edges(const TriangleSoup& soup) {
  struct EdgeUse { int count = 0; HalfEdge he; };
  std::unordered_map<std::uint64_t, int> index;
  std::vector<EdgeUse> uses;
  index.reserve(soup.faces.size() * 2);
  uses.reserve(soup.faces.size() * 3 / 2 + 1);
  const int nv = static_cast<int>(soup.vertices.size());
  for (std::size_t f = 0; f < soup.faces.size(); ++f) {
    const auto& t = soup.faces[f];
    for (int c : t)
      if (c < 0 || c >= nv)
        throw InvalidInput("find_holes: face " + std::to_string(f) + " refers to missing vertex " + std::to_string(c));
    if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) continue;  // not a triangle, bounds nothing
    for (int k = 0; k < 3; ++k) {
      const int a = t[k], b = t[(k + 1) % 3];
      auto [it, inserted] = index.emplace(edge_key(a, b), static_cast<int>(uses.size()));
      if (inserted) uses.push_back({0, {b, a, static_cast<int>(f)}});
      ++uses[it->second].count;
    }
  }
  std::vector<HalfEdge> out;
  for (const auto& u : uses)
    if (u.count == 1) out.push_back(u.he);
  return out;
}

using UnionFind = DisjointSets;

/// Clockwise angle in (0, 2π] from direction `ref` to direction `d` about the normal `n`
/// (both directions projected into the plane ⊥ n). Faces are counter-clockwise about n, so
/// sweeping clockwise from the incoming edge crosses the missing region first.
double clockwise_angle(const Vector3d& n, Vector3d ref, Vector3d d) {
  ref -= n * n.dot(ref);
  d -= n * n.dot(d);
  double a = -std::atan2(n.dot(ref.cross(d)), ref.dot(d));
  if (a <= 1e-12) a += 2 * kPi;
  return a;
}

double loop_perimeter(const TriangleSoup& soup, const std::vector<int>& loop) {
  double p = 0;
  for (std::size_t i = 0; i < loop.size(); ++i)
    p += (soup.vertices[loop[(i + 1) % loop.size()]] - soup.vertices[loop[i]]).norm();
  return p;
}

/// Largest distance between two loop vertices: exact up to 2048 vertices; beyond, the largest
/// distance from the extreme points along 13 directions to every vertex (a tight lower bound
/// in practice, O(n)), to keep huge scan holes linear.
double loop_diameter(const TriangleSoup& soup, const std::vector<int>& loop) {
  const std::size_t n = loop.size();
  double best = 0;
  if (n <= 2048) {
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j)
        best = std::max(best, (soup.vertices[loop[i]] - soup.vertices[loop[j]]).squaredNorm());
    return std::sqrt(best);
  }
  static const std::array<Vector3d, 13> dirs = {
      Vector3d(1, 0, 0), Vector3d(0, 1, 0), Vector3d(0, 0, 1), Vector3d(1, 1, 0),  Vector3d(1, -1, 0),
      Vector3d(1, 0, 1), Vector3d(1, 0, -1), Vector3d(0, 1, 1), Vector3d(0, 1, -1), Vector3d(1, 1, 1),
      Vector3d(1, 1, -1), Vector3d(1, -1, 1), Vector3d(-1, 1, 1)};
  std::vector<int> extremes;
  for (const auto& d : dirs) {
    auto proj = [&](int v) { return d.dot(soup.vertices[v]); };
    const auto [lo, hi] = std::minmax_element(loop.begin(), loop.end(), [&](int a, int b) { return proj(a) < proj(b); });
    extremes.push_back(*lo);
    extremes.push_back(*hi);
  }
  for (int e : extremes)
    for (int v : loop) best = std::max(best, (soup.vertices[e] - soup.vertices[v]).squaredNorm());
  return std::sqrt(best);
}

/// Everything about one boundary component needed by steps 1-7.
class NestedSplitter {
 public:
  NestedSplitter(const TriangleSoup& soup, const std::vector<HalfEdge>& hes, const std::vector<int>& comp_edges,
                 const std::unordered_map<int, Vector3d>& vertex_normals)
      : soup_(soup), hes_(hes), edges_(comp_edges), normals_(vertex_normals) {
    for (int e : edges_) out_[hes_[e].from].push_back(e);
  }

  /// Steps 1-2: walks the hole line and cuts a loop off whenever the walk returns to a vertex
  /// it already passed (a common point), so every loop is simple. Walks are bounded by the
  /// number of edges (each step uses one); a walk that dead-ends (unbalanced input: a vertex
  /// with more free edges in than out) drops its open chain.
  std::vector<std::vector<int>> split_into_loops() {
    std::vector<std::vector<int>> loops;
    std::unordered_map<int, int> pos;  // vertex -> position on the current path
    std::unordered_set<int> used;
    for (int start : edges_) {
      if (used.count(start)) continue;
      std::vector<int> path{hes_[start].from}, in_edge{-1};
      pos.clear();
      pos[path[0]] = 0;
      int next = start;
      for (std::size_t steps = 0; steps <= edges_.size() && next >= 0; ++steps) {
        used.insert(next);
        const int v = hes_[next].to;
        auto it = pos.find(v);
        if (it != pos.end()) {
          const int k = it->second;
          loops.emplace_back(path.begin() + k, path.end());
          for (std::size_t i = k + 1; i < path.size(); ++i) pos.erase(path[i]);
          path.resize(k + 1);
          in_edge.resize(k + 1);
        } else {
          pos[v] = static_cast<int>(path.size());
          path.push_back(v);
          in_edge.push_back(next);
        }
        next = choose_out(path.back(), in_edge.back(), used);
      }
      // path.size() > 1 here means a dead end: the open chain is not a hole line, drop it.
    }
    return loops;
  }

  /// Steps 3-7: classifies loops as inner/outer, merges inner holes into their outer hole at a
  /// common point chosen by the smallest-angle rule, returns the single holes.
  std::vector<std::vector<int>> merge_inner(std::vector<std::vector<int>> loops) {
    const std::size_t n = loops.size();
    if (n < 2) return loops;
    std::vector<std::vector<int>> groups = projection_reliable(loops) ? groups_by_projection(loops) : groups_by_angle(loops);
    std::vector<std::vector<int>> out;
    for (const auto& g : groups) {
      // Step 6: start from the group's first loop (the outer one in projection mode) and insert
      // the others where they touch it; loops that never touch the merged line (no common
      // point with it) stay separate holes.
      std::vector<int> merged = loops[g[0]];
      std::vector<int> pending(g.begin() + 1, g.end());
      bool progress = true;
      while (!pending.empty() && progress) {
        progress = false;
        for (std::size_t i = 0; i < pending.size(); ++i)
          if (insert_loop(merged, loops[pending[i]])) {
            pending.erase(pending.begin() + static_cast<std::ptrdiff_t>(i));
            progress = true;
            break;
          }
      }
      out.push_back(std::move(merged));
      for (int p : pending) out.push_back(loops[p]);
    }
    return out;
  }

 private:
  Vector3d normal_at(int v) const {
    auto it = normals_.find(v);
    return it != normals_.end() && it->second.squaredNorm() > 0 ? it->second : plane_normal_;
  }

  Vector3d pos(int v) const { return soup_.vertices[v]; }

  /// The unused outgoing free edge of `v` that the smallest-angle rule picks after arriving by
  /// `in_edge` (any unused one at the start of a walk); -1 if none.
  int choose_out(int v, int in_edge, const std::unordered_set<int>& used) const {
    auto it = out_.find(v);
    if (it == out_.end()) return -1;
    int best = -1;
    double best_angle = 1e300;
    for (int e : it->second) {
      if (used.count(e)) continue;
      if (in_edge < 0) return e;
      const double a = clockwise_angle(normal_at(v), pos(hes_[in_edge].from) - pos(v), pos(hes_[e].to) - pos(v));
      if (a < best_angle) best_angle = a, best = e;
    }
    return best;
  }

  /// Step 3 precondition (beyond the paper): is the projection onto the best-fit plane injective
  /// enough for point-in-polygon? Also computes the plane and the projected loops.
  bool projection_reliable(const std::vector<std::vector<int>>& loops) {
    Vector3d centroid = Vector3d::Zero();
    std::size_t count = 0;
    for (const auto& l : loops)
      for (int v : l) centroid += pos(v), ++count;
    centroid /= static_cast<double>(count);
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& l : loops)
      for (int v : l) cov += (pos(v) - centroid) * (pos(v) - centroid).transpose();
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    Vector3d n = eig.eigenvectors().col(0);
    Vector3d face_sum = Vector3d::Zero();
    std::vector<Vector3d> face_normals;
    for (int e : edges_) {
      const auto& t = soup_.faces[hes_[e].face];
      face_normals.push_back((pos(t[1]) - pos(t[0])).cross(pos(t[2]) - pos(t[0])));
      face_sum += face_normals.back();
    }
    if (face_sum.dot(n) < 0) n = -n;
    plane_normal_ = n;
    const Vector3d u = n.unitOrthogonal(), w = n.cross(u);
    proj_.clear();
    for (const auto& l : loops) {
      std::vector<Vector2d> p;
      p.reserve(l.size());
      for (int v : l) p.emplace_back(u.dot(pos(v) - centroid), w.dot(pos(v) - centroid));
      proj_.push_back(std::move(p));
    }
    // A rim face seen from behind means the surface folds over the plane.
    for (const auto& fn : face_normals)
      if (fn.dot(n) <= 0) return false;
    return !projected_lines_cross(loops);
  }

  /// Do two projected free edges of the component cross (other than at a shared vertex)?
  /// Uniform grid over the projected segments, each cell tested pairwise.
  bool projected_lines_cross(const std::vector<std::vector<int>>& loops) const {
    struct Seg { Vector2d a, b; int va, vb; };
    std::vector<Seg> segs;
    Vector2d lo(1e300, 1e300), hi(-1e300, -1e300);
    double total = 0;
    for (std::size_t i = 0; i < loops.size(); ++i)
      for (std::size_t k = 0; k < loops[i].size(); ++k) {
        const std::size_t k1 = (k + 1) % loops[i].size();
        segs.push_back({proj_[i][k], proj_[i][k1], loops[i][k], loops[i][k1]});
        lo = lo.cwiseMin(proj_[i][k]);
        hi = hi.cwiseMax(proj_[i][k]);
        total += (proj_[i][k1] - proj_[i][k]).norm();
      }
    const double cell = std::max(total / static_cast<double>(segs.size()), 1e-12);
    const auto cells = ((hi - lo) / cell).array().floor().cast<long>() + 1;
    if (cells.x() * cells.y() > 16 * static_cast<long>(segs.size()) + 1024) return true;  // degenerate spread
    std::unordered_map<long, std::vector<int>> grid;
    for (std::size_t s = 0; s < segs.size(); ++s) {
      const Vector2d smin = segs[s].a.cwiseMin(segs[s].b), smax = segs[s].a.cwiseMax(segs[s].b);
      const long x0 = static_cast<long>((smin.x() - lo.x()) / cell), x1 = static_cast<long>((smax.x() - lo.x()) / cell);
      const long y0 = static_cast<long>((smin.y() - lo.y()) / cell), y1 = static_cast<long>((smax.y() - lo.y()) / cell);
      for (long x = x0; x <= x1; ++x)
        for (long y = y0; y <= y1; ++y) grid[x * cells.y() + y].push_back(static_cast<int>(s));
    }
    auto orient = [](const Vector2d& a, const Vector2d& b, const Vector2d& c) {
      return (b.x() - a.x()) * (c.y() - a.y()) - (b.y() - a.y()) * (c.x() - a.x());
    };
    for (const auto& [key, list] : grid)
      for (std::size_t i = 0; i < list.size(); ++i)
        for (std::size_t j = i + 1; j < list.size(); ++j) {
          const Seg &s = segs[list[i]], &t = segs[list[j]];
          if (s.va == t.va || s.va == t.vb || s.vb == t.va || s.vb == t.vb) continue;
          const double d1 = orient(s.a, s.b, t.a), d2 = orient(s.a, s.b, t.b);
          const double d3 = orient(t.a, t.b, s.a), d4 = orient(t.a, t.b, s.b);
          if (((d1 > 0 && d2 < 0) || (d1 < 0 && d2 > 0)) && ((d3 > 0 && d4 < 0) || (d3 < 0 && d4 > 0))) return true;
        }
    return false;
  }

  static bool point_in_polygon(const Vector2d& p, const std::vector<Vector2d>& poly) {
    bool in = false;
    for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++) {
      const Vector2d &a = poly[i], &b = poly[j];
      if ((a.y() > p.y()) != (b.y() > p.y()) && p.x() < (b.x() - a.x()) * (p.y() - a.y()) / (b.y() - a.y()) + a.x())
        in = !in;
    }
    return in;
  }

  static double signed_area(const std::vector<Vector2d>& poly) {
    double a = 0;
    for (std::size_t i = 0, j = poly.size() - 1; i < poly.size(); j = i++)
      a += poly[j].x() * poly[i].y() - poly[i].x() * poly[j].y();
    return 0.5 * a;
  }

  /// Steps 3-4 as the paper states them: loop L1 is inside L2 when all its points (those not on
  /// L2) are inside L2's projected polygon. The parent of a loop is its smallest container; a
  /// loop at odd depth is an inner hole (an island's rim) and joins its parent. Returns the
  /// groups, each led by its outer hole; falls back to the local rule if the depths contradict
  /// the turning sense (outer holes turn counter-clockwise, island rims clockwise).
  std::vector<std::vector<int>> groups_by_projection(const std::vector<std::vector<int>>& loops) {
    const int n = static_cast<int>(loops.size());
    std::vector<double> area(n);
    std::vector<Vector2d> bmin(n), bmax(n);
    std::vector<std::unordered_set<int>> members(n);
    for (int i = 0; i < n; ++i) {
      area[i] = signed_area(proj_[i]);
      bmin[i] = bmax[i] = proj_[i][0];
      for (const auto& p : proj_[i]) bmin[i] = bmin[i].cwiseMin(p), bmax[i] = bmax[i].cwiseMax(p);
      members[i].insert(loops[i].begin(), loops[i].end());
    }
    auto inside = [&](int a, int b) {  // is loop a inside loop b?
      if (std::abs(area[b]) <= std::abs(area[a])) return false;
      if ((bmin[a].array() < bmin[b].array()).any() || (bmax[a].array() > bmax[b].array()).any()) return false;
      bool any = false;
      for (std::size_t k = 0; k < loops[a].size(); ++k) {
        if (members[b].count(loops[a][k])) continue;
        if (!point_in_polygon(proj_[a][k], proj_[b])) return false;
        any = true;
      }
      return any;
    };
    std::vector<int> parent(n, -1);
    for (int i = 0; i < n; ++i)
      for (int j = 0; j < n; ++j)
        if (i != j && inside(i, j) && (parent[i] < 0 || std::abs(area[j]) < std::abs(area[parent[i]]))) parent[i] = j;
    std::vector<int> depth(n, 0);
    for (int i = 0; i < n; ++i) {
      for (int p = parent[i], guard = 0; p >= 0 && guard <= n; p = parent[p], ++guard) ++depth[i];
      if ((depth[i] % 2 == 1) != (area[i] < 0)) return groups_by_angle(loops);
    }
    std::vector<std::vector<int>> groups;
    std::vector<int> group_of(n, -1);
    for (int i = 0; i < n; ++i)
      if (depth[i] % 2 == 0) group_of[i] = static_cast<int>(groups.size()), groups.push_back({i});
    for (int i = 0; i < n; ++i)
      if (depth[i] % 2 == 1) groups[group_of[parent[i]]].push_back(i);
    return groups;
  }

  /// The local rule (used when the projection is unreliable): at every common point, follow the
  /// smallest-angle rule from each loop's incoming edge over all outgoing edges there; if it
  /// leads into another loop, the two bound one missing region and are grouped.
  std::vector<std::vector<int>> groups_by_angle(const std::vector<std::vector<int>>& loops) {
    const int n = static_cast<int>(loops.size());
    struct Visit { int loop; int prev, next; };
    std::unordered_map<int, std::vector<Visit>> at;
    for (int i = 0; i < n; ++i)
      for (std::size_t k = 0; k < loops[i].size(); ++k) {
        const std::size_t m = loops[i].size();
        at[loops[i][k]].push_back({i, loops[i][(k + m - 1) % m], loops[i][(k + 1) % m]});
      }
    UnionFind uf(n);
    for (const auto& [v, visits] : at) {
      if (visits.size() < 2) continue;
      for (const auto& in : visits) {
        int best = -1;
        double best_angle = 1e300;
        for (const auto& out : visits) {
          const double a = clockwise_angle(normal_at(v), pos(in.prev) - pos(v), pos(out.next) - pos(v));
          if (a < best_angle) best_angle = a, best = out.loop;
        }
        if (best != in.loop) uf.unite(in.loop, best);
      }
    }
    std::vector<std::vector<int>> groups;
    std::unordered_map<int, int> index;
    for (int i = 0; i < n; ++i) {
      auto [it, inserted] = index.emplace(uf.find(i), static_cast<int>(groups.size()));
      if (inserted) groups.emplace_back();
      groups[it->second].push_back(i);
    }
    // Lead each group with its longest loop (the outer rim when there is one).
    for (auto& g : groups)
      std::stable_sort(g.begin(), g.end(), [&](int a, int b) { return loops[a].size() > loops[b].size(); });
    return groups;
  }

  /// Steps 5-6: inserts `inner` into `outer` at a common point. Among every occurrence of every
  /// shared vertex C in the outer line, the paper's rule picks the one where the angle between
  /// C->(previous outer point) and C->(inner's next point) is smallest; we measure it clockwise
  /// in the tangent plane and prefer occurrences whose sector actually contains the inner
  /// line's first edge (after a merge C occurs more than once). False if they share no vertex.
  bool insert_loop(std::vector<int>& outer, const std::vector<int>& inner) const {
    std::unordered_map<int, int> inner_pos;
    for (std::size_t k = 0; k < inner.size(); ++k) inner_pos.emplace(inner[k], static_cast<int>(k));
    const std::size_t m = outer.size();
    int best_t = -1, best_k = -1;
    bool best_in_sector = false;
    double best_angle = 1e300;
    for (std::size_t t = 0; t < m; ++t) {
      auto it = inner_pos.find(outer[t]);
      if (it == inner_pos.end()) continue;
      const int c = outer[t], k = it->second;
      const Vector3d n = normal_at(c);
      const Vector3d ref = pos(outer[(t + m - 1) % m]) - pos(c);
      const double a_inner = clockwise_angle(n, ref, pos(inner[(k + 1) % inner.size()]) - pos(c));
      const double a_outer = clockwise_angle(n, ref, pos(outer[(t + 1) % m]) - pos(c));
      const bool in_sector = a_inner < a_outer;
      if ((in_sector && !best_in_sector) || (in_sector == best_in_sector && a_inner < best_angle)) {
        best_in_sector = in_sector;
        best_angle = a_inner;
        best_t = static_cast<int>(t);
        best_k = k;
      }
    }
    if (best_t < 0) return false;
    // outer[..t] C, inner[k+1..], inner[..k] (= C), outer[t+1..]
    std::vector<int> piece;
    piece.reserve(inner.size());
    for (std::size_t i = 1; i <= inner.size(); ++i) piece.push_back(inner[(best_k + i) % inner.size()]);
    outer.insert(outer.begin() + best_t + 1, piece.begin(), piece.end());
    return true;
  }

  const TriangleSoup& soup_;
  const std::vector<HalfEdge>& hes_;
  const std::vector<int>& edges_;
  const std::unordered_map<int, Vector3d>& normals_;
  std::unordered_map<int, std::vector<int>> out_;
  Vector3d plane_normal_ = Vector3d::UnitZ();
  std::vector<std::vector<Vector2d>> proj_;
};

}  // namespace

std::vector<Hole> find_holes(const TriangleSoup& soup, HoleStats* stats) {
  HoleStats st;
  const std::vector<HalfEdge> hes = free_half_edges(soup);
  st.boundary_edges = hes.size();

  // Boundary components (the paper's "hole line" sets) and the common points: vertices with
  // more than one outgoing free edge, i.e. on more than one hole line.
  UnionFind uf(soup.vertices.size());
  std::unordered_map<int, int> out_degree;
  for (const auto& h : hes) uf.unite(h.from, h.to), ++out_degree[h.from];
  std::unordered_map<int, Vector3d> normals;  // area-weighted normals at the common points
  for (const auto& [v, d] : out_degree)
    if (d > 1) normals.emplace(v, Vector3d::Zero()), ++st.common_points;
  if (!normals.empty())
    for (const auto& t : soup.faces) {
      if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) continue;
      const Vector3d fn = (soup.vertices[t[1]] - soup.vertices[t[0]]).cross(soup.vertices[t[2]] - soup.vertices[t[0]]);
      for (int c : t) {
        auto it = normals.find(c);
        if (it != normals.end()) it->second += fn;
      }
    }
  for (auto& [v, n] : normals)
    if (n.squaredNorm() > 0) n.normalize();

  std::vector<std::vector<int>> components;
  std::unordered_map<int, int> comp_of_root;
  for (std::size_t e = 0; e < hes.size(); ++e) {
    auto [it, inserted] = comp_of_root.emplace(uf.find(hes[e].from), static_cast<int>(components.size()));
    if (inserted) components.emplace_back();
    components[it->second].push_back(static_cast<int>(e));
  }

  std::vector<Hole> holes;
  for (const auto& comp : components) {
    bool nested = false;
    for (int e : comp) nested = nested || out_degree[hes[e].from] > 1;
    NestedSplitter splitter(soup, hes, comp, normals);
    std::vector<std::vector<int>> loops = splitter.split_into_loops();
    if (nested) {
      ++st.nested_holes;
      loops = splitter.merge_inner(std::move(loops));
    } else {
      ++st.single_holes;
    }
    for (auto& l : loops) {
      Hole h;
      h.loop = std::move(l);
      h.origin = nested ? Hole::Origin::nested : Hole::Origin::single;
      h.perimeter = loop_perimeter(soup, h.loop);
      h.diameter = loop_diameter(soup, h.loop);
      holes.push_back(std::move(h));
    }
  }
  st.holes_out = holes.size();
  if (stats) *stats = st;
  return holes;
}

}  // namespace s2c::repair
