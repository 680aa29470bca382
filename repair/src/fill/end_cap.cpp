// trim_end_caps: the part's unseen end face, cut flush with its plane (see s2c/repair/fill.h).
#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <unordered_map>
#include <unordered_set>

#include "fill/patch.h"
#include "fill/rim_surfaces.h"
#include "s2c/core/disjoint_sets.h"
#include "s2c/repair/fill.h"
#include "soup_topology.h"

namespace s2c::repair {
namespace {

using fill::HoleShape;
using fill::MeshIndex;

// Where the cut goes: the plane through `point` with unit normal `inward` (towards the mesh);
// everything of the band between the rim and the plane is cut off.
struct Cut {
  Eigen::Vector3d point, inward;
  double snap = 0;  // vertices this close to the plane are moved onto it
  double depth = 0;
};

bool simple_loop(const std::vector<int>& loop) {
  std::vector<int> sorted = loop;
  std::sort(sorted.begin(), sorted.end());
  return std::adjacent_find(sorted.begin(), sorted.end()) == sorted.end();
}

// The surface around the rim keeps its angle θ to the rim plane over a band of 5–25 % of the
// hole's radius: a least-squares line θ(d) in the distance d from the rim turns by less than a
// quarter of θ over the radius. The band skips the rim's first rings, which a reconstruction
// rounds towards the missing face.
bool straight_walls(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& loop, const HoleShape& s) {
  const double radius = 0.5 * s.diameter, lo = 0.05 * radius, hi = 0.25 * radius;
  // Distance to the rim, looked up in a grid of rim vertices with cells of size `hi` (only
  // distances up to `hi` matter): a few cells instead of the whole rim per vertex.
  const auto cell_of = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector3i((p / hi).array().floor().max(-1e9).min(1e9).cast<int>());  // (no overflowing cast)
  };
  const auto key = [](const Eigen::Vector3i& c) {
    return (std::uint64_t(std::uint32_t(c.x()) & 0x1fffff) << 42) | (std::uint64_t(std::uint32_t(c.y()) & 0x1fffff) << 21) |
           (std::uint64_t(std::uint32_t(c.z()) & 0x1fffff));
  };
  std::unordered_map<std::uint64_t, std::vector<int>> grid;
  for (int g : loop) grid[key(cell_of(soup.vertices[g]))].push_back(g);
  const auto rim_distance = [&](const Eigen::Vector3d& p) {
    double best = std::numeric_limits<double>::infinity();
    if (!p.allFinite()) return best;
    const Eigen::Vector3i c = cell_of(p);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          const auto it = grid.find(key(c + Eigen::Vector3i(dx, dy, dz)));
          if (it == grid.end()) continue;
          for (int g : it->second) best = std::min(best, (soup.vertices[g] - p).squaredNorm());
        }
    return std::sqrt(best);
  };
  const std::unordered_map<int, Eigen::Vector3d> unmoved;
  const fill::Position at{soup.vertices, unmoved};
  std::unordered_set<int> seen(loop.begin(), loop.end());
  std::vector<int> frontier(loop), next;
  double n = 0, sd = 0, st = 0, sdd = 0, sdt = 0;  // sums for the line θ(d)
  while (!frontier.empty()) {
    next.clear();
    for (int v : frontier)
      index.for_each_face_of(v, [&](int f) {
        for (int u : soup.faces[static_cast<std::size_t>(f)]) {
          if (!seen.insert(u).second) continue;
          const double d = rim_distance(soup.vertices[u]);
          if (!(d <= hi)) continue;
          next.push_back(u);
          if (d < lo) continue;
          const Eigen::Vector3d normal = fill::area_normal(soup, index, u, at);
          if (normal.squaredNorm() == 0) continue;
          const double theta = std::acos(std::min(1.0, std::abs(normal.dot(s.normal))));
          n += 1, sd += d, st += theta, sdd += d * d, sdt += d * theta;
        }
      });
    frontier.swap(next);
  }
  if (n < 10) return false;
  const double var = sdd - sd * sd / n;
  if (!(var > 0)) return false;
  const double slope = (sdt - sd * st / n) / var, mean_theta = st / n;
  return std::abs(slope) * radius < 0.25 * mean_theta;
}

