// Defective variants of a clean mesh (see defect_corpus.h). Each defect is placed at a "site"
// (a vertex picked by farthest-point sampling from a seeded start), applied, and verified by the
// change it makes to check_mesh's counts; a placement that does more or less than intended
// (a disc wrapping round a thin wall, a pushed patch that misses the opposite wall) is undone
// and tried at the next site.
#include "defect_corpus.h"

#include "common/sampling.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <functional>
#include <fstream>
#include <queue>
#include <unordered_map>
#include <unordered_set>
#include <utility>

#include "s2c/core/errors.h"
#include "s2c/core/files.h"

namespace s2c::bench {
namespace {

using Eigen::Vector3d;
using Tri = std::array<int, 3>;

/// The benchmarks' SplitMix64, with an index draw.
struct CorpusRng : s2c::bench::Rng {
  explicit CorpusRng(std::uint64_t seed) : s2c::bench::Rng{seed} {}
  std::size_t index(std::size_t n) { return static_cast<std::size_t>(next() % n); }
};

std::uint64_t edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(a)) << 32) | static_cast<std::uint32_t>(b);
}

Vector3d face_normal(const TriangleSoup& s, const Tri& t) {
  return (s.vertices[t[1]] - s.vertices[t[0]]).cross(s.vertices[t[2]] - s.vertices[t[0]]);
}

/// Longest-edge bisection until no edge exceeds `target`: splitting an edge splits every face
/// on it, so the mesh stays conforming, closed and manifold.
TriangleSoup refine(TriangleSoup s, double target, std::size_t max_faces) {
  std::unordered_map<std::uint64_t, std::vector<int>> ef;
  auto link = [&](int f) {
    for (int k = 0; k < 3; ++k) ef[edge_key(s.faces[f][k], s.faces[f][(k + 1) % 3])].push_back(f);
  };
  auto unlink = [&](int f) {
    for (int k = 0; k < 3; ++k) {
      auto it = ef.find(edge_key(s.faces[f][k], s.faces[f][(k + 1) % 3]));
      it->second.erase(std::find(it->second.begin(), it->second.end(), f));
      if (it->second.empty()) ef.erase(it);
    }
  };
  struct E { double len; int a, b; bool operator<(const E& o) const { return std::tie(len, a, b) < std::tie(o.len, o.a, o.b); } };
  std::priority_queue<E> heap;
  auto push = [&](int a, int b) {
    const double l = (s.vertices[a] - s.vertices[b]).norm();
    if (l > target) heap.push({l, std::min(a, b), std::max(a, b)});
  };
  for (std::size_t f = 0; f < s.faces.size(); ++f) link(static_cast<int>(f));
  for (const auto& [key, faces] : ef) push(static_cast<int>(key >> 32), static_cast<int>(key & 0xffffffffu));
  while (!heap.empty() && s.faces.size() < max_faces) {
    const E e = heap.top();
    heap.pop();
    auto it = ef.find(edge_key(e.a, e.b));
    if (it == ef.end()) continue;  // already split
    const std::vector<int> faces = it->second;
    const int m = static_cast<int>(s.vertices.size());
    s.vertices.push_back(0.5 * (s.vertices[e.a] + s.vertices[e.b]));
    for (int f : faces) {
      const Tri t = s.faces[f];
      int k = 0;
      while (!((t[k] == e.a || t[k] == e.b) && (t[(k + 1) % 3] == e.a || t[(k + 1) % 3] == e.b))) ++k;
      const int p = t[k], q = t[(k + 1) % 3], x = t[(k + 2) % 3];
      unlink(f);
      s.faces[f] = {p, m, x};
      link(f);
      s.faces.push_back({m, q, x});
      link(static_cast<int>(s.faces.size()) - 1);
      push(m, x);
    }
    push(e.a, m);
    push(m, e.b);
  }
  s.normals.clear();
  return s;
}

