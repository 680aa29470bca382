// Adjacency of the soup for hole filling (see patch.h).
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "fill/patch.h"

namespace s2c::repair::fill {
namespace {

bool valid_face(const TriangleSoup& soup, std::size_t f) {
  const auto& t = soup.faces[f];
  const int nv = static_cast<int>(soup.vertices.size());
  return std::min({t[0], t[1], t[2]}) >= 0 && std::max({t[0], t[1], t[2]}) < nv;  // bad index: ignored
}

// float boxes that contain the double ones: the conversion rounds to nearest (half an ulp, 2⁻²⁴
// relative), so widening by 2⁻²² relative plus the smallest normal float is always enough.
Eigen::Vector3f down(const Eigen::Vector3d& x) {
  const Eigen::Vector3f f = x.cast<float>();
  return f - (f.cwiseAbs() * 2.4e-7f).array().matrix() - Eigen::Vector3f::Constant(1.2e-38f);
}
Eigen::Vector3f up(const Eigen::Vector3d& x) {
  const Eigen::Vector3f f = x.cast<float>();
  return f + (f.cwiseAbs() * 2.4e-7f).array().matrix() + Eigen::Vector3f::Constant(1.2e-38f);
}

}  // namespace

MeshIndex::MeshIndex(const TriangleSoup& soup) : soup_(soup) {
  vf_offset_.assign(soup.vertices.size() + 1, 0);
  for (std::size_t f = 0; f < soup.faces.size(); ++f)
    if (valid_face(soup, f))
      for (int c : soup.faces[f]) ++vf_offset_[static_cast<std::size_t>(c) + 1];
  for (std::size_t v = 1; v < vf_offset_.size(); ++v) vf_offset_[v] += vf_offset_[v - 1];
  vf_faces_.resize(static_cast<std::size_t>(vf_offset_.back()));
  std::vector<int> fill(vf_offset_.begin(), vf_offset_.end() - 1);
  for (std::size_t f = 0; f < soup.faces.size(); ++f)
    if (valid_face(soup, f))
      for (int c : soup.faces[f]) vf_faces_[static_cast<std::size_t>(fill[static_cast<std::size_t>(c)]++)] = static_cast<int>(f);
}

void MeshIndex::extend_boxes() const {
  const TriangleSoup& soup = soup_;
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();
  const Box none{Eigen::Vector3f::Constant(nan), Eigen::Vector3f::Constant(nan)};
  const auto corner_box = [&](std::size_t v) {
    const Eigen::Vector3d& p = soup.vertices[v];
    return p.allFinite() ? Box{down(p), up(p)} : none;
  };
  // A face's box from its corners' rounded boxes (down/up are monotone: the min of the rounded
  // corners is the rounded min); NaN when a corner is not finite (min/max would drop it silently).
  const auto face_box = [&](std::size_t f, const auto& corner) {
    if (!valid_face(soup, f)) return none;
    const auto& t = soup.faces[f];
    const Box a = corner(static_cast<std::size_t>(t[0])), b = corner(static_cast<std::size_t>(t[1])),
              c = corner(static_cast<std::size_t>(t[2]));
    if (!a.lo.allFinite() || !b.lo.allFinite() || !c.lo.allFinite()) return none;
    return Box{a.lo.cwiseMin(b.lo).cwiseMin(c.lo), a.hi.cwiseMax(b.hi).cwiseMax(c.hi)};
  };
  // Block boxes: a NaN face box makes its block's box NaN (always opened, see faces_near).
  const auto merge = [&](Box& block, const Box& box) {
    if (!box.lo.allFinite() || !block.lo.allFinite()) block = none;
    else block = {block.lo.cwiseMin(box.lo), block.hi.cwiseMax(box.hi)};
  };
  const std::size_t from = face_boxes_.size(), to = soup.faces.size();
  if (from >= to) return;
  if (face_boxes_.capacity() < to) {  // room for the faces later fills append
    face_boxes_.reserve(to + to / 4);
    block_boxes_.reserve(face_boxes_.capacity() / kBlock + 1);
  }
  if (from == 0) {
    // The first build, O(#F) in every call that fills holes: each vertex rounded once, then
    // whole blocks of faces, both in parallel on large meshes (a small one is a single task).
    const std::size_t nv = soup.vertices.size();
    std::vector<Box> corners(nv);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nv, 4096), [&](const auto& range) {
      for (std::size_t v = range.begin(); v != range.end(); ++v) corners[v] = corner_box(v);
    });
    const auto cached = [&](std::size_t v) -> const Box& { return corners[v]; };
    face_boxes_.resize(to);
    block_boxes_.resize((to + kBlock - 1) / kBlock);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, block_boxes_.size(), 256), [&](const auto& range) {
      for (std::size_t k = range.begin(); k != range.end(); ++k) {
        const std::size_t end = std::min(to, (k + 1) * kBlock);
        block_boxes_[k] = face_boxes_[k * kBlock] = face_box(k * kBlock, cached);
        for (std::size_t f = k * kBlock + 1; f < end; ++f) merge(block_boxes_[k], face_boxes_[f] = face_box(f, cached));
      }
    });
    return;
  }
  for (std::size_t f = from; f < to; ++f) {  // faces appended by fills: a few, corners rounded each time
    face_boxes_.push_back(face_box(f, corner_box));
    const std::size_t k = f / kBlock;
    if (k == block_boxes_.size()) block_boxes_.push_back(face_boxes_.back());
    else merge(block_boxes_[k], face_boxes_.back());
  }
}

