// Patch validation: topology first (cheap, and the geometric test assumes it), then exact
// intersection tests with a uniform-grid broad phase.
#include "fill/patch_check.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <unordered_map>
#include <unordered_set>

#include "s2c/core/predicates.h"

namespace s2c::repair::fill {
namespace {

// Exactly zero area: the three corners are collinear iff all three axis projections are.
bool collinear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const auto proj = [](const Eigen::Vector3d& p, int x, int y) { return Eigen::Vector2d(p[x], p[y]); };
  for (const auto& [x, y] : {std::pair{0, 1}, std::pair{1, 2}, std::pair{2, 0}})
    if (orient2d(proj(a, x, y), proj(b, x, y), proj(c, x, y)) != 0) return false;
  return true;
}


}  // namespace

int fans_at(int v, const std::vector<std::array<int, 3>>& faces, DisjointSets& fans) {
  fans = DisjointSets(faces.size());
  std::unordered_map<int, int> by_other;  // other corner of an edge at v → a face holding it
  for (int f = 0; f < static_cast<int>(faces.size()); ++f)
    for (int c : faces[f]) {
      if (c == v) continue;
      auto [it, inserted] = by_other.try_emplace(c, f);
      if (!inserted) fans.unite(f, it->second);
    }
  int roots = 0;
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) roots += fans.find(f) == f;
  return roots;
}

namespace {

std::string check_topology(const TriangleSoup& soup, const MeshIndex& index, const Patch& p) {
  const int n = p.rim_size();
  // Directed patch edges by soup index.
  std::unordered_map<std::uint64_t, int> directed, undirected;
  for (const auto& t : p.faces)
    for (int k = 0; k < 3; ++k) {
      const int a = p.global(t[k]), b = p.global(t[(k + 1) % 3]);
      ++directed[directed_key(a, b)];
      ++undirected[edge_key(a, b)];
    }
  for (const auto& [key, count] : directed)
    if (count > 1) return "patch uses an edge twice in the same direction";
  std::unordered_set<std::uint64_t> rim_edges;
  for (int i = 0; i < n; ++i) {
    const int a = p.rim[i], b = p.rim[(i + 1) % n];
    if (!directed.count(directed_key(a, b))) return "patch does not close the rim edge " + std::to_string(a) + "-" + std::to_string(b);
    rim_edges.insert(edge_key(a, b));
  }
  for (const auto& [key, count] : undirected) {
    const int a = int(key >> 32), b = int(key & 0xffffffffu);
    const int mesh = index.edge_faces(a, b);
    if (rim_edges.count(key)) {
      if (count != 1 || mesh != 1) return "rim edge would not be manifold after filling";
    } else if (count != 2 || mesh != 0) {
      return "patch edge " + std::to_string(a) + "-" + std::to_string(b) + " would not be manifold";
    }
  }
  // Disc: V - E + F = 1 counting loop positions as corners.
  const long long V = p.size(), E = static_cast<long long>(undirected.size()), F = static_cast<long long>(p.faces.size());
  long long positions_extra = 0;  // a repeated rim vertex is one soup vertex but two corners
  {
    std::unordered_set<int> seen;
    for (int g : p.rim) positions_extra += !seen.insert(g).second;
  }
  if (V - E + F != 1 && V - positions_extra - E + F != 1) return "patch is not a disc";
  // Fans (edge-connected faces) around every touched vertex. A vertex must end with one fan,
  // except a rim vertex that already had several (a pinch that no patch can undo, e.g. a closed
  // cone of faces touching the rim's fan at one vertex, or a nested loop split into two): it may
  // keep them as long as each patch face there joins a fan of mesh faces (no fan of patch faces
  // only) and no fan is lost or added, i.e. after ≤ before.
  std::unordered_map<int, std::vector<std::array<int, 3>>> fans;
  for (const auto& t : p.faces) {
    const std::array<int, 3> g{p.global(t[0]), p.global(t[1]), p.global(t[2])};
    for (int c : g) fans[c].push_back(g);
  }
  DisjointSets parent;
  for (auto& [v, faces] : fans) {
    const std::size_t patch_faces = faces.size();
    std::vector<std::array<int, 3>> mesh;
    if (v < p.base)
      for (int f : index.faces_of(v)) mesh.push_back(soup.faces[f]);
    faces.insert(faces.end(), mesh.begin(), mesh.end());
    const int after = fans_at(v, faces, parent);
    if (after == 1) continue;
    DisjointSets mesh_parent;
    const int before = mesh.empty() ? 0 : fans_at(v, mesh, mesh_parent);
    bool attached = before > 1 && after <= before;
    if (attached) {
      std::unordered_set<int> with_mesh;
      for (std::size_t f = patch_faces; f < faces.size(); ++f) with_mesh.insert(parent.find(static_cast<int>(f)));
      for (std::size_t f = 0; f < patch_faces && attached; ++f) attached = with_mesh.count(parent.find(static_cast<int>(f))) > 0;
    }
    if (!attached) return "vertex " + std::to_string(v) + " would be non-manifold";
  }
  return {};
}

struct Box {
  Eigen::Vector3d lo, hi;
};
Box box_of(const std::array<Eigen::Vector3d, 3>& t) {
  return {t[0].cwiseMin(t[1]).cwiseMin(t[2]), t[0].cwiseMax(t[1]).cwiseMax(t[2])};
}
bool overlap(const Box& a, const Box& b) {
  return (a.lo.array() <= b.hi.array()).all() && (b.lo.array() <= a.hi.array()).all();
}

}  // namespace