// The cut for `hole` when it is an end cap (see trim_end_caps), nothing otherwise.
std::optional<Cut> end_cap_cut(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& referenced,
                               const Hole& hole, const FillOptions& options) {
  const auto& loop = hole.loop;
  if (hole.origin != Hole::Origin::single || loop.size() < 12 || !simple_loop(loop)) return std::nullopt;
  if (options.max_hole_vertices && loop.size() > options.max_hole_vertices) return std::nullopt;  // left open anyway
  for (int g : loop)
    if (g < 0 || static_cast<std::size_t>(g) >= soup.vertices.size() || !soup.vertices[g].allFinite())
      return std::nullopt;
  const HoleShape s = fill::analyse_rim(soup, index, loop, 0, options.planar_tolerance);
  // Flat ground (faces within 10° of the plane) is filled flat anyway; nothing to trim there.
  if (!(s.diameter > 0) || s.planarity > options.end_cap_tolerance || s.wall_angle_deg < 10) return std::nullopt;
  // The local test first: the global one below scans the whole mesh.
  if (!straight_walls(soup, index, loop, s)) return std::nullopt;
  // The whole mesh on one side of the plane (beyond it by no more than the rim's own spread).
  const double spread = s.planarity * s.diameter + 1e-9 * s.diameter;
  double low = 0, high = 0;
  for (int v : referenced) {
    const auto& p = soup.vertices[static_cast<std::size_t>(v)];
    if (!p.allFinite()) continue;
    const double h = (p - s.centroid).dot(s.normal);
    low = std::min(low, h), high = std::max(high, h);
    if (low < -spread && high > spread) return std::nullopt;
  }
  if (low >= -spread && high <= spread) return std::nullopt;  // a flat mesh: no side
  Cut cut;
  cut.inward = low < -spread ? Eigen::Vector3d(-s.normal) : s.normal;
  double lowest = std::numeric_limits<double>::infinity(), highest = -lowest;
  for (int g : loop) {
    const double d = (soup.vertices[g] - s.centroid).dot(cut.inward);
    lowest = std::min(lowest, d), highest = std::max(highest, d);
  }
  cut.point = s.centroid + highest * cut.inward;
  cut.depth = highest - lowest;
  cut.snap = 0.01 * s.edge;
  return cut;
}

// Bumps of a jagged rim that rose above the plane come loose from the part when the band around
// them is cut off: every edge-connected piece that touches the plane and stays within the
// band's height is removed.
void remove_debris(TriangleSoup& soup, const std::vector<int>& on_plane, const Cut& cut, EndCapTrim& trim) {
  const std::size_t nf = soup.faces.size();
  DisjointSets pieces(nf);
  for (const auto& [key, faces] : EdgeFaces(soup))
    for (std::size_t i = 1; i < faces.size(); ++i) pieces.unite(faces[i], faces[0]);
  std::vector<double> top(nf, -std::numeric_limits<double>::infinity());
  std::vector<char> touches(nf, 0);
  for (std::size_t f = 0; f < nf; ++f) {
    const int root = pieces.find(static_cast<int>(f));
    for (int v : soup.faces[f]) {
      top[root] = std::max(top[root], (soup.vertices[static_cast<std::size_t>(v)] - cut.point).dot(cut.inward));
      touches[root] |= std::binary_search(on_plane.begin(), on_plane.end(), v);
    }
  }
  std::size_t w = 0;
  for (std::size_t f = 0; f < nf; ++f) {
    const int root = pieces.find(static_cast<int>(f));
    if (touches[root] && top[root] <= cut.depth) {
      ++trim.faces_removed;
      continue;
    }
    soup.faces[w++] = soup.faces[f];
  }
  soup.faces.resize(w);
}

