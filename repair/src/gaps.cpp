// Gap closing by vertex-edge contraction (../shared/papers/repair-survey.txt, "Gap Closing"):
// a boundary vertex v and a boundary edge e within the tolerance form a candidate with error
// |v - c|, c the closest point of e. Candidates are processed cheapest first from a priority
// queue; c interior to e splits e and its one triangle, then v and c are merged (v moves to c).
// When c is (nearly) an endpoint of e, v is merged with that endpoint instead, which welds the
// matching vertices of an unwelded STL seam without creating slivers.
//
// The queue is lazy: an entry is re-validated when popped (v still on the boundary, e still a
// free edge, distance unchanged - otherwise it is re-queued with its new distance). Candidates
// come from two uniform hash grids (boundary vertices by cell, boundary edges in every cell
// within the tolerance of the segment); new and moved elements are added as they appear and
// stale grid entries are filtered by the same validation. A last pass closes the free-edge
// slivers a zipper can leave at its end (see close_slivers).
#include "s2c/repair/gaps.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <queue>
#include <string>
#include <tuple>
#include <unordered_map>
#include <vector>

#include "s2c/core/errors.h"

namespace s2c::repair {
namespace {

using Eigen::Vector3d;
using Tri = std::array<int, 3>;

std::uint64_t edge_key(int a, int b) { return undirected_edge_key(a, b); }

struct Cell {
  long x, y, z;
  bool operator==(const Cell& o) const { return x == o.x && y == o.y && z == o.z; }
  bool operator!=(const Cell& o) const { return !(*this == o); }
};
struct CellHash {
  std::size_t operator()(const Cell& c) const {
    std::uint64_t h = static_cast<std::uint64_t>(c.x) * 0x9E3779B97F4A7C15ull;
    h ^= static_cast<std::uint64_t>(c.y) * 0xC2B2AE3D27D4EB4Full + (h << 6) + (h >> 2);
    h ^= static_cast<std::uint64_t>(c.z) * 0x165667B19E3779F9ull + (h << 6) + (h >> 2);
    return static_cast<std::size_t>(h);
  }
};

struct Candidate {
  double distance;
  int v, a, b;
  bool operator>(const Candidate& o) const {
    if (distance != o.distance) return distance > o.distance;
    if (v != o.v) return v > o.v;  // deterministic order among ties
    if (a != o.a) return a > o.a;
    return b > o.b;
  }
};

bool degenerate(const Vector3d& a, const Vector3d& b, const Vector3d& c) {
  const double scale = std::max({(b - a).squaredNorm(), (c - a).squaredNorm(), (c - b).squaredNorm()});
  return (b - a).cross(c - a).norm() <= 1e-12 * scale || scale == 0;
}

class GapCloser {
 public:
  GapCloser(TriangleSoup& soup, const GapOptions& options) : soup_(soup), options_(options) {}