/// Drops unreferenced vertices (removed faces leave some behind).
void compact(TriangleSoup& s) {
  std::vector<int> map(s.vertices.size(), -1);
  std::vector<Vector3d> vs;
  for (auto& t : s.faces)
    for (int& v : t) {
      if (map[v] < 0) map[v] = static_cast<int>(vs.size()), vs.push_back(s.vertices[v]);
      v = map[v];
    }
  s.vertices = std::move(vs);
  s.normals.clear();
}

/// Vertex -> faces, vertex -> neighbours of the current soup.
struct Topology {
  std::vector<std::vector<int>> vf, vv;
  explicit Topology(const TriangleSoup& s) : vf(s.vertices.size()), vv(s.vertices.size()) {
    for (std::size_t f = 0; f < s.faces.size(); ++f)
      for (int k = 0; k < 3; ++k) {
        const int a = s.faces[f][k], b = s.faces[f][(k + 1) % 3];
        vf[a].push_back(static_cast<int>(f));
        vv[a].push_back(b);
        vv[b].push_back(a);
      }
    for (auto& n : vv) {
      std::sort(n.begin(), n.end());
      n.erase(std::unique(n.begin(), n.end()), n.end());
    }
  }
};

/// Geodesic (edge-path) distances from `src` up to `radius`.
std::unordered_map<int, double> geodesic_ball(const TriangleSoup& s, const Topology& topo, int src, double radius) {
  std::unordered_map<int, double> dist{{src, 0.0}};
  using Item = std::pair<double, int>;
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> q;
  q.push({0.0, src});
  while (!q.empty()) {
    const auto [d, v] = q.top();
    q.pop();
    if (d > dist[v]) continue;
    for (int w : topo.vv[v]) {
      const double nd = d + (s.vertices[v] - s.vertices[w]).norm();
      if (nd > radius) continue;
      auto it = dist.find(w);
      if (it == dist.end() || nd < it->second) {
        dist[w] = nd;
        q.push({nd, w});
      }
    }
  }
  return dist;
}

/// Faces with all three corners strictly inside the ball.
std::vector<int> disc_faces(const TriangleSoup& s, const Topology& topo, int src, double radius) {
  const auto ball = geodesic_ball(s, topo, src, radius);
  std::vector<int> out;
  for (std::size_t f = 0; f < s.faces.size(); ++f) {
    bool in = true;
    for (int v : s.faces[f]) in = in && ball.count(v) && ball.at(v) < radius;
    if (in) out.push_back(static_cast<int>(f));
  }
  return out;
}

void remove_faces(TriangleSoup& s, std::vector<int> faces) {
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  std::vector<Tri> kept;
  kept.reserve(s.faces.size());
  for (std::size_t f = 0, k = 0; f < s.faces.size(); ++f) {
    if (k < faces.size() && faces[k] == static_cast<int>(f)) {
      ++k;
      continue;
    }
    kept.push_back(s.faces[f]);
  }
  s.faces = std::move(kept);
}

Vector3d vertex_normal(const TriangleSoup& s, const Topology& topo, int v) {
  Vector3d n = Vector3d::Zero();
  for (int f : topo.vf[v]) n += face_normal(s, s.faces[f]);
  return n.normalized();
}

/// Faces around v in rotational order (following the faces' orientation); empty if v is not
/// an interior manifold vertex.
std::vector<int> ordered_fan(const TriangleSoup& s, const Topology& topo, int v) {
  std::unordered_map<int, int> by_first;  // a -> face (v, a, b)
  for (int f : topo.vf[v]) {
    const Tri& t = s.faces[f];
    int k = 0;
    while (t[k] != v) ++k;
    if (!by_first.emplace(t[(k + 1) % 3], f).second) return {};
  }
  std::vector<int> fan;
  int f = topo.vf[v].empty() ? -1 : topo.vf[v][0];
  for (std::size_t i = 0; i < topo.vf[v].size() && f >= 0; ++i) {
    fan.push_back(f);
    const Tri& t = s.faces[f];
    int k = 0;
    while (t[k] != v) ++k;
    auto it = by_first.find(t[(k + 2) % 3]);
    f = it == by_first.end() ? -1 : it->second;
  }
  if (fan.size() != topo.vf[v].size() || f != fan[0]) return {};
  return fan;
}