// Cuts the band between the rim and the plane off; returns the plane's vertices (snapped and
// new), or nothing (the soup untouched) when a corner there is not finite.
std::vector<int> apply_cut(TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& loop, const Cut& cut,
                           EndCapTrim& trim) {
  const auto height = [&](int v) { return (soup.vertices[static_cast<std::size_t>(v)] - cut.point).dot(cut.inward); };
  const auto below = [&](int v) { return height(v) < -cut.snap; };
  // The band: vertices below the plane reachable from the rim through vertices below it.
  std::unordered_set<int> band;
  std::vector<int> frontier;
  for (int g : loop) {
    if (below(g)) band.insert(g);
    frontier.push_back(g);
  }
  while (!frontier.empty()) {
    const int v = frontier.back();
    frontier.pop_back();
    index.for_each_face_of(v, [&](int f) {
      for (int u : soup.faces[static_cast<std::size_t>(f)])
        if (below(u) && band.insert(u).second) frontier.push_back(u);
    });
  }
  std::vector<int> faces;
  for (int v : band) index.for_each_face_of(v, [&](int f) { faces.push_back(f); });
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  // Snap: every corner of those faces and every rim vertex within `snap` of the plane, once.
  std::vector<int> corners(loop);
  for (int f : faces)
    for (int v : soup.faces[static_cast<std::size_t>(f)]) corners.push_back(v);
  std::sort(corners.begin(), corners.end());
  corners.erase(std::unique(corners.begin(), corners.end()), corners.end());
  for (int v : corners)
    if (!soup.vertices[static_cast<std::size_t>(v)].allFinite()) return {};  // no cut through that
  std::vector<int> on_plane;
  for (int v : corners) {
    const double h = height(v);
    if (!(std::abs(h) <= cut.snap)) continue;
    if (h != 0) soup.vertices[static_cast<std::size_t>(v)] -= h * cut.inward, ++trim.vertices_snapped;
    on_plane.push_back(v);
  }
  // Clip: each face keeps the polygon of its corners on or above the plane and the crossings of
  // its edges (one new vertex per crossed edge, shared by both faces).
  const bool normals = soup.normals.size() == soup.vertices.size();
  std::unordered_map<std::uint64_t, int> crossing;
  const auto cross = [&](int a, int b) {
    const auto [it, fresh] = crossing.try_emplace(undirected_edge_key(a, b), 0);
    if (!fresh) return it->second;
    const double ha = height(a), hb = height(b), t = ha / (ha - hb);
    const auto &pa = soup.vertices[static_cast<std::size_t>(a)], &pb = soup.vertices[static_cast<std::size_t>(b)];
    Eigen::Vector3d p = pa + t * (pb - pa);
    p -= (p - cut.point).dot(cut.inward) * cut.inward;  // exactly in the plane
    it->second = static_cast<int>(soup.vertices.size());
    soup.vertices.push_back(p);
    if (normals) {
      const Eigen::Vector3d n = (1 - t) * soup.normals[static_cast<std::size_t>(a)] + t * soup.normals[static_cast<std::size_t>(b)];
      soup.normals.push_back(n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : n);
    }
    on_plane.push_back(it->second);
    return it->second;
  };
  // Snapped vertices are exactly on the plane (their rounding must not put them on a side).
  const auto level = [&](int v) {
    const double h = height(v);
    return std::abs(h) <= cut.snap ? 0.0 : h;
  };
  std::vector<std::array<int, 3>> kept;
  for (int f : faces) {
    const auto t = soup.faces[static_cast<std::size_t>(f)];
    std::vector<int> poly;
    for (int i = 0; i < 3; ++i) {
      const int a = t[i], b = t[(i + 1) % 3];
      const double ha = level(a), hb = level(b);
      if (ha >= 0) poly.push_back(a);
      if ((ha < 0 && hb > 0) || (ha > 0 && hb < 0)) poly.push_back(cross(a, b));
    }
    if (poly.size() == 3) {
      kept.push_back({poly[0], poly[1], poly[2]});
    } else if (poly.size() == 4) {  // split along the shorter diagonal
      const auto dist = [&](int a, int b) { return (soup.vertices[a] - soup.vertices[b]).squaredNorm(); };
      if (dist(poly[0], poly[2]) <= dist(poly[1], poly[3]))
        kept.push_back({poly[0], poly[1], poly[2]}), kept.push_back({poly[0], poly[2], poly[3]});
      else
        kept.push_back({poly[1], poly[2], poly[3]}), kept.push_back({poly[1], poly[3], poly[0]});
    }
    if (poly.size() >= 3) ++trim.faces_clipped;
    else ++trim.faces_removed;
  }
  // Replace the band's faces by the clipped ones (the rest keep their order).
  std::size_t w = 0, next_face = 0;
  for (std::size_t f = 0; f < soup.faces.size(); ++f) {
    if (next_face < faces.size() && static_cast<std::size_t>(faces[next_face]) == f) {
      ++next_face;
      continue;
    }
    soup.faces[w++] = soup.faces[f];
  }
  soup.faces.resize(w);
  soup.faces.insert(soup.faces.end(), kept.begin(), kept.end());
  std::sort(on_plane.begin(), on_plane.end());
  on_plane.erase(std::unique(on_plane.begin(), on_plane.end()), on_plane.end());
  remove_debris(soup, on_plane, cut, trim);
  return on_plane;
}

}  // namespace

