// Noise estimate and crease split of the surface around a hole (see rim_surfaces.h).
#include "fill/rim_surfaces.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include "fill/local_ids.h"

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
  const LocalIds local(vertices), skipped(skip);
  for (std::size_t i = 0; i < n; ++i) {
    const int v = vertices[i];
    first[i] = nbrs.size();
    if (skipped.contains(v)) continue;
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
      const int at_k = local.find(nbrs[k]);
      if (at_k < 0) continue;
      const double l = normal_laplacian[static_cast<std::size_t>(at_k)];
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
  // them; flat sorted arrays rather than hash maps (this runs for every hole). Each such face is
  // taken once, from its smallest corner.
  const LocalIds local(vertices);
  std::vector<int> faces;  // ascending
  for (int v : vertices)
    index.for_each_face_of(v, [&](int f) {
      const auto& t = soup.faces[static_cast<std::size_t>(f)];
      if (v == std::min({t[0], t[1], t[2]}) && local.contains(t[0]) && local.contains(t[1]) && local.contains(t[2]))
        faces.push_back(f);
    });
  std::sort(faces.begin(), faces.end());
  faces.erase(std::unique(faces.begin(), faces.end()), faces.end());  // (a corner repeated in a face)
  std::vector<Eigen::Vector3d> normal(faces.size());
  // The faces' edges by (smaller corner, larger corner, position in `faces`): a counting sort by
  // the smaller corner's local number (local order is vertex order), then each corner's few
  // edges by insertion.
  struct Edge {
    int lo, hi, face;
    bool operator<(const Edge& o) const { return hi != o.hi ? hi < o.hi : face < o.face; }
  };
  std::vector<int> first_edge(vertices.size() + 1, 0);
  for (std::size_t i = 0; i < faces.size(); ++i) {
    const auto& t = soup.faces[static_cast<std::size_t>(faces[i])];
    normal[i] = unit_normal(at(t[0]), at(t[1]), at(t[2]));
    for (int k = 0; k < 3; ++k) ++first_edge[local.find(std::min(t[k], t[(k + 1) % 3])) + 1];
  }
  for (std::size_t v = 1; v < first_edge.size(); ++v) first_edge[v] += first_edge[v - 1];
  std::vector<Edge> by_edge(static_cast<std::size_t>(first_edge.back()));
  {
    std::vector<int> next(first_edge.begin(), first_edge.end() - 1);
    for (std::size_t i = 0; i < faces.size(); ++i) {
      const auto& t = soup.faces[static_cast<std::size_t>(faces[i])];
      for (int k = 0; k < 3; ++k) {
        const int a = std::min(t[k], t[(k + 1) % 3]), b = std::max(t[k], t[(k + 1) % 3]);
        by_edge[static_cast<std::size_t>(next[local.find(a)]++)] = {a, b, static_cast<int>(i)};
      }
    }
    for (std::size_t v = 0; v + 1 < first_edge.size(); ++v)
      std::sort(by_edge.begin() + first_edge[v], by_edge.begin() + first_edge[v + 1]);
  }
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
    const auto same_edge = [&](const Edge& x, const Edge& y) { return x.lo == y.lo && x.hi == y.hi; };
    while (end < by_edge.size() && same_edge(by_edge[end], by_edge[e])) ++end;
    if (end - e == 2) {  // a manifold edge between two of the faces
      const int u = by_edge[e].lo, w = by_edge[e].hi;
      const int a = by_edge[e].face, b = by_edge[e + 1].face;
      if (normal[a].squaredNorm() == 0 || normal[b].squaredNorm() == 0 || normal[a].dot(normal[b]) >= cos_crease) {
        pieces.unite(a, b);
      } else {
        const auto& tb = soup.faces[static_cast<std::size_t>(faces[b])];
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
  // Pieces, in order of their root face; small ones (a crease's sliver) are dropped. The faces
  // by root (a counting sort, ascending within a root); per piece each face's area vector is
  // summed into its corners in face order, and the touched corners, ascending, are the piece's
  // vertices.
  const std::size_t nf = faces.size();
  std::vector<int> root(nf), first_of_root(nf + 1, 0);
  for (std::size_t i = 0; i < nf; ++i) ++first_of_root[(root[i] = pieces.find(static_cast<int>(i))) + 1];
  for (std::size_t r = 1; r <= nf; ++r) first_of_root[r] += first_of_root[r - 1];
  std::vector<int> by_root(nf);
  {
    std::vector<int> next(first_of_root.begin(), first_of_root.end() - 1);
    for (std::size_t i = 0; i < nf; ++i) by_root[static_cast<std::size_t>(next[root[i]]++)] = static_cast<int>(i);
  }
  std::vector<int> piece_of_root(nf, -1);
  std::vector<Eigen::Vector3d> sum(vertices.size(), Eigen::Vector3d::Zero());
  std::vector<int> touched;
  for (std::size_t r = 0; r < nf; ++r) {
    if (first_of_root[r] == first_of_root[r + 1]) continue;
    touched.clear();
    for (int k = first_of_root[r]; k < first_of_root[r + 1]; ++k) {
      const auto& t = soup.faces[static_cast<std::size_t>(faces[static_cast<std::size_t>(by_root[static_cast<std::size_t>(k)])])];
      const Eigen::Vector3d area = (at(t[1]) - at(t[0])).cross(at(t[2]) - at(t[0]));
      for (int c : t) {
        const int l = local.find(c);
        touched.push_back(l);
        sum[static_cast<std::size_t>(l)] += area;
      }
    }
    std::sort(touched.begin(), touched.end());
    touched.erase(std::unique(touched.begin(), touched.end()), touched.end());
    SmoothPiece p;
    for (int l : touched) {
      Eigen::Vector3d& n = sum[static_cast<std::size_t>(l)];
      p.vertices.push_back(vertices[static_cast<std::size_t>(l)]);
      p.normals.push_back(n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero());
      n.setZero();
    }
    if (p.vertices.size() >= min_vertices) {
      piece_of_root[r] = static_cast<int>(out.pieces.size());
      out.pieces.push_back(std::move(p));
    }
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
