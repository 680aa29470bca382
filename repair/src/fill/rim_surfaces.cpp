// Noise estimate and crease split of the surface around a hole (see rim_surfaces.h).
#include "fill/rim_surfaces.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace s2c::repair::fill {
namespace {

constexpr double kPi = 3.14159265358979323846;

}  // namespace

Eigen::Vector3d area_normal(const TriangleSoup& soup, const MeshIndex& index, int v, const Position& at) {
  Eigen::Vector3d n = Eigen::Vector3d::Zero();
  index.for_each_face_of(v, [&](int f) {
    const auto& t = soup.faces[static_cast<std::size_t>(f)];
    n += (at(t[1]) - at(t[0])).cross(at(t[2]) - at(t[0]));
  });
  return n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero();
}

double surface_noise(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& vertices,
                     const Position& at, const std::vector<int>& skip) {
  // Flat arrays over `vertices` (sorted): this runs for every hole.
  const std::size_t n = vertices.size();
  constexpr double none = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> normal_laplacian(n, none);
  std::vector<std::size_t> first(n + 1, 0);
  std::vector<int> nbrs;
  for (std::size_t i = 0; i < n; ++i) {
    const int v = vertices[i];
    first[i] = nbrs.size();
    if (std::binary_search(skip.begin(), skip.end(), v)) continue;
    index.append_neighbours(v, nbrs);
    const auto list = nbrs.begin() + static_cast<std::ptrdiff_t>(first[i]);
    const Eigen::Vector3d normal = area_normal(soup, index, v, at);
    if (list == nbrs.end() || normal.squaredNorm() == 0) continue;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (auto u = list; u != nbrs.end(); ++u) mean += at(*u);
    normal_laplacian[i] = (mean / double(nbrs.end() - list) - at(v)).dot(normal);
  }
  first[n] = nbrs.size();
  std::vector<double> jumps;
  for (std::size_t i = 0; i < n; ++i) {
    if (std::isnan(normal_laplacian[i])) continue;
    double sum = 0;
    int count = 0;
    for (std::size_t k = first[i]; k < first[i + 1]; ++k) {
      const auto it = std::lower_bound(vertices.begin(), vertices.end(), nbrs[k]);
      if (it == vertices.end() || *it != nbrs[k]) continue;
      const double l = normal_laplacian[static_cast<std::size_t>(it - vertices.begin())];
      if (std::isnan(l)) continue;
      sum += l;
      ++count;
    }
    if (count >= 3) jumps.push_back(std::abs(normal_laplacian[i] - sum / count));
  }
  if (jumps.empty()) return 0;
  const auto mid = jumps.begin() + static_cast<std::ptrdiff_t>(jumps.size() / 2);
  std::nth_element(jumps.begin(), mid, jumps.end());
  return *mid;
}

CreaseSplit one_piece(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& vertices,
                      const Position& at) {
  CreaseSplit out;
  out.pieces.resize(1);
  out.pieces[0].vertices = vertices;
  out.pieces[0].normals.reserve(vertices.size());
  for (int v : vertices) out.pieces[0].normals.push_back(area_normal(soup, index, v, at));
  return out;
}

