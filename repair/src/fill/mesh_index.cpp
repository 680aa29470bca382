// Adjacency of the soup for hole filling (see patch.h).
#include <algorithm>
#include <cmath>
#include <cstddef>

#include "fill/patch.h"

namespace s2c::repair::fill {
namespace {

bool valid_face(const TriangleSoup& soup, std::size_t f) {
  const auto& t = soup.faces[f];
  const int nv = static_cast<int>(soup.vertices.size());
  return std::min({t[0], t[1], t[2]}) >= 0 && std::max({t[0], t[1], t[2]}) < nv;  // bad index: ignored
}

}  // namespace

MeshIndex::MeshIndex(const TriangleSoup& soup) {
  directed_.reserve(soup.faces.size() * 3);
  vf_offset_.assign(soup.vertices.size() + 1, 0);
  for (std::size_t f = 0; f < soup.faces.size(); ++f) {
    if (!valid_face(soup, f)) continue;
    const auto& t = soup.faces[f];
    for (int k = 0; k < 3; ++k) {
      directed_.push_back({directed_key(t[k], t[(k + 1) % 3]), static_cast<int>(f)});
      ++vf_offset_[static_cast<std::size_t>(t[k]) + 1];
    }
  }
  std::sort(directed_.begin(), directed_.end());
  for (std::size_t v = 1; v < vf_offset_.size(); ++v) vf_offset_[v] += vf_offset_[v - 1];
  vf_faces_.resize(static_cast<std::size_t>(vf_offset_.back()));
  std::vector<int> fill(vf_offset_.begin(), vf_offset_.end() - 1);
  for (std::size_t f = 0; f < soup.faces.size(); ++f)
    if (valid_face(soup, f))
      for (int c : soup.faces[f]) vf_faces_[static_cast<std::size_t>(fill[static_cast<std::size_t>(c)]++)] = static_cast<int>(f);
  // Grid: origin at the vertices' lower corner, cell twice the mean edge length (sampled).
  if (!soup.vertices.empty()) {
    Eigen::Vector3d lo = soup.vertices[0];
    for (const auto& p : soup.vertices) lo = lo.cwiseMin(p);
    grid_origin_ = lo.allFinite() ? lo : Eigen::Vector3d::Zero();
  }
  double sum = 0;
  std::size_t count = 0;
  const std::size_t step = std::max<std::size_t>(1, soup.faces.size() / 4096);
  for (std::size_t f = 0; f < soup.faces.size(); f += step)
    if (valid_face(soup, f)) {
      const double e = (soup.vertices[soup.faces[f][1]] - soup.vertices[soup.faces[f][0]]).norm();
      if (std::isfinite(e)) {
        sum += e;
        ++count;
      }
    }
  cell_ = count && sum > 0 ? 2 * sum / double(count) : 1.0;
  grid_.reserve(soup.faces.size() * 2);
  for (std::size_t f = 0; f < soup.faces.size(); ++f)
    if (valid_face(soup, f)) grid_insert(soup, static_cast<int>(f), false);
  std::sort(grid_.begin(), grid_.end());
  faces_ = soup.faces.size();
}

namespace {
constexpr int kOversizeCells = 512;  // a face spanning more cells is tested with every patch
std::uint64_t cell_key(long long x, long long y, long long z) {
  const auto c = [](long long v) { return std::uint64_t(v + (1 << 20)) & 0x1fffff; };
  return (c(x) << 42) | (c(y) << 21) | c(z);
}
}  // namespace

void MeshIndex::grid_insert(const TriangleSoup& soup, int f, bool appended) {
  const auto& t = soup.faces[static_cast<std::size_t>(f)];
  const Eigen::Vector3d &a = soup.vertices[t[0]], &b = soup.vertices[t[1]], &c = soup.vertices[t[2]];
  const Eigen::Vector3d lo = a.cwiseMin(b).cwiseMin(c), hi = a.cwiseMax(b).cwiseMax(c);
  const Eigen::Array3d l = ((lo - grid_origin_) / cell_).array().floor(), h = ((hi - grid_origin_) / cell_).array().floor();
  if (!l.allFinite() || !h.allFinite() || (l < -1e6).any() || (h > 1e6).any() ||
      (h - l + 1).prod() > kOversizeCells) {
    oversize_.push_back(f);
    return;
  }
  for (long long x = (long long)l.x(); x <= (long long)h.x(); ++x)
    for (long long y = (long long)l.y(); y <= (long long)h.y(); ++y)
      for (long long z = (long long)l.z(); z <= (long long)h.z(); ++z) {
        if (appended) added_grid_[cell_key(x, y, z)].push_back(f);
        else grid_.push_back({cell_key(x, y, z), f});
      }
}

void MeshIndex::faces_near(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, std::vector<int>& out) const {
  const std::size_t start = out.size();
  const Eigen::Array3d l = ((lo - grid_origin_) / cell_).array().floor(), h = ((hi - grid_origin_) / cell_).array().floor();
  const double cells = (h - l + 1).prod();
  if (!(cells <= double(faces_ + added_grid_.size() + 64)) || (l < -1e6).any() || (h > 1e6).any()) {
    // Box larger than the mesh's face count in cells: every face (still cheaper than the grid).
    for (std::size_t f = 0; f < faces_; ++f) out.push_back(static_cast<int>(f));
    for (const auto& [key, faces] : added_grid_) out.insert(out.end(), faces.begin(), faces.end());
  } else {
    for (long long x = (long long)l.x(); x <= (long long)h.x(); ++x)
      for (long long y = (long long)l.y(); y <= (long long)h.y(); ++y)
        for (long long z = (long long)l.z(); z <= (long long)h.z(); ++z) {
          const std::uint64_t key = cell_key(x, y, z);
          auto it = std::lower_bound(grid_.begin(), grid_.end(), std::pair<std::uint64_t, int>{key, -1});
          for (; it != grid_.end() && it->first == key; ++it) out.push_back(it->second);
          const auto added = added_grid_.find(key);
          if (added != added_grid_.end()) out.insert(out.end(), added->second.begin(), added->second.end());
        }
  }
  out.insert(out.end(), oversize_.begin(), oversize_.end());
  std::sort(out.begin() + static_cast<std::ptrdiff_t>(start), out.end());
  out.erase(std::unique(out.begin() + static_cast<std::ptrdiff_t>(start), out.end()), out.end());
}

void MeshIndex::add_faces(const TriangleSoup& soup, std::size_t first) {
  for (std::size_t f = first; f < soup.faces.size(); ++f) {
    if (!valid_face(soup, f)) continue;
    const auto& t = soup.faces[f];
    for (int k = 0; k < 3; ++k) {
      added_directed_[directed_key(t[k], t[(k + 1) % 3])].push_back(static_cast<int>(f));
      added_vertex_faces_[t[k]].push_back(static_cast<int>(f));
    }
    grid_insert(soup, static_cast<int>(f), true);
  }
}

std::vector<int> MeshIndex::faces_of(int v) const {
  std::vector<int> out;
  if (v >= 0 && static_cast<std::size_t>(v) + 1 < vf_offset_.size())
    out.assign(vf_faces_.begin() + vf_offset_[v], vf_faces_.begin() + vf_offset_[v + 1]);
  const auto it = added_vertex_faces_.find(v);
  if (it != added_vertex_faces_.end()) out.insert(out.end(), it->second.begin(), it->second.end());
  return out;
}

int MeshIndex::face_with(int a, int b) const {
  const std::uint64_t key = directed_key(a, b);
  const auto it = std::lower_bound(directed_.begin(), directed_.end(), std::pair<std::uint64_t, int>{key, -1});
  if (it != directed_.end() && it->first == key) return it->second;
  const auto added = added_directed_.find(key);
  return added == added_directed_.end() ? -1 : added->second.front();
}

int MeshIndex::edge_faces(int a, int b) const {
  int count = 0;
  for (const std::uint64_t key : {directed_key(a, b), directed_key(b, a)}) {
    const auto lo = std::lower_bound(directed_.begin(), directed_.end(), std::pair<std::uint64_t, int>{key, -1});
    auto hi = lo;
    while (hi != directed_.end() && hi->first == key) ++hi;
    count += static_cast<int>(hi - lo);
    const auto added = added_directed_.find(key);
    if (added != added_directed_.end()) count += static_cast<int>(added->second.size());
  }
  return count;
}

std::vector<int> MeshIndex::neighbours(const TriangleSoup& soup, int v) const {
  std::vector<int> out;
  for (int f : faces_of(v))
    for (int c : soup.faces[static_cast<std::size_t>(f)])
      if (c != v) out.push_back(c);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace s2c::repair::fill
