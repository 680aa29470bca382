// Adjacency of the soup for hole filling (see patch.h).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "fill/patch.h"

namespace s2c::repair::fill {
namespace {

// A face with a bad (negative or too large) vertex index is ignored; as unsigned a negative
// index is too large.
bool valid_face(const std::array<int, 3>& t, unsigned nv) {
  return static_cast<unsigned>(t[0]) < nv && static_cast<unsigned>(t[1]) < nv && static_cast<unsigned>(t[2]) < nv;
}
bool valid_face(const TriangleSoup& soup, std::size_t f) {
  return valid_face(soup.faces[f], static_cast<unsigned>(soup.vertices.size()));
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

// A face's box in double; `finite` false when a corner is not finite (min/max would drop it).
struct FaceBox {
  Eigen::Vector3d lo, hi;
  bool finite;
};
FaceBox face_box(const TriangleSoup& soup, std::size_t f) {
  const auto& t = soup.faces[f];
  const Eigen::Vector3d &a = soup.vertices[static_cast<std::size_t>(t[0])], &b = soup.vertices[static_cast<std::size_t>(t[1])],
                        &c = soup.vertices[static_cast<std::size_t>(t[2])];
  return {a.cwiseMin(b).cwiseMin(c), a.cwiseMax(b).cwiseMax(c), a.allFinite() && b.allFinite() && c.allFinite()};
}

// Whether valid face f's box is not apart from [lo, hi] (a face with a non-finite corner always is).
bool face_near(const TriangleSoup& soup, std::size_t f, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi) {
  const FaceBox b = face_box(soup, f);
  return !b.finite || !((b.hi.array() < lo.array()).any() || (b.lo.array() > hi.array()).any());
}

}  // namespace

MeshIndex::MeshIndex(const TriangleSoup& soup) : soup_(soup) {
  // Counting sort of the (vertex, face) incidences; raw pointers in the two O(#F) passes (every
  // fill_holes call pays them).
  const std::size_t nf = soup.faces.size();
  const auto nv = static_cast<unsigned>(soup.vertices.size());
  const std::array<int, 3>* faces = soup.faces.data();
  vf_offset_.assign(std::size_t{nv} + 1, 0);
  int* count = vf_offset_.data() + 1;
  for (std::size_t f = 0; f < nf; ++f)
    if (valid_face(faces[f], nv))
      for (int c : faces[f]) ++count[c];
  for (std::size_t v = 1; v < vf_offset_.size(); ++v) vf_offset_[v] += vf_offset_[v - 1];
  vf_faces_.resize(static_cast<std::size_t>(vf_offset_.back()));
  std::vector<int> next(vf_offset_.begin(), vf_offset_.end() - 1);
  int* out = vf_faces_.data();
  int* at = next.data();
  for (std::size_t f = 0; f < nf; ++f)
    if (valid_face(faces[f], nv))
      for (int c : faces[f]) out[at[c]++] = static_cast<int>(f);
}

void MeshIndex::extend_boxes() const {
  const TriangleSoup& soup = soup_;
  constexpr float nan = std::numeric_limits<float>::quiet_NaN();
  const Box none{Eigen::Vector3f::Constant(nan), Eigen::Vector3f::Constant(nan)};
  // Block k's box: its valid faces' corners, rounded outwards to float once per block; NaN (the
  // block always opened) when a corner is not finite or a face has a bad index.
  const auto block_box = [&](std::size_t k, std::size_t end) {
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (std::size_t f = k * kBlock; f < end; ++f) {
      if (!valid_face(soup, f)) return none;
      const FaceBox b = face_box(soup, f);
      if (!b.finite) return none;
      lo = lo.cwiseMin(b.lo);
      hi = hi.cwiseMax(b.hi);
    }
    return Box{down(lo), up(hi)};
  };
  const std::size_t to = soup.faces.size();
  if (boxed_ >= to) return;
  const std::size_t first_block = boxed_ / kBlock, blocks = (to + kBlock - 1) / kBlock;
  block_boxes_.resize(blocks);
  const auto build = [&](std::size_t k0, std::size_t k1) {
    for (std::size_t k = k0; k < k1; ++k) block_boxes_[k] = block_box(k, std::min(to, (k + 1) * kBlock));
  };
  // Only the blocks' boxes are stored (24 bytes per 32 faces): the first build is O(#F) in every
  // call that fills holes, and a per-face array of boxes cost more in fresh pages than in work.
  if (blocks - first_block > 4096)
    tbb::parallel_for(tbb::blocked_range<std::size_t>(first_block, blocks, 1024),
                      [&](const auto& range) { build(range.begin(), range.end()); });
  else
    build(first_block, blocks);
  boxed_ = to;
}

void MeshIndex::faces_near(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, std::vector<int>& out,
                           std::size_t first) const {
  if (!use_blocks_) {
    scan_near(lo, hi, out, first);
    return;
  }
  if (boxed_ < soup_.faces.size()) extend_boxes();
  const Eigen::Vector3f l = down(lo), h = up(hi);
  // "Not apart" rather than "overlapping", so that NaN boxes are always kept.
  const auto near = [&](const Box& b) {
    return !((b.hi.array() < l.array()).any() || (b.lo.array() > h.array()).any());
  };
  for (std::size_t k = first / kBlock; k < block_boxes_.size(); ++k) {
    if (!near(block_boxes_[k])) continue;
    const std::size_t end = std::min(boxed_, (k + 1) * kBlock);
    for (std::size_t f = std::max(k * kBlock, first); f < end; ++f)
      if (valid_face(soup_, f) && face_near(soup_, f, lo, hi)) out.push_back(static_cast<int>(f));
  }
}

void MeshIndex::scan_near(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, std::vector<int>& out,
                          std::size_t first) const {
  const TriangleSoup& soup = soup_;
  const std::size_t faces = soup.faces.size(), vertices = soup.vertices.size();
  if (first >= faces) return;
  // A few faces (appended since `first`): their boxes directly.
  if (3 * (faces - first) < vertices) {
    for (std::size_t f = first; f < faces; ++f)
      if (valid_face(soup, f) && face_near(soup, f, lo, hi)) out.push_back(static_cast<int>(f));
    return;
  }
  // Outcode bit 2a: below lo on axis a, bit 2a+1: above hi. A non-finite corner gets none, so
  // its faces are always kept.
  thread_local std::vector<std::uint8_t> code;
  code.resize(vertices);
  const Eigen::Vector3d* point = soup.vertices.data();
  const double lx = lo.x(), ly = lo.y(), lz = lo.z(), hx = hi.x(), hy = hi.y(), hz = hi.z();
  std::uint8_t* c = code.data();
  for (std::size_t v = 0; v < vertices; ++v) {
    const double x = point[v].x(), y = point[v].y(), z = point[v].z();
    const bool finite = std::isfinite(x + y + z);  // NaN or ±inf in any coordinate
    c[v] = static_cast<std::uint8_t>(finite * ((x < lx) | (x > hx) << 1 | (y < ly) << 2 | (y > hy) << 3 |
                                               (z < lz) << 4 | (z > hz) << 5));
  }
  const auto nv = static_cast<unsigned>(vertices);
  const std::array<int, 3>* face = soup.faces.data();
  for (std::size_t f = first; f < faces; ++f) {
    const auto& t = face[f];
    if (valid_face(t, nv) && (c[t[0]] & c[t[1]] & c[t[2]]) == 0) out.push_back(static_cast<int>(f));
  }
}

void MeshIndex::add_faces(std::size_t first) {
  for (std::size_t f = first; f < soup_.faces.size(); ++f) {
    if (!valid_face(soup_, f)) continue;
    for (int c : soup_.faces[f]) {
      added_vertex_faces_[c].push_back(static_cast<int>(f));
      if (static_cast<std::size_t>(c) >= has_added_.size()) has_added_.resize(soup_.vertices.size(), 0);
      has_added_[static_cast<std::size_t>(c)] = 1;
    }
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
  append_neighbours(v, out);
  return out;
}

void MeshIndex::append_neighbours(int v, std::vector<int>& out) const {
  const auto first = static_cast<std::ptrdiff_t>(out.size());
  for_each_face_of(v, [&](int f) {
    for (int c : soup_.faces[static_cast<std::size_t>(f)])
      if (c != v) out.push_back(c);
  });
  std::sort(out.begin() + first, out.end());
  out.erase(std::unique(out.begin() + first, out.end()), out.end());
}

}  // namespace s2c::repair::fill
