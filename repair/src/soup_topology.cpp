#include "soup_topology.h"

#include <algorithm>
#include <numeric>
#include <stdexcept>

#include "s2c/core/disjoint_sets.h"
#include "s2c/core/predicates.h"

namespace s2c::repair {

EdgeFaces::EdgeFaces(const TriangleSoup& soup) {
  std::vector<std::pair<std::uint64_t, int>> sides;
  sides.reserve(soup.faces.size() * 3);
  for (std::size_t fi = 0; fi < soup.faces.size(); ++fi) {
    const auto& f = soup.faces[fi];
    for (int k = 0; k < 3; ++k) sides.emplace_back(undirected_key(f[k], f[(k + 1) % 3]), static_cast<int>(fi));
  }
  std::sort(sides.begin(), sides.end());
  faces_.reserve(sides.size());
  for (std::size_t i = 0; i < sides.size(); ++i) {
    if (i == 0 || sides[i].first != sides[i - 1].first) {
      keys_.push_back(sides[i].first);
      start_.push_back(static_cast<int>(faces_.size()));
    }
    faces_.push_back(sides[i].second);
  }
  start_.push_back(static_cast<int>(faces_.size()));
}

EdgeFaces::Faces EdgeFaces::at(std::uint64_t key) const {
  const auto it = std::lower_bound(keys_.begin(), keys_.end(), key);
  if (it == keys_.end() || *it != key) throw std::out_of_range("no face has this edge");
  return faces_of(static_cast<std::size_t>(it - keys_.begin()));
}

std::vector<int> face_components(const TriangleSoup& soup, int& count) {
  DisjointSets sets(soup.vertices.size());
  for (const auto& f : soup.faces)
    for (int k = 1; k < 3; ++k) sets.unite(f[k], f[0]);
  std::unordered_map<int, int> id;
  std::vector<int> comp(soup.faces.size());
  for (std::size_t fi = 0; fi < soup.faces.size(); ++fi) {
    const int root = sets.find(soup.faces[fi][0]);
    comp[fi] = id.emplace(root, static_cast<int>(id.size())).first->second;
  }
  count = static_cast<int>(id.size());
  return comp;
}

double face_area(const TriangleSoup& soup, int face) {
  const auto& f = soup.faces[face];
  return 0.5 * (soup.vertices[f[1]] - soup.vertices[f[0]]).cross(soup.vertices[f[2]] - soup.vertices[f[0]]).norm();
}

std::vector<char> tiny_open_components(const TriangleSoup& soup, const std::vector<int>& comp, int count,
                                       double fraction) {
  std::vector<double> area(count, 0.0);
  std::vector<char> open(count, 0), tiny(count, 0);
  double total = 0;
  for (std::size_t fi = 0; fi < soup.faces.size(); ++fi) {
    const double a = face_area(soup, static_cast<int>(fi));
    area[comp[fi]] += a;
    total += a;
  }
  for (const auto& [key, faces] : edge_faces(soup))
    if (faces.size() == 1) open[comp[faces[0]]] = 1;
  for (int c = 0; c < count; ++c) tiny[c] = open[c] && area[c] < fraction * total;
  return tiny;
}

bool zero_area(const TriangleSoup& soup, int face) {
  const auto& f = soup.faces[face];
  if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) return true;
  const Eigen::Vector3d &a = soup.vertices[f[0]], &b = soup.vertices[f[1]], &c = soup.vertices[f[2]];
  // Collinear in 3D iff collinear in all three coordinate projections (exact predicates).
  for (int axis = 0; axis < 3; ++axis) {
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    if (orient2d({a[u], a[v]}, {b[u], b[v]}, {c[u], c[v]}) != 0) return false;
  }
  return true;
}

std::size_t remove_unreferenced(TriangleSoup& soup) {
  std::vector<int> map(soup.vertices.size(), -1);
  for (const auto& f : soup.faces)
    for (int v : f) map[v] = 0;
  int next = 0;
  std::vector<Eigen::Vector3d> kept;
  std::vector<Eigen::Vector3d> kept_normals;
  const bool normals = soup.normals.size() == soup.vertices.size();
  for (std::size_t i = 0; i < map.size(); ++i) {
    if (map[i] < 0) continue;
    map[i] = next++;
    kept.push_back(soup.vertices[i]);
    if (normals) kept_normals.push_back(soup.normals[i]);
  }
  const std::size_t removed = soup.vertices.size() - kept.size();
  for (auto& f : soup.faces)
    for (int& v : f) v = map[v];
  soup.vertices = std::move(kept);
  soup.normals = std::move(kept_normals);
  return removed;
}

}  // namespace s2c::repair