std::vector<EndCapTrim> trim_end_caps(TriangleSoup& soup, std::vector<Hole>& holes, const FillOptions& options,
                                      HoleStats* stats) {
  std::vector<EndCapTrim> out;
  if (!(options.end_cap_tolerance > 0) || holes.empty()) return out;
  const auto nv = static_cast<int>(soup.vertices.size());
  for (const auto& t : soup.faces)
    if (std::min({t[0], t[1], t[2]}) < 0 || std::max({t[0], t[1], t[2]}) >= nv) return out;  // (find_holes throws)
  std::vector<std::vector<int>> caps;  // plane vertices of each trimmed cap
  const auto in_cap = [&](int v) {
    return std::any_of(caps.begin(), caps.end(), [&](const auto& c) { return std::binary_search(c.begin(), c.end(), v); });
  };
  // One cap at a time: each cut changes the soup, so the next hole's test sees it. Each hole is
  // tested once (by its smallest vertex: the list is found again after every cut).
  std::unordered_set<int> tested;
  std::optional<MeshIndex> index;
  std::vector<int> referenced;  // vertices of faces, for the one-side test
  for (std::size_t h = 0; h < holes.size(); ++h) {
    const auto& loop = holes[h].loop;
    if (loop.empty() || in_cap(loop.front()) || !tested.insert(*std::min_element(loop.begin(), loop.end())).second)
      continue;
    if (!index) {
      index.emplace(soup);
      referenced.clear();
      for (const auto& t : soup.faces) referenced.insert(referenced.end(), t.begin(), t.end());
      std::sort(referenced.begin(), referenced.end());
      referenced.erase(std::unique(referenced.begin(), referenced.end()), referenced.end());
    }
    const std::optional<Cut> cut = end_cap_cut(soup, *index, referenced, holes[h], options);
    if (!cut) continue;
    const TriangleSoup before = soup;
    EndCapTrim trim;
    trim.depth_mm = cut->depth;
    std::vector<int> plane = apply_cut(soup, *index, holes[h].loop, *cut, trim);
    if (plane.empty()) {  // no plane vertex: nothing to fill flat
      soup = before;
      continue;
    }
    // Accept only when the holes that now run through the plane's vertices lie wholly in the
    // plane, as simple loops: the cap's rim, and maybe small holes where the surface near the
    // rim was within the snap distance of the plane (in-plane faces around them).
    HoleStats found_stats;
    std::vector<Hole> found = find_holes(soup, &found_stats);
    int touching = 0;
    bool clean_cut = true;
    for (std::size_t k = 0; k < found.size(); ++k) {
      const auto on = [&](int v) { return std::binary_search(plane.begin(), plane.end(), v); };
      const auto& l = found[k].loop;
      const long count = std::count_if(l.begin(), l.end(), on);
      if (count == 0) continue;
      ++touching;
      clean_cut = clean_cut && count == static_cast<long>(l.size()) && simple_loop(l);
    }
    // Snapping two ends of a short edge onto the plane can leave a face without area.
    for (const auto& t : soup.faces) {
      const auto on = [&](int v) { return std::binary_search(plane.begin(), plane.end(), v); };
      if (!on(t[0]) && !on(t[1]) && !on(t[2])) continue;
      const Eigen::Vector3d &a = soup.vertices[t[0]], &b = soup.vertices[t[1]], &c = soup.vertices[t[2]];
      if (!((b - a).cross(c - a).norm() > 1e-12 * (b - a).squaredNorm())) clean_cut = false;
    }
    if (touching == 0 || !clean_cut) {
      soup = before;  // (the index still describes it)
      continue;
    }
    index.reset();  // the soup changed: index it again when needed
    holes = std::move(found);
    if (stats) *stats = found_stats;
    caps.push_back(std::move(plane));
    out.push_back(trim);
    h = static_cast<std::size_t>(-1);  // the list was rebuilt: go over it again (tested ones are skipped)
  }
  // Map each cap to its holes in the final list (its rim: the longest; none when a later cut
  // took it, which the acceptance test makes unlikely).
  for (std::size_t c = 0; c < caps.size(); ++c) {
    out[c].hole = EndCapTrim::kNone;
    std::size_t longest = 0;
    for (std::size_t k = 0; k < holes.size(); ++k)
      if (std::binary_search(caps[c].begin(), caps[c].end(), holes[k].loop.front())) {
        holes[k].end_cap = true;
        if (holes[k].loop.size() > longest) longest = holes[k].loop.size(), out[c].hole = k;
      }
  }
  return out;
}

}  // namespace s2c::repair
