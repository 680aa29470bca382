// Patch validation: topology first (cheap, and the geometric test assumes it), then exact
// intersection tests with a sort-and-sweep broad phase.
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
  // Filter: a projection's determinant far above its rounding error (Shewchuk's bound is
  // 3.3e-16 relative; 1e-14 here, and products clear of underflow) is nonzero for sure.
  for (const auto& [x, y] : {std::pair{0, 1}, std::pair{1, 2}, std::pair{2, 0}}) {
    const double l = (a[x] - c[x]) * (b[y] - c[y]), r = (a[y] - c[y]) * (b[x] - c[x]);
    const double scale = std::abs(l) + std::abs(r);
    if (scale > 1e-280 && std::abs(l - r) > 1e-14 * scale) return false;
  }
  const auto proj = [](const Eigen::Vector3d& p, int x, int y) { return Eigen::Vector2d(p[x], p[y]); };
  for (const auto& [x, y] : {std::pair{0, 1}, std::pair{1, 2}, std::pair{2, 0}})
    if (orient2d(proj(a, x, y), proj(b, x, y), proj(c, x, y)) != 0) return false;
  return true;
}


}  // namespace

int fans_at(int v, const std::vector<std::array<int, 3>>& faces, DisjointSets& fans) {
  fans.parent.resize(faces.size());  // reused: this runs for every vertex a patch touches
  std::iota(fans.parent.begin(), fans.parent.end(), 0);
  // (other corner of an edge at v, a face holding it), sorted: faces sharing an edge at v meet.
  thread_local std::vector<std::pair<int, int>> by_other;
  by_other.clear();
  for (int f = 0; f < static_cast<int>(faces.size()); ++f)
    for (int c : faces[f])
      if (c != v) by_other.emplace_back(c, f);
  std::sort(by_other.begin(), by_other.end());
  for (std::size_t i = 1; i < by_other.size(); ++i)
    if (by_other[i].first == by_other[i - 1].first) fans.unite(by_other[i].second, by_other[i - 1].second);
  int roots = 0;
  for (int f = 0; f < static_cast<int>(faces.size()); ++f) roots += fans.find(f) == f;
  return roots;
}

