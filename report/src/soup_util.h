#pragma once
// Small geometric helpers the report's sources share.
#include <vector>

#include "s2c/core/mesh.h"

namespace s2c::report {

inline double face_area(const TriangleSoup& s, std::size_t f) {
  const auto& t = s.faces[f];
  return 0.5 * (s.vertices[t[1]] - s.vertices[t[0]]).cross(s.vertices[t[2]] - s.vertices[t[0]]).norm();
}

/// Bounds of every point (core's bounds() counts only the vertices faces use: a cloud has none).
inline Bounds vertex_bounds(const std::vector<Eigen::Vector3d>& points) {
  Bounds b;
  if (points.empty()) return b;
  b.min = b.max = points.front();
  for (const auto& p : points) {
    b.min = b.min.cwiseMin(p);
    b.max = b.max.cwiseMax(p);
  }
  return b;
}

/// Six times the signed volume enclosed by the faces (positive when they face outward).
inline double signed_volume6(const TriangleSoup& s) {
  double v = 0;
  for (const auto& t : s.faces) v += s.vertices[t[0]].dot(s.vertices[t[1]].cross(s.vertices[t[2]]));
  return v;
}

}  // namespace s2c::report