  GapStats run() {
    const int nv = static_cast<int>(soup_.vertices.size());
    vert_faces_.assign(nv, {});
    alive_.assign(nv, 1);
    for (std::size_t f = 0; f < soup_.faces.size(); ++f) {
      const Tri t = soup_.faces[f];
      for (int c : t)
        if (c < 0 || c >= nv)
          throw InvalidInput("close_gaps: face " + std::to_string(f) + " refers to missing vertex " + std::to_string(c));
      if (t[0] == t[1] || t[1] == t[2] || t[2] == t[0]) continue;  // left alone, takes no part
      link_face(static_cast<int>(f));
    }
    // Boundary edges and the tolerance.
    std::vector<std::pair<int, int>> boundary;
    double total = 0;
    for (const auto& [key, faces] : edge_faces_)
      if (faces.size() == 1) {
        const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
        boundary.emplace_back(a, b);
        total += (pos(a) - pos(b)).norm();
      }
    if (boundary.empty()) return stats_;
    std::sort(boundary.begin(), boundary.end());  // the map's order is not deterministic
    const double mean = total / static_cast<double>(boundary.size());
    tol_ = options_.tolerance > 0 ? options_.tolerance : 0.5 * mean;
    if (!(tol_ > 0)) return stats_;
    cell_ = std::max(tol_, mean);

    for (const auto& [a, b] : boundary) add_edge_to_grid(a, b);
    for (const auto& [a, b] : boundary) add_vertex_to_grid(a), add_vertex_to_grid(b);
    for (const auto& [a, b] : boundary) {
      queue_vertex(a);
      queue_vertex(b);
    }
    // Every contraction welds or splits along a free edge; the caps keep a pathological input
    // (candidates that keep re-queueing each other) from running forever.
    const std::size_t max_contractions = 4 * boundary.size() + 16;
    std::size_t pops = 0;
    const std::size_t max_pops = 64 * boundary.size() + 1024;
    while (!queue_.empty() && stats_.contractions < max_contractions && pops++ < max_pops) {
      const Candidate cand = queue_.top();
      queue_.pop();
      process(cand);
    }
    close_slivers();
    return stats_;
  }

 private:
  const Vector3d& pos(int v) const { return soup_.vertices[v]; }

  std::vector<int>& faces_of_edge(int a, int b) { return edge_faces_[edge_key(a, b)]; }
  std::size_t edge_count(int a, int b) const {
    auto it = edge_faces_.find(edge_key(a, b));
    return it == edge_faces_.end() ? 0 : it->second.size();
  }

  void link_face(int f) {
    const Tri& t = soup_.faces[f];
    for (int k = 0; k < 3; ++k) {
      faces_of_edge(t[k], t[(k + 1) % 3]).push_back(f);
      vert_faces_[t[k]].push_back(f);
    }
  }
  void unlink_face(int f) {
    const Tri& t = soup_.faces[f];
    for (int k = 0; k < 3; ++k) {
      auto it = edge_faces_.find(edge_key(t[k], t[(k + 1) % 3]));
      auto& list = it->second;
      list.erase(std::find(list.begin(), list.end(), f));
      if (list.empty()) edge_faces_.erase(it);
      auto& vf = vert_faces_[t[k]];
      vf.erase(std::find(vf.begin(), vf.end(), f));
    }
  }

  /// Does face f traverse a->b (rather than b->a)?
  bool traverses(int f, int a, int b) const {
    const Tri& t = soup_.faces[f];
    for (int k = 0; k < 3; ++k)
      if (t[k] == a && t[(k + 1) % 3] == b) return true;
    return false;
  }

  std::vector<std::pair<int, int>> boundary_edges_of(int v) const {
    std::vector<std::pair<int, int>> out;
    for (int f : vert_faces_[v]) {
      const Tri& t = soup_.faces[f];
      for (int k = 0; k < 3; ++k) {
        const int a = t[k], b = t[(k + 1) % 3];
        if ((a == v || b == v) && edge_count(a, b) == 1) out.emplace_back(a, b);
      }
    }
    return out;
  }

  Cell cell_of(const Vector3d& p) const {
    return {static_cast<long>(std::floor(p.x() / cell_)), static_cast<long>(std::floor(p.y() / cell_)),
            static_cast<long>(std::floor(p.z() / cell_))};
  }
  /// The cells within the tolerance of segment ab: boxes around samples along the segment (a
  /// long CAD edge covers a thin band of cells, not its whole bounding box).
  std::vector<Cell> edge_cells(int a, int b) const {
    const double len = (pos(b) - pos(a)).norm();
    const long samples = static_cast<long>(std::min(std::ceil(len / (0.5 * cell_)), 1e6)) + 1;
    const Vector3d pad = Vector3d::Constant(tol_ + 0.25 * cell_);
    std::vector<Cell> cells;
    for (long i = 0; i <= samples; ++i) {
      const Vector3d p = pos(a) + (pos(b) - pos(a)) * (static_cast<double>(i) / static_cast<double>(samples));
      const Cell c0 = cell_of(p - pad), c1 = cell_of(p + pad);
      for (long x = c0.x; x <= c1.x; ++x)
        for (long y = c0.y; y <= c1.y; ++y)
          for (long z = c0.z; z <= c1.z; ++z) cells.push_back({x, y, z});
    }
    std::sort(cells.begin(), cells.end(),
              [](const Cell& l, const Cell& r) { return std::tie(l.x, l.y, l.z) < std::tie(r.x, r.y, r.z); });
    cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
    return cells;
  }