namespace {

// rim_only: the patch was checked before against an earlier state of the soup. Only what
// touches existing vertices can have changed since (edges and fans at the rim); the new
// vertices and their edges are the patch's own.
std::string check_topology(const TriangleSoup& soup, const MeshIndex& index, const Patch& p, bool rim_only) {
  const int n = p.rim_size();
  // Patch edges by soup index, directed and undirected, as sorted key lists (no hashing: a
  // patch has a few hundred edges). The directed ones and the disc test below are the patch's
  // own properties: not repeated in a rim_only re-check.
  std::vector<std::uint64_t> directed, undirected;
  undirected.reserve(3 * p.faces.size());
  if (!rim_only) directed.reserve(3 * p.faces.size());
  for (const auto& t : p.faces)
    for (int k = 0; k < 3; ++k) {
      const int a = p.global(t[k]), b = p.global(t[(k + 1) % 3]);
      if (!rim_only) directed.push_back(directed_key(a, b));
      undirected.push_back(edge_key(a, b));
    }
  std::sort(directed.begin(), directed.end());
  if (std::adjacent_find(directed.begin(), directed.end()) != directed.end())
    return "patch uses an edge twice in the same direction";
  std::vector<std::uint64_t> rim_edges;
  for (int i = 0; i < n; ++i) {
    const int a = p.rim[i], b = p.rim[(i + 1) % n];
    if (!rim_only && !std::binary_search(directed.begin(), directed.end(), directed_key(a, b)))
      return "patch does not close the rim edge " + std::to_string(a) + "-" + std::to_string(b);
    rim_edges.push_back(edge_key(a, b));
  }
  std::sort(rim_edges.begin(), rim_edges.end());
  std::sort(undirected.begin(), undirected.end());
  long long distinct_edges = 0;
  for (std::size_t i = 0; i < undirected.size();) {
    std::size_t j = i;
    while (j < undirected.size() && undirected[j] == undirected[i]) ++j;
    const std::uint64_t key = undirected[i];
    const long long count = static_cast<long long>(j - i);
    i = j;
    ++distinct_edges;
    const int a = int(key >> 32), b = int(key & 0xffffffffu);
    if (rim_only && (a >= p.base || b >= p.base)) continue;
    const int mesh = index.edge_faces(a, b);
    if (std::binary_search(rim_edges.begin(), rim_edges.end(), key)) {
      if (count != 1 || mesh != 1) return "rim edge would not be manifold after filling";
    } else if (count != 2 || mesh != 0) {
      return "patch edge " + std::to_string(a) + "-" + std::to_string(b) + " would not be manifold";
    }
  }
  if (!rim_only) {  // Disc: V - E + F = 1 counting loop positions as corners.
    const long long V = p.size(), E = distinct_edges, F = static_cast<long long>(p.faces.size());
    long long positions_extra = 0;  // a repeated rim vertex is one soup vertex but two corners
    std::unordered_set<int> seen;
    for (int g : p.rim) positions_extra += !seen.insert(g).second;
    if (V - E + F != 1 && V - positions_extra - E + F != 1) return "patch is not a disc";
  }
  // Fans (edge-connected faces) around every touched vertex. A vertex must end with one fan,
  // except a rim vertex that already had several (a pinch that no patch can undo, e.g. a closed
  // cone of faces touching the rim's fan at one vertex, or a nested loop split into two): it may
  // keep them as long as each patch face there joins a fan of mesh faces (no fan of patch faces
  // only) and no fan is lost or added, i.e. after ≤ before.
  std::vector<std::array<int, 3>> global(p.faces.size());
  std::vector<std::pair<int, int>> incidence;  // (vertex, patch face), sorted: one group per vertex
  incidence.reserve(3 * p.faces.size());
  for (std::size_t f = 0; f < p.faces.size(); ++f) {
    const auto& t = p.faces[f];
    global[f] = {p.global(t[0]), p.global(t[1]), p.global(t[2])};
    for (int c : global[f])
      if (!rim_only || c < p.base) incidence.emplace_back(c, static_cast<int>(f));
  }
  std::sort(incidence.begin(), incidence.end());
  DisjointSets parent;
  std::vector<std::array<int, 3>> faces;
  for (std::size_t i = 0; i < incidence.size();) {
    const int v = incidence[i].first;
    faces.clear();
    for (; i < incidence.size() && incidence[i].first == v; ++i) faces.push_back(global[static_cast<std::size_t>(incidence[i].second)]);
    const std::size_t patch_faces = faces.size();
    if (v < p.base) index.for_each_face_of(v, [&](int f) { faces.push_back(soup.faces[static_cast<std::size_t>(f)]); });
    const int after = fans_at(v, faces, parent);
    if (after == 1) continue;
    const std::vector<std::array<int, 3>> mesh(faces.begin() + static_cast<std::ptrdiff_t>(patch_faces), faces.end());
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

// Whether a face from `first` on uses a rim vertex of `p`. A re-check's topology (rim_only) only
// reads edges and fans at rim vertices: faces appended away from the rim cannot change it.
bool appended_faces_touch_rim(const TriangleSoup& soup, const Patch& p, std::size_t first) {
  std::vector<int> rim(p.rim);
  std::sort(rim.begin(), rim.end());
  for (std::size_t f = first; f < soup.faces.size(); ++f)
    for (int c : soup.faces[f])
      if (std::binary_search(rim.begin(), rim.end(), c)) return true;
  return false;
}

}  // namespace

bool patch_embeds_by_projection(const Patch& p) {
  const int n = p.rim_size();
  if (n < 3 || n > 256 || p.faces.empty()) return false;
  // The boundary: every directed patch edge is matched by its reverse or is a rim edge.
  std::vector<std::uint64_t> directed;
  directed.reserve(3 * p.faces.size());
  for (const auto& t : p.faces)
    for (int k = 0; k < 3; ++k) directed.push_back(directed_key(t[k], t[(k + 1) % 3]));
  std::sort(directed.begin(), directed.end());
  if (std::adjacent_find(directed.begin(), directed.end()) != directed.end()) return false;
  const auto has = [&](int a, int b) { return std::binary_search(directed.begin(), directed.end(), directed_key(a, b)); };
  int forward = 0, backward = 0;  // rim edges the patch holds as l → l+1, and as l+1 → l
  for (int l = 0; l < n; ++l) {
    const int m = (l + 1) % n;
    forward += has(l, m) && !has(m, l);
    backward += has(m, l) && !has(l, m);
  }
  if (!(forward == n || backward == n)) return false;
  std::size_t boundary = 0;
  for (const std::uint64_t e : directed) {
    const int a = static_cast<int>(e >> 32), b = static_cast<int>(e & 0xffffffffu);
    boundary += !has(b, a);
  }
  if (boundary != static_cast<std::size_t>(n)) return false;
  // Project along the axis where the patch's area vector is largest.
  Eigen::Vector3d area = Eigen::Vector3d::Zero();
  for (const auto& t : p.faces) area += (p.points[t[1]] - p.points[t[0]]).cross(p.points[t[2]] - p.points[t[0]]);
  int drop = 0;
  area.cwiseAbs().maxCoeff(&drop);
  const int u = (drop + 1) % 3, w = (drop + 2) % 3;
  const auto flat = [&](int l) { return Eigen::Vector2d(p.points[l][u], p.points[l][w]); };
  int sign = 0;
  for (const auto& t : p.faces) {
    const int o = orient2d(flat(t[0]), flat(t[1]), flat(t[2]));
    if (o == 0 || (sign != 0 && o != sign)) return false;
    sign = o;
  }
  // The rim polygon is simple: no two of its segments meet but consecutive ones at their common
  // end (and those not along one line). Boxes first, the exact test for the pairs left.
  std::vector<Eigen::Vector2d> q(static_cast<std::size_t>(n));
  for (int l = 0; l < n; ++l) q[l] = flat(l);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d &a = q[i], &b = q[(i + 1) % n];
    if (orient2d(q[(i + n - 1) % n], a, b) == 0) return false;  // consecutive segments along one line
    const Eigen::Vector2d lo = a.cwiseMin(b), hi = a.cwiseMax(b);
    for (int j = i + 2; j < n; ++j) {
      if (i == 0 && j == n - 1) continue;  // consecutive through the loop's end
      const Eigen::Vector2d &c = q[j], &d = q[(j + 1) % n];
      if ((c.cwiseMax(d).array() < lo.array()).any() || (c.cwiseMin(d).array() > hi.array()).any()) continue;
      if (segments_intersect_2d(a, b, c, d)) return false;
    }
  }
  return true;
}

namespace {

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

std::string check_patch(const TriangleSoup& soup, const MeshIndex& index, const Patch& p, const CheckScope& scope) {
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
    if (scope.patch_itself && collinear(tri[f][0], tri[f][1], tri[f][2])) return "degenerate patch triangle";
  }
  const bool topology = scope.patch_itself ? !p.topology_ok : appended_faces_touch_rim(soup, p, scope.mesh_faces_from);
  if (topology)
    if (auto why = check_topology(soup, index, p, !scope.patch_itself); !why.empty()) return why;