/// Nearest hit of the ray o + t d (t > 0) with faces not touching `skip`; -1 if none.
double ray_hit(const TriangleSoup& s, const Vector3d& o, const Vector3d& d, const std::unordered_set<int>& skip) {
  double best = -1;
  for (const auto& t : s.faces) {
    if (skip.count(t[0]) || skip.count(t[1]) || skip.count(t[2])) continue;
    const Vector3d &a = s.vertices[t[0]], e1 = s.vertices[t[1]] - a, e2 = s.vertices[t[2]] - a;
    const Vector3d p = d.cross(e2);
    const double det = e1.dot(p);
    if (std::abs(det) < 1e-14) continue;
    const Vector3d tv = o - a;
    const double u = tv.dot(p) / det;
    if (u < 0 || u > 1) continue;
    const Vector3d q = tv.cross(e1);
    const double w = d.dot(q) / det;
    if (w < 0 || u + w > 1) continue;
    const double dist = e2.dot(q) / det;
    if (dist > 0 && (best < 0 || dist < best)) best = dist;
  }
  return best;
}

struct Plane {
  Vector3d n, o;
};

class Builder {
 public:
  Builder(TriangleSoup base, const DefectOptions& options, double edge)
      : base_(std::move(base)), options_(options), edge_(edge), rng_(options.seed * 0x2545F4914F6CDD1Dull + 17) {
    const Bounds b = bounds(base_);
    diag_ = b.diagonal();
    // The gap: a plane section across the longest extent, placed (among seeded candidates)
    // as far from every vertex as possible so the cut makes no slivers.
    Eigen::Index axis = 0;
    (b.max - b.min).maxCoeff(&axis);
    gap_plane_.n = Vector3d::Unit(axis);
    double best = -1;
    for (int i = 0; i < 16; ++i) {
      Vector3d o = b.center();
      o[axis] += (rng_.uniform() - 0.5) * 0.3 * (b.max[axis] - b.min[axis]);
      double closest = 1e300;
      for (const auto& p : base_.vertices) closest = std::min(closest, std::abs((p - o).dot(gap_plane_.n)));
      if (closest > best) best = closest, gap_plane_.o = o;
    }
    // Sites: farthest-point sampling over vertices away from the gap plane.
    std::vector<int> cand;
    for (std::size_t v = 0; v < base_.vertices.size(); ++v)
      if (std::abs((base_.vertices[v] - gap_plane_.o).dot(gap_plane_.n)) > 4 * edge_) cand.push_back(static_cast<int>(v));
    if (cand.size() < 16) throw InvalidInput("mesh too small to place the defects (" + std::to_string(cand.size()) + " vertices)");
    std::vector<double> d(cand.size(), 1e300);
    int cur = static_cast<int>(rng_.index(cand.size()));
    for (int k = 0; k < 256; ++k) {
      sites_.push_back(cand[cur]);
      for (std::size_t i = 0; i < cand.size(); ++i)
        d[i] = std::min(d[i], (base_.vertices[cand[i]] - base_.vertices[cand[cur]]).squaredNorm());
      cur = static_cast<int>(std::max_element(d.begin(), d.end()) - d.begin());
      if (d[cur] == 0) break;
    }
  }

  const TriangleSoup& base() const { return base_; }

  /// Applies `defect` to the variant, trying sites in order until the check counts change as
  /// `expected` says. A defect reaches `radius` edge lengths around its site; sites whose
  /// defect would come within an edge length of one placed before are skipped.
  bool place(DefectVariant& var, std::vector<std::pair<int, double>>& used, double radius,
             const std::function<bool(TriangleSoup&, int)>& defect,
             const std::function<bool(const CheckResult&, const CheckResult&)>& expected, bool self_intersections = false) {
    CheckOptions co;
    co.self_intersections = self_intersections;
    const CheckResult before = check_mesh(var.soup, co);
    for (int site : sites_) {
      bool far = true;
      for (const auto& [u, r] : used) far = far && (base_.vertices[site] - base_.vertices[u]).norm() > (radius + r + 1) * edge_;
      if (!far) continue;
      TriangleSoup trial = var.soup;
      if (!defect(trial, site)) continue;
      if (!expected(before, check_mesh(trial, co))) continue;
      var.soup = std::move(trial);
      used.emplace_back(site, radius);
      return true;
    }
    return false;
  }