  void add_edge_to_grid(int a, int b) {
    for (const Cell& c : edge_cells(a, b)) edge_grid_[c].emplace_back(a, b);
  }
  void add_vertex_to_grid(int v) { vertex_grid_[cell_of(pos(v))].push_back(v); }

  /// Closest point of segment ab to p: returns the parameter t in [0, 1].
  static double closest_t(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
    const Vector3d d = b - a;
    const double len2 = d.squaredNorm();
    if (len2 == 0) return 0;
    return std::clamp((p - a).dot(d) / len2, 0.0, 1.0);
  }

  /// Is (v, a-b) a candidate at all: e a free edge, v on the boundary and not part of e's face.
  bool valid(int v, int a, int b, int* face) const {
    if (!alive_[v] || v == a || v == b) return false;
    auto it = edge_faces_.find(edge_key(a, b));
    if (it == edge_faces_.end() || it->second.size() != 1) return false;
    const Tri& t = soup_.faces[it->second[0]];
    if (t[0] == v || t[1] == v || t[2] == v) return false;
    *face = it->second[0];
    return true;
  }

  void push(int v, int a, int b) {
    int f = 0;
    if (!valid(v, a, b, &f)) return;
    const double t = closest_t(pos(v), pos(a), pos(b));
    const double d = (pos(v) - (pos(a) + t * (pos(b) - pos(a)))).norm();
    if (d <= tol_) queue_.push({d, v, a, b});
  }

  void queue_vertex(int v) {
    if (boundary_edges_of(v).empty()) return;
    auto it = edge_grid_.find(cell_of(pos(v)));
    if (it == edge_grid_.end()) return;
    const auto edges = it->second;  // push() does not touch the grid, but keep it simple
    for (const auto& [a, b] : edges) push(v, a, b);
  }

  void queue_edge(int a, int b) {
    std::vector<int> near;
    for (const Cell& c : edge_cells(a, b)) {
      auto it = vertex_grid_.find(c);
      if (it != vertex_grid_.end()) near.insert(near.end(), it->second.begin(), it->second.end());
    }
    std::sort(near.begin(), near.end());
    near.erase(std::unique(near.begin(), near.end()), near.end());
    for (int v : near)
      if (!boundary_edges_of(v).empty()) push(v, a, b);
  }

  void process(const Candidate& cand) {
    int f = 0;
    if (!valid(cand.v, cand.a, cand.b, &f)) return;
    if (boundary_edges_of(cand.v).empty()) return;
    const Vector3d &pv = pos(cand.v), &pa = pos(cand.a), &pb = pos(cand.b);
    const double t = closest_t(pv, pa, pb);
    const Vector3d c = pa + t * (pb - pa);
    const double d = (pv - c).norm();
    if (d > tol_) return;
    if (d > cand.distance * (1 + 1e-9) + 1e-15) {  // geometry changed since it was queued
      queue_.push({d, cand.v, cand.a, cand.b});
      return;
    }
    const double len = (pb - pa).norm();
    const double snap = 0.05 * len;
    bool done = false;
    if (t * len <= snap)
      done = merge_into_vertex(cand.v, cand.a);
    else if ((1 - t) * len <= snap)
      done = merge_into_vertex(cand.v, cand.b);
    else
      done = split_and_merge(cand.v, f, cand.a, cand.b, c);
    if (!done) return;
    ++stats_.contractions;
    stats_.max_distance = std::max(stats_.max_distance, d);
  }

