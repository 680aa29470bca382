// Adjacency of the soup for hole filling (see patch.h).
#include <algorithm>

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
}

void MeshIndex::add_faces(const TriangleSoup& soup, std::size_t first) {
  for (std::size_t f = first; f < soup.faces.size(); ++f) {
    if (!valid_face(soup, f)) continue;
    const auto& t = soup.faces[f];
    for (int k = 0; k < 3; ++k) {
      added_directed_[directed_key(t[k], t[(k + 1) % 3])].push_back(static_cast<int>(f));
      added_vertex_faces_[t[k]].push_back(static_cast<int>(f));
    }
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