  std::vector<Box> boxes(tri.size());
  Box all{tri[0][0], tri[0][0]};
  for (std::size_t f = 0; f < tri.size(); ++f) {
    boxes[f] = box_of(tri[f]);
    all.lo = all.lo.cwiseMin(boxes[f].lo);
    all.hi = all.hi.cwiseMax(boxes[f].hi);
  }
  // Faces found early for a larger box serve as well: the loop below tests each face's box
  // against the patch's anyway, in the same (ascending) order.
  const bool early = scope.patch_itself && scope.mesh_faces_from == 0 && (p.near_lo.array() <= all.lo.array()).all() &&
                     (all.hi.array() <= p.near_hi.array()).all();
  std::vector<int> scanned;
  if (!early) index.faces_near(all.lo, all.hi, scanned, scope.mesh_faces_from);
  const std::vector<int>& near = early ? p.near_faces : scanned;
  if (!scope.patch_itself && near.empty()) return {};  // nothing new nearby
  // Broad phase: patch faces sorted by the low end of their boxes along the patch's longest
  // axis; a query box scans from the first face that can reach it (low end ≥ its low end − the
  // longest face box) to the last that starts before its high end. No allocation per cell.
  int axis = 0;
  (all.hi - all.lo).maxCoeff(&axis);
  std::vector<int> order(tri.size());
  double span = 0;
  for (int f = 0; f < static_cast<int>(tri.size()); ++f) {
    order[f] = f;
    span = std::max(span, boxes[f].hi[axis] - boxes[f].lo[axis]);
  }
  std::sort(order.begin(), order.end(), [&](int a, int b) { return boxes[a].lo[axis] < boxes[b].lo[axis]; });
  std::vector<double> low(tri.size());
  for (std::size_t k = 0; k < order.size(); ++k) low[k] = boxes[order[k]].lo[axis];
  // Tests `t` (ids `ti`, box `bt`) against the patch faces whose boxes overlap; `self` ≥ 0 only
  // tests higher patch faces (each pair once).
  const auto against_patch = [&](const std::array<Eigen::Vector3d, 3>& t, const std::array<int, 3>& ti,
                                 const Box& bt, int self) {
    for (auto k = static_cast<std::size_t>(std::lower_bound(low.begin(), low.end(), bt.lo[axis] - span) - low.begin());
         k < order.size() && low[k] <= bt.hi[axis]; ++k) {
      const int g = order[k];
      if (g <= self) continue;
      if (overlap(bt, boxes[g]) && faces_self_intersect(t, ti, tri[g], ids[g])) return g;
    }
    return -1;
  };
  if (scope.patch_itself && !patch_embeds_by_projection(p))
    for (int f = 0; f < static_cast<int>(tri.size()); ++f)
      if (against_patch(tri[f], ids[f], boxes[f], f) >= 0) return "patch intersects itself";
  for (const int f : near) {
    if (f < 0 || static_cast<std::size_t>(f) >= soup.faces.size()) continue;
    const auto& t = soup.faces[static_cast<std::size_t>(f)];
    const int nv = static_cast<int>(soup.vertices.size());
    if (std::min({t[0], t[1], t[2]}) < 0 || std::max({t[0], t[1], t[2]}) >= nv) continue;
    const std::array<Eigen::Vector3d, 3> q{soup.vertices[t[0]], soup.vertices[t[1]], soup.vertices[t[2]]};
    const Box bq = box_of(q);
    if (!overlap(bq, all)) continue;
    if (against_patch(q, t, bq, -1) >= 0) return "patch intersects the mesh near the hole (face " + std::to_string(f) + ")";
  }
  return {};
}

std::string check_patch_topology(const TriangleSoup& soup, const MeshIndex& index, const Patch& patch) {
  return check_topology(soup, index, patch, false);
}

}  // namespace s2c::repair::fill