  /// Would moving v to `to` flip or degenerate one of v's faces?
  bool move_breaks_faces(int v, const Vector3d& to) const {
    for (int g : vert_faces_[v]) {
      const Tri& t = soup_.faces[g];
      std::array<Vector3d, 3> p{pos(t[0]), pos(t[1]), pos(t[2])};
      const Vector3d before = (p[1] - p[0]).cross(p[2] - p[0]);
      for (int i = 0; i < 3; ++i)
        if (t[i] == v) p[i] = to;
      if (degenerate(p[0], p[1], p[2])) return true;
      if ((p[1] - p[0]).cross(p[2] - p[0]).dot(before) <= 0) return true;
    }
    return false;
  }

  /// c interior to e = (a, b): split e's face f = (p, q, x) (p->q being e in f's direction) into
  /// (p, v, x) and (v, q, x) and move v to c.
  bool split_and_merge(int v, int f, int a, int b, const Vector3d& c) {
    Tri t = soup_.faces[f];
    int k = 0;
    while (!((t[k] == a || t[k] == b) && (t[(k + 1) % 3] == a || t[(k + 1) % 3] == b))) ++k;
    const int p = t[k], q = t[(k + 1) % 3], x = t[(k + 2) % 3];
    // New edges p->v, v->q (each may close a free edge of v that runs the other way) and v-x
    // (must be new: it gets both new faces).
    if (edge_count(v, x) != 0) return false;
    auto closes = [&](int from, int to) {  // the new face traverses from->to
      auto it = edge_faces_.find(edge_key(from, to));
      if (it == edge_faces_.end()) return true;
      return it->second.size() == 1 && traverses(it->second[0], to, from);
    };
    if (!closes(p, v) || !closes(v, q)) return false;
    if (degenerate(pos(p), c, pos(x)) || degenerate(c, pos(q), pos(x))) return false;
    if (move_breaks_faces(v, c)) return false;

    unlink_face(f);
    soup_.vertices[v] = c;
    soup_.faces[f] = {p, v, x};
    link_face(f);
    soup_.faces.push_back({v, q, x});
    link_face(static_cast<int>(soup_.faces.size()) - 1);
    ++stats_.edge_splits;
    after_change({v, p, q});
    return true;
  }

  /// v and w (the endpoint of e) become one vertex at w's position.
  bool merge_into_vertex(int v, int w) {
    for (int g : vert_faces_[v]) {
      const Tri& t = soup_.faces[g];
      if (t[0] == w || t[1] == w || t[2] == w) return false;  // would collapse a face
    }
    if (move_breaks_faces(v, pos(w))) return false;
    // Every edge v-y becomes w-y: at most two faces afterwards, in opposite directions, and no
    // face may end up with the same corners as an existing one.
    std::unordered_map<int, std::vector<std::pair<int, bool>>> uses;  // y -> (face, traverses w->y)
    for (int g : vert_faces_[v]) {
      const Tri& t = soup_.faces[g];
      for (int k = 0; k < 3; ++k) {
        if (t[k] != v) continue;
        uses[t[(k + 1) % 3]].push_back({g, true});
        uses[t[(k + 2) % 3]].push_back({g, false});
      }
    }
    for (const auto& [y, list] : uses) {
      auto it = edge_faces_.find(edge_key(w, y));
      std::vector<bool> dirs;
      if (it != edge_faces_.end())
        for (int g : it->second) dirs.push_back(traverses(g, w, y));
      for (const auto& u : list) dirs.push_back(u.second);
      if (dirs.size() > 2) return false;
      if (dirs.size() == 2 && dirs[0] == dirs[1]) return false;
    }
    for (int g : vert_faces_[v]) {
      Tri t = soup_.faces[g];
      for (int& c : t)
        if (c == v) c = w;
      std::array<int, 3> s = t;
      std::sort(s.begin(), s.end());
      for (int h : vert_faces_[w]) {
        std::array<int, 3> u = soup_.faces[h];
        std::sort(u.begin(), u.end());
        if (u == s) return false;
      }
    }
    const std::vector<int> moved = vert_faces_[v];
    std::vector<int> touched{w};
    for (int g : moved) {
      unlink_face(g);
      for (int& c : soup_.faces[g])
        if (c == v) c = w;
      link_face(g);
      for (int c : soup_.faces[g]) touched.push_back(c);
    }
    alive_[v] = 0;
    after_change(touched);
    return true;
  }