  // --- the defects -------------------------------------------------------------------------

  bool hole(TriangleSoup& s, int site) const {
    const Topology topo(s);
    const auto faces = disc_faces(s, topo, site, 2.5 * edge_);
    if (faces.size() < 4) return false;
    remove_faces(s, faces);
    return true;
  }
  static bool is_one_more_hole(const CheckResult& a, const CheckResult& b) {
    return b.boundary_loops == a.boundary_loops + 1 && b.nonmanifold_vertices == a.nonmanifold_vertices &&
           b.nonmanifold_edges == a.nonmanifold_edges && b.components == a.components;
  }

  /// Two face discs touching at `site`: the one-rings of two neighbours of the site that lie
  /// on opposite sides of its fan, with faces of the fan kept between them on both sides.
  bool touching_discs(TriangleSoup& s, int site) const {
    const Topology topo(s);
    const auto fan = ordered_fan(s, topo, site);
    const std::size_t k = fan.size();
    if (k < 6) return false;
    auto spoke = [&](int f) {  // the vertex after the site in face f
      const Tri& t = s.faces[f];
      int i = 0;
      while (t[i] != site) ++i;
      return t[(i + 1) % 3];
    };
    const int a = spoke(fan[1]), b = spoke(fan[k / 2 + 1]);
    std::vector<int> faces = topo.vf[a];
    faces.insert(faces.end(), topo.vf[b].begin(), topo.vf[b].end());
    for (int n : topo.vv[a])  // the two discs may meet only at the site
      if (n != site && std::binary_search(topo.vv[b].begin(), topo.vv[b].end(), n)) return false;
    remove_faces(s, faces);
    return true;
  }
  static bool is_one_more_nested(const CheckResult& a, const CheckResult& b) {
    return b.boundary_loops == a.boundary_loops + 1 && b.nonmanifold_vertices == a.nonmanifold_vertices + 1 &&
           b.nonmanifold_edges == a.nonmanifold_edges && b.components == a.components;
  }

  /// An outer hole with an island inside touching it at one vertex: the island is the one-ring
  /// of the site; the faces around the island are removed except those at one rim vertex n0
  /// that share no edge with the island, so the outer rim passes through n0 too.
  bool island(TriangleSoup& s, int site) const {
    const Topology topo(s);
    if (ordered_fan(s, topo, site).size() < 5) return false;
    const std::unordered_set<int> island(topo.vf[site].begin(), topo.vf[site].end());
    const std::unordered_set<int> ring(topo.vv[site].begin(), topo.vv[site].end());
    std::unordered_set<std::uint64_t> island_edges;
    for (int f : island)
      for (int k = 0; k < 3; ++k) island_edges.insert(edge_key(s.faces[f][k], s.faces[f][(k + 1) % 3]));
    auto keepable = [&](int f, int n0) {  // (a face at n0) keeps the outer rim through n0
      if (island.count(f)) return false;
      for (int k = 0; k < 3; ++k) {
        const int v = s.faces[f][k];
        if (v != n0 && ring.count(v)) return false;
        if (island_edges.count(edge_key(v, s.faces[f][(k + 1) % 3]))) return false;
      }
      return true;
    };
    int n0 = -1;
    std::size_t most = 0;
    for (int r : topo.vv[site]) {
      std::size_t c = 0;
      for (int f : topo.vf[r]) c += keepable(f, r);
      if (c > most) most = c, n0 = r;
    }
    if (n0 < 0) return false;
    std::vector<int> removed;
    for (int r : topo.vv[site])
      for (int f : topo.vf[r])
        if (!island.count(f) && !keepable(f, n0)) removed.push_back(f);
    remove_faces(s, removed);
    return true;
  }