std::string check_patch(const TriangleSoup& soup, const MeshIndex& index, const Patch& p) {
  for (const auto& q : p.points)
    if (!q.allFinite()) return "patch has non-finite coordinates";
  if (p.faces.empty()) return "empty patch";
  std::vector<std::array<Eigen::Vector3d, 3>> tri(p.faces.size());
  std::vector<std::array<int, 3>> ids(p.faces.size());
  for (std::size_t f = 0; f < p.faces.size(); ++f) {
    const auto& t = p.faces[f];
    tri[f] = {p.points[t[0]], p.points[t[1]], p.points[t[2]]};
    ids[f] = {p.global(t[0]), p.global(t[1]), p.global(t[2])};
    if (ids[f][0] == ids[f][1] || ids[f][1] == ids[f][2] || ids[f][0] == ids[f][2])
      return "patch triangle with a repeated vertex";
    if (collinear(tri[f][0], tri[f][1], tri[f][2])) return "degenerate patch triangle";
  }
  if (auto why = check_topology(soup, index, p); !why.empty()) return why;

  // Broad phase: patch faces in a uniform grid of about the patch's mean edge length.
  Box all{tri[0][0], tri[0][0]};
  double edge_sum = 0;
  for (const auto& t : tri) {
    const Box b = box_of(t);
    all.lo = all.lo.cwiseMin(b.lo);
    all.hi = all.hi.cwiseMax(b.hi);
    edge_sum += (t[1] - t[0]).norm();
  }
  const double extent = (all.hi - all.lo).maxCoeff();
  double cell = std::max(2.0 * edge_sum / static_cast<double>(tri.size()), extent / 512.0);
  if (!(cell > 0)) cell = 1;
  const auto cell_of = [&](const Eigen::Vector3d& x) {
    return Eigen::Vector3i(((x - all.lo) / cell).array().floor().cast<int>().cwiseMax(-1).cwiseMin(1 << 20));
  };
  const auto key = [](int x, int y, int z) {
    return (std::uint64_t(std::uint32_t(x + 2)) << 42) ^ (std::uint64_t(std::uint32_t(y + 2)) << 21) ^ std::uint32_t(z + 2);
  };
  std::unordered_map<std::uint64_t, std::vector<int>> grid;
  std::vector<Box> boxes(tri.size());
  for (int f = 0; f < static_cast<int>(tri.size()); ++f) {
    boxes[f] = box_of(tri[f]);
    const Eigen::Vector3i a = cell_of(boxes[f].lo), b = cell_of(boxes[f].hi);
    for (int x = a.x(); x <= b.x(); ++x)
      for (int y = a.y(); y <= b.y(); ++y)
        for (int z = a.z(); z <= b.z(); ++z) grid[key(x, y, z)].push_back(f);
  }
  std::vector<int> stamp(tri.size(), -1);
  // Tests `t` (ids `ti`, box `bt`) against the patch faces sharing a cell; `self` ≥ 0 only tests
  // higher patch faces (each pair once).
  const auto against_patch = [&](const std::array<Eigen::Vector3d, 3>& t, const std::array<int, 3>& ti,
                                 const Box& bt, int self, int tag) {
    const Eigen::Vector3i a = cell_of(bt.lo), b = cell_of(bt.hi);
    for (int x = a.x(); x <= b.x(); ++x)
      for (int y = a.y(); y <= b.y(); ++y)
        for (int z = a.z(); z <= b.z(); ++z) {
          const auto it = grid.find(key(x, y, z));
          if (it == grid.end()) continue;
          for (int g : it->second) {
            if (g <= self || stamp[g] == tag) continue;
            stamp[g] = tag;
            if (overlap(bt, boxes[g]) && faces_self_intersect(t, ti, tri[g], ids[g])) return g;
          }
        }
    return -1;
  };
  for (int f = 0; f < static_cast<int>(tri.size()); ++f)
    if (against_patch(tri[f], ids[f], boxes[f], f, f) >= 0) return "patch intersects itself";
  int tag = static_cast<int>(tri.size());
  std::vector<int> near;
  index.faces_near(all.lo, all.hi, near);
  for (const int f : near) {
    if (f < 0 || static_cast<std::size_t>(f) >= soup.faces.size()) continue;
    const auto& t = soup.faces[static_cast<std::size_t>(f)];
    const int nv = static_cast<int>(soup.vertices.size());
    if (std::min({t[0], t[1], t[2]}) < 0 || std::max({t[0], t[1], t[2]}) >= nv) continue;
    const std::array<Eigen::Vector3d, 3> q{soup.vertices[t[0]], soup.vertices[t[1]], soup.vertices[t[2]]};
    const Box bq = box_of(q);
    if (!overlap(bq, all)) continue;
    if (against_patch(q, t, bq, -1, tag++) >= 0) return "patch intersects the mesh near the hole (face " + std::to_string(f) + ")";
  }
  return {};
}

}  // namespace s2c::repair::fill