CreaseSplit split_at_creases(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& vertices,
                             const Position& at, double crease_deg, std::size_t min_vertices) {
  const auto whole = [&] { return one_piece(soup, index, vertices, at); };
  if (!(crease_deg > 0)) return whole();
  CreaseSplit out;
  // Faces with all three corners in `vertices` (sorted), their normals and the edges between
  // them; flat sorted arrays rather than hash maps (this runs for every hole).
  const auto in_set = [&](int v) { return std::binary_search(vertices.begin(), vertices.end(), v); };
  std::vector<int> faces;  // every face of the vertices once, then those wholly inside
  for (int v : vertices) index.for_each_face_of(v, [&](int f) { faces.push_back(f); });
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());
  faces.erase(std::remove_if(faces.begin(), faces.end(),
                             [&](int f) {
                               const auto& t = soup.faces[static_cast<std::size_t>(f)];
                               return !(in_set(t[0]) && in_set(t[1]) && in_set(t[2]));
                             }),
              faces.end());
  std::vector<Eigen::Vector3d> normal(faces.size());
  std::vector<std::pair<std::uint64_t, int>> by_edge;  // (edge key, position in `faces`)
  by_edge.reserve(3 * faces.size());
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const auto& t = soup.faces[static_cast<std::size_t>(faces[i])];
    normal[i] = unit_normal(at(t[0]), at(t[1]), at(t[2]));
    for (int k = 0; k < 3; ++k) by_edge.emplace_back(edge_key(t[k], t[(k + 1) % 3]), static_cast<int>(i));
  }
  std::sort(by_edge.begin(), by_edge.end());
  // Region growing across smooth edges (degenerate faces join anything: they have no normal).
  const double cos_crease = std::cos(crease_deg * kPi / 180);
  DisjointSets pieces(faces.size());
  struct Crease {
    int a, b;  // faces (positions in `faces`)
    int edge_vertex, far_vertex;
  };
  std::vector<Crease> creases;
  for (std::size_t e = 0; e < by_edge.size();) {
    std::size_t end = e + 1;
    while (end < by_edge.size() && by_edge[end].first == by_edge[e].first) ++end;
    if (end - e == 2) {  // a manifold edge between two of the faces
      const std::uint64_t key = by_edge[e].first;
      const int a = by_edge[e].second, b = by_edge[e + 1].second;
      if (normal[a].squaredNorm() == 0 || normal[b].squaredNorm() == 0 || normal[a].dot(normal[b]) >= cos_crease) {
        pieces.unite(a, b);
      } else {
        const auto& tb = soup.faces[static_cast<std::size_t>(faces[b])];
        const int u = static_cast<int>(key >> 32), w = static_cast<int>(key & 0xffffffffu);
        int far = tb[0];
        for (int c : tb)
          if (c != u && c != w) far = c;
        creases.push_back({a, b, u, far});
        out.crease_vertices.push_back(u);
        out.crease_vertices.push_back(w);
      }
    }
    e = end;
  }
  std::sort(out.crease_vertices.begin(), out.crease_vertices.end());
  out.crease_vertices.erase(std::unique(out.crease_vertices.begin(), out.crease_vertices.end()), out.crease_vertices.end());
  if (creases.empty()) return whole();
  const auto whole_with_creases = [&] {
    CreaseSplit one = whole();
    one.crease_vertices = out.crease_vertices;
    return one;
  };
  // Pieces, in order of their first face; small ones (a crease's sliver) are dropped. Each
  // piece's (vertex, face) incidences, sorted, give its vertices and their normals.
  std::vector<std::pair<int, int>> by_root;  // (root, position in `faces`)
  for (std::size_t i = 0; i < faces.size(); ++i) by_root.emplace_back(pieces.find(static_cast<int>(i)), static_cast<int>(i));
  std::sort(by_root.begin(), by_root.end());
  std::vector<int> piece_of_root(faces.size(), -1);
  for (std::size_t r = 0; r < by_root.size();) {
    std::size_t end = r + 1;
    while (end < by_root.size() && by_root[end].first == by_root[r].first) ++end;
    std::vector<std::pair<int, int>> corners;  // (vertex, position in `faces`)
    for (std::size_t k = r; k < end; ++k)
      for (int c : soup.faces[static_cast<std::size_t>(faces[by_root[k].second])]) corners.emplace_back(c, by_root[k].second);
    std::sort(corners.begin(), corners.end());
    SmoothPiece p;
    for (std::size_t c = 0; c < corners.size();) {
      std::size_t stop = c + 1;
      while (stop < corners.size() && corners[stop].first == corners[c].first) ++stop;
      Eigen::Vector3d n = Eigen::Vector3d::Zero();
      for (std::size_t k = c; k < stop; ++k) {
        const auto& t = soup.faces[static_cast<std::size_t>(faces[corners[k].second])];
        n += (at(t[1]) - at(t[0])).cross(at(t[2]) - at(t[0]));
      }
      p.vertices.push_back(corners[c].first);
      p.normals.push_back(n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero());
      c = stop;
    }
    if (p.vertices.size() >= min_vertices) {
      piece_of_root[by_root[r].first] = static_cast<int>(out.pieces.size());
      out.pieces.push_back(std::move(p));
    }
    r = end;
  }
  if (out.pieces.size() < 2) return whole_with_creases();
  // How the kept pieces meet: every crease between two of them votes.
  int convex = 0, concave = 0;
  for (const Crease& c : creases) {
    if (piece_of_root[pieces.find(c.a)] < 0 || piece_of_root[pieces.find(c.b)] < 0) continue;
    (normal[c.a].dot(at(c.far_vertex) - at(c.edge_vertex)) < 0 ? convex : concave) += 1;
  }
  // Mixed (a step: one convex and one concave crease) needs one surface; a stray vote or two
  // (a noisy edge along a crease) does not make it mixed.
  if (convex + concave == 0 || 10 * std::min(convex, concave) > convex + concave) return whole_with_creases();
  out.convex = convex > 0;
  // Deterministic order: by first vertex.
  std::sort(out.pieces.begin(), out.pieces.end(),
            [](const SmoothPiece& a, const SmoothPiece& b) { return a.vertices.front() < b.vertices.front(); });
  return out;
}

}  // namespace s2c::repair::fill