  bool flip_patch(TriangleSoup& s, int site, std::size_t* flipped) const {
    const Topology topo(s);
    const auto faces = disc_faces(s, topo, site, 2.5 * edge_);
    if (faces.size() < 4) return false;
    for (int f : faces) std::swap(s.faces[f][1], s.faces[f][2]);
    *flipped = faces.size();
    return true;
  }

  /// Pushes the geodesic patch around the site inwards, through the opposite wall.
  bool push_through(TriangleSoup& s, int site) const {
    const Topology topo(s);
    const double r = 3 * edge_;
    const auto ball = geodesic_ball(s, topo, site, r);
    const Vector3d n = vertex_normal(s, topo, site);
    std::unordered_set<int> skip;
    for (const auto& [v, d] : ball) skip.insert(v);
    const double h = ray_hit(s, s.vertices[site], -n, skip);
    const double depth = h > 0 ? h + 1.5 * edge_ : 0.25 * diag_;
    for (const auto& [v, d] : ball) {
      const double w = 1 - (d / r) * (d / r);
      s.vertices[v] -= n * depth * w * w;
    }
    return true;
  }

  void duplicate_faces(TriangleSoup& s, std::size_t count, CorpusRng& rng) const {
    const std::size_t n = s.faces.size();
    std::unordered_set<std::size_t> chosen;
    while (chosen.size() < count) {
      const std::size_t f = rng.index(n);
      if (chosen.insert(f).second) s.faces.push_back(s.faces[f]);
    }
  }

  /// A tiny triangle floating 2 edge lengths off the surface at the site, where nothing is
  /// within 4 edge lengths in front of the surface (so it cannot touch another wall).
  bool loose_triangle(TriangleSoup& s, int site) const {
    const Topology topo(s);
    if (topo.vf[site].empty()) return false;
    const Vector3d n = vertex_normal(s, topo, site);
    const double hit = ray_hit(s, s.vertices[site], n, {site});
    if (hit > 0 && hit < 4 * edge_) return false;
    const Vector3d c = s.vertices[site] + 2 * edge_ * n;
    const Vector3d u = n.unitOrthogonal() * 0.2 * edge_, w = n.cross(u);
    const int b = static_cast<int>(s.vertices.size());
    s.vertices.push_back(c + u);
    s.vertices.push_back(c + w * std::sqrt(3.0) / 2 - u / 2);
    s.vertices.push_back(c - w * std::sqrt(3.0) / 2 - u / 2);
    s.faces.push_back({b, b + 1, b + 2});
    return true;
  }

  /// Cuts the soup along the gap plane (faces crossing it are split) and moves the positive
  /// side `options_.gap` along the plane normal, on its own copies of the cut vertices.
  void cut_gap(TriangleSoup& s) const {
    const Vector3d n = gap_plane_.n;
    std::vector<double> d(s.vertices.size());
    for (std::size_t v = 0; v < s.vertices.size(); ++v) d[v] = (s.vertices[v] - gap_plane_.o).dot(n);
    std::unordered_map<std::uint64_t, std::pair<int, int>> cut;  // edge -> (negative copy, positive copy)
    auto cut_vertex = [&](int a, int b, bool positive) {
      auto [it, inserted] = cut.emplace(edge_key(a, b), std::make_pair(0, 0));
      if (inserted) {
        const double t = d[a] / (d[a] - d[b]);
        const Vector3d p = s.vertices[a] + t * (s.vertices[b] - s.vertices[a]);
        it->second.first = static_cast<int>(s.vertices.size());
        s.vertices.push_back(p);
        it->second.second = static_cast<int>(s.vertices.size());
        s.vertices.push_back(p + options_.gap * n);
      }
      return positive ? it->second.second : it->second.first;
    };
    std::vector<Tri> out;
    const std::size_t nf = s.faces.size();
    for (std::size_t f = 0; f < nf; ++f) {
      const Tri t = s.faces[f];
      const int pos = (d[t[0]] > 0) + (d[t[1]] > 0) + (d[t[2]] > 0);
      if (pos == 0 || pos == 3) {
        out.push_back(t);
        continue;
      }
      // The corner alone on its side comes first: (a, b, c) with a alone.
      int k = 0;
      while (((d[t[k]] > 0) ? 1 : 0) != (pos == 1 ? 1 : 0)) ++k;
      const int a = t[k], b = t[(k + 1) % 3], c = t[(k + 2) % 3];
      const bool a_pos = d[a] > 0;
      out.push_back({a, cut_vertex(a, b, a_pos), cut_vertex(a, c, a_pos)});
      out.push_back({cut_vertex(a, b, !a_pos), b, c});
      out.push_back({cut_vertex(a, b, !a_pos), c, cut_vertex(a, c, !a_pos)});
    }
    s.faces = std::move(out);
    for (std::size_t v = 0; v < d.size(); ++v)
      if (d[v] > 0) s.vertices[v] += options_.gap * n;
  }