void MeshIndex::faces_near(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, std::vector<int>& out,
                           std::size_t first) const {
  if (face_boxes_.size() < soup_.faces.size()) extend_boxes();
  const Eigen::Vector3f l = down(lo), h = up(hi);
  // "Not apart" rather than "overlapping", so that NaN boxes are always kept.
  const auto near = [&](const Box& b) {
    return !((b.hi.array() < l.array()).any() || (b.lo.array() > h.array()).any());
  };
  for (std::size_t k = first / kBlock; k < block_boxes_.size(); ++k) {
    if (!near(block_boxes_[k])) continue;
    const std::size_t end = std::min(face_boxes_.size(), (k + 1) * kBlock);
    for (std::size_t f = std::max(k * kBlock, first); f < end; ++f)
      if (near(face_boxes_[f]) && valid_face(soup_, f)) out.push_back(static_cast<int>(f));
  }
}

void MeshIndex::add_faces(std::size_t first) {
  for (std::size_t f = first; f < soup_.faces.size(); ++f) {
    if (!valid_face(soup_, f)) continue;
    for (int c : soup_.faces[f]) added_vertex_faces_[c].push_back(static_cast<int>(f));
  }
}

std::vector<int> MeshIndex::faces_of(int v) const {
  std::vector<int> out;
  for_each_face_of(v, [&](int f) { out.push_back(f); });
  return out;
}

int MeshIndex::face_with(int a, int b) const {
  // Through a's faces: a vertex has a handful, and this needs no edge table (see the class).
  // The vertex → faces lists are in face order, so "first" is the lowest face index.
  int found = -1;
  for_each_face_of(a, [&](int f) {
    if (found >= 0) return;
    const auto& t = soup_.faces[static_cast<std::size_t>(f)];
    for (int k = 0; k < 3; ++k)
      if (t[k] == a && t[(k + 1) % 3] == b) found = f;
  });
  return found;
}

int MeshIndex::edge_faces(int a, int b) const {
  int count = 0;
  for_each_face_of(a, [&](int f) {
    const auto& t = soup_.faces[static_cast<std::size_t>(f)];
    for (int k = 0; k < 3; ++k) {
      const int u = t[k], w = t[(k + 1) % 3];
      if ((u == a && w == b) || (u == b && w == a)) ++count;
    }
  });
  return count;
}

std::vector<int> MeshIndex::neighbours(int v) const {
  std::vector<int> out;
  for_each_face_of(v, [&](int f) {
    for (int c : soup_.faces[static_cast<std::size_t>(f)])
      if (c != v) out.push_back(c);
  });
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

}  // namespace s2c::repair::fill