  /// Where two zipped boundaries end, a triangle of free edges can remain whose corner lies
  /// within the tolerance of the opposite side, but contracting it would collapse an edge (its
  /// corner is already joined to that side's endpoints). Such a sliver is closed with one face
  /// in the hole's order, which gives each of its edges a second face of opposite direction.
  void close_slivers() {
    std::vector<std::pair<int, int>> hole_edges;  // hole direction: reverse of the face's edge
    for (const auto& [key, faces] : edge_faces_) {
      if (faces.size() != 1) continue;
      const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
      hole_edges.push_back(traverses(faces[0], a, b) ? std::make_pair(b, a) : std::make_pair(a, b));
    }
    std::sort(hole_edges.begin(), hole_edges.end());
    auto next_of = [&](int u) {
      auto lo = std::lower_bound(hole_edges.begin(), hole_edges.end(), std::make_pair(u, -1));
      std::vector<int> out;
      for (; lo != hole_edges.end() && lo->first == u; ++lo) out.push_back(lo->second);
      return out;
    };
    for (const auto& [u, w] : hole_edges)
      for (int x : next_of(w)) {
        if (x == u) continue;
        const auto back = next_of(x);
        if (std::find(back.begin(), back.end(), u) == back.end()) continue;
        if (edge_count(u, w) != 1 || edge_count(w, x) != 1 || edge_count(x, u) != 1) continue;  // filled already
        const Vector3d &pu = pos(u), &pw = pos(w), &px = pos(x);
        if (degenerate(pu, pw, px)) continue;
        const double longest = std::max({(pw - pu).norm(), (px - pw).norm(), (pu - px).norm()});
        const double height = (pw - pu).cross(px - pu).norm() / longest;
        if (height > tol_) continue;
        soup_.faces.push_back({u, w, x});
        link_face(static_cast<int>(soup_.faces.size()) - 1);
        stats_.max_distance = std::max(stats_.max_distance, height);
      }
  }

  /// Registers the free edges around the changed vertices and queues their new candidates.
  void after_change(const std::vector<int>& changed) {
    for (int u : changed) {
      if (!alive_[u]) continue;
      add_vertex_to_grid(u);
      for (const auto& [a, b] : boundary_edges_of(u)) {
        add_edge_to_grid(a, b);
        queue_edge(a, b);
      }
      queue_vertex(u);
    }
  }

  TriangleSoup& soup_;
  const GapOptions& options_;
  GapStats stats_;
  double tol_ = 0, cell_ = 1;
  std::unordered_map<std::uint64_t, std::vector<int>> edge_faces_;
  std::vector<std::vector<int>> vert_faces_;
  std::vector<char> alive_;
  std::unordered_map<Cell, std::vector<std::pair<int, int>>, CellHash> edge_grid_;
  std::unordered_map<Cell, std::vector<int>, CellHash> vertex_grid_;
  std::priority_queue<Candidate, std::vector<Candidate>, std::greater<Candidate>> queue_;
};

}  // namespace

GapStats close_gaps(TriangleSoup& soup, const GapOptions& options) {
  GapCloser closer(soup, options);
  return closer.run();
}

}  // namespace s2c::repair