 private:
  TriangleSoup base_;
  const DefectOptions& options_;
  double edge_, diag_ = 0;
  CorpusRng rng_;
  Plane gap_plane_;
  std::vector<int> sites_;
};

}  // namespace

DefectCorpus make_defect_corpus(const TriangleSoup& clean, const DefectOptions& options) {
  const CheckResult input = check_mesh(clean, {false});
  if (!input.closed || input.nonmanifold_vertices != 0)
    throw InvalidInput("the clean mesh must be closed and manifold (" + std::to_string(input.boundary_edges) +
                       " boundary edges, " + std::to_string(input.nonmanifold_edges) + " non-manifold edges, " +
                       std::to_string(input.nonmanifold_vertices) + " non-manifold vertices)");
  DefectCorpus corpus;
  const double edge = options.edge_length > 0 ? options.edge_length : bounds(clean).diagonal() / 40;
  corpus.edge_length = edge;
  TriangleSoup base = refine(clean, edge, 2'000'000);
  compact(base);
  corpus.clean = base;
  Builder b(base, options, edge);

  auto need = [](bool ok, const char* what) {
    if (!ok) throw InvalidInput(std::string("could not place ") + what + " on this mesh");
  };
  auto holes = [&](DefectVariant& v, std::vector<std::pair<int, double>>& used, std::size_t n) {
    for (std::size_t i = 0; i < n; ++i)
      need(b.place(v, used, 2.5, [&](TriangleSoup& s, int site) { return b.hole(s, site); }, Builder::is_one_more_hole), "a hole");
    v.defects["holes"] += n;
  };
  auto nested = [&](DefectVariant& v, std::vector<std::pair<int, double>>& used) {
    need(b.place(v, used, 2.5, [&](TriangleSoup& s, int site) { return b.touching_discs(s, site); },
                 Builder::is_one_more_nested),
         "two touching holes");
    need(b.place(v, used, 2.5, [&](TriangleSoup& s, int site) { return b.island(s, site); }, Builder::is_one_more_nested),
         "a hole with an island");
    v.defects["nested_holes"] += 2;
    v.defects["touching_hole_pairs"] += 1;
    v.defects["islands"] += 1;
  };
  auto flipped = [&](DefectVariant& v, std::vector<std::pair<int, double>>& used) {
    std::size_t count = 0;
    need(b.place(v, used, 2.5, [&](TriangleSoup& s, int site) { return b.flip_patch(s, site, &count); },
                 [](const CheckResult& x, const CheckResult& y) {
                   return y.orientation_conflicts > x.orientation_conflicts && y.boundary_loops == x.boundary_loops &&
                          y.nonmanifold_vertices == x.nonmanifold_vertices;
                 }),
         "a flipped patch");
    v.defects["flipped_faces"] += count;
  };
  auto pushed = [&](DefectVariant& v, std::vector<std::pair<int, double>>& used) {
    need(b.place(v, used, 3, [&](TriangleSoup& s, int site) { return b.push_through(s, site); },
                 [](const CheckResult& x, const CheckResult& y) {
                   return y.self_intersections > x.self_intersections && y.degenerate_faces == x.degenerate_faces;
                 },
                 true),
         "a self-intersecting patch");
    v.defects["self_intersecting_patches"] += 1;
  };
  CorpusRng dup_rng(options.seed ^ 0xD1B54A32D192ED03ull);
  auto duplicates = [&](DefectVariant& v) {
    b.duplicate_faces(v.soup, 5, dup_rng);
    v.defects["duplicate_faces"] += 5;
  };
  auto loose = [&](DefectVariant& v, std::vector<std::pair<int, double>>& used) {
    for (int i = 0; i < 3; ++i)
      need(b.place(v, used, 1, [&](TriangleSoup& s, int site) { return b.loose_triangle(s, site); },
                   [](const CheckResult& x, const CheckResult& y) { return y.components == x.components + 1; }),
           "a loose triangle");
    v.defects["loose_components"] += 3;
  };
  auto gap = [&](DefectVariant& v) {
    b.cut_gap(v.soup);
    v.defects["gaps"] += 1;
  };

  auto variant = [&](const std::string& name, const std::function<void(DefectVariant&, std::vector<std::pair<int, double>>&)>& make) {
    DefectVariant v;
    v.name = name;
    v.soup = b.base();
    std::vector<std::pair<int, double>> used;
    try {
      make(v, used);
    } catch (const InvalidInput& e) {
      throw InvalidInput(name + ".ply: " + e.what());
    }
    compact(v.soup);
    v.check = check_mesh(v.soup);
    corpus.variants.push_back(std::move(v));
  };
  variant("holes", [&](DefectVariant& v, std::vector<std::pair<int, double>>& used) { holes(v, used, 2); });
  variant("nested", [&](DefectVariant& v, std::vector<std::pair<int, double>>& used) { nested(v, used); });
  variant("flipped", [&](DefectVariant& v, std::vector<std::pair<int, double>>& used) { flipped(v, used); });
  variant("duplicates", [&](DefectVariant& v, std::vector<std::pair<int, double>>&) { duplicates(v); });
  variant("gap", [&](DefectVariant& v, std::vector<std::pair<int, double>>&) { gap(v); });
  variant("self_intersections", [&](DefectVariant& v, std::vector<std::pair<int, double>>& used) { pushed(v, used); });
  variant("loose", [&](DefectVariant& v, std::vector<std::pair<int, double>>& used) { loose(v, used); });
  variant("everything", [&](DefectVariant& v, std::vector<std::pair<int, double>>& used) {
    // The gap first (sites keep away from its plane), duplicates last (they add non-manifold
    // edges that would confuse the checks of the later placements).
    gap(v);
    holes(v, used, 2);
    nested(v, used);
    flipped(v, used);
    pushed(v, used);
    loose(v, used);
    duplicates(v);
  });
  return corpus;
}

void write_soup_ply(const TriangleSoup& soup, const std::filesystem::path& path) {
  AtomicFile out(path);
  {
    std::ofstream f(out.temp_path(), std::ios::binary);
    if (!f) throw IoError(path.string() + ": cannot open for writing");
    f << "ply\nformat binary_little_endian 1.0\ncomment scan2cad defect corpus, mm\nelement vertex "
      << soup.vertices.size() << "\nproperty double x\nproperty double y\nproperty double z\nelement face "
      << soup.faces.size() << "\nproperty list uchar int vertex_indices\nend_header\n";
    static_assert(sizeof(double) == 8 && sizeof(int) == 4, "PLY layout");
    for (const auto& p : soup.vertices) {
      const double xyz[3] = {p.x(), p.y(), p.z()};
      f.write(reinterpret_cast<const char*>(xyz), sizeof xyz);
    }
    for (const auto& t : soup.faces) {
      const unsigned char three = 3;
      f.write(reinterpret_cast<const char*>(&three), 1);
      f.write(reinterpret_cast<const char*>(t.data()), 3 * sizeof(int));
    }
    if (!f.flush()) throw IoError(path.string() + ": writing failed (disk full?)");
  }
  out.commit();
}

}  // namespace s2c::bench
