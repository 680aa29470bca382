#include "volumetric/mc_table.h"

#include <algorithm>
#include <utility>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace s2c::repair::mc {

const std::array<Edge, 12>& edges() {
  static const std::array<Edge, 12> table = [] {
    std::array<Edge, 12> e{};
    int n = 0;
    for (int axis = 0; axis < 3; ++axis)
      for (int c = 0; c < 8; ++c)
        if (!(c & (1 << axis))) e[n++] = {c, c | (1 << axis), axis};
    return e;
  }();
  return table;
}

namespace {

int edge_id(int a, int b) {
  if (a > b) std::swap(a, b);
  const auto& e = edges();
  for (int i = 0; i < 12; ++i)
    if (e[i].a == a && e[i].b == b) return i;
  return -1;
}

Eigen::Vector3d corner(int c) { return {double(c & 1), double((c >> 1) & 1), double((c >> 2) & 1)}; }

Case build_case(int mask) {
  auto inside = [&](int c) { return (mask >> c) & 1; };
  // partner[e][k]: the edges paired with crossing edge e on its two faces.
  std::array<std::array<int, 2>, 12> link;
  for (auto& l : link) l = {-1, -1};
  auto connect = [&](int e0, int e1) {
    for (int e : {e0, e1}) {
      auto& l = link[e];
      (l[0] < 0 ? l[0] : l[1]) = (e == e0 ? e1 : e0);
    }
  };
  for (int axis = 0; axis < 3; ++axis) {
    const int u = 1 << ((axis + 1) % 3), v = 1 << ((axis + 2) % 3);
    for (int side = 0; side < 2; ++side) {
      const int base = side ? (1 << axis) : 0;
      const int ring[4] = {base, base | u, base | u | v, base | v};  // cyclic around the face
      std::vector<int> crossing;
      for (int i = 0; i < 4; ++i)
        if (inside(ring[i]) != inside(ring[(i + 1) % 4])) crossing.push_back(i);  // face edge i: ring[i]-ring[i+1]
      if (crossing.size() == 2) {
        connect(edge_id(ring[crossing[0]], ring[(crossing[0] + 1) % 4]),
                edge_id(ring[crossing[1]], ring[(crossing[1] + 1) % 4]));
      } else if (crossing.size() == 4) {
        // Ambiguous face: cut each inside corner off by itself (its two face edges form a pair).
        for (int i = 0; i < 4; ++i)
          if (inside(ring[i]))
            connect(edge_id(ring[(i + 3) % 4], ring[i]), edge_id(ring[i], ring[(i + 1) % 4]));
      }
    }
  }
  Case out;
  std::array<bool, 12> used{};
  for (int start = 0; start < 12; ++start) {
    if (used[start] || link[start][0] < 0) continue;
    std::vector<int> loop;
    int prev = -1, cur = start;
    while (!used[cur]) {
      used[cur] = true;
      loop.push_back(cur);
      const int next = link[cur][0] != prev ? link[cur][0] : link[cur][1];
      prev = cur;
      cur = next;
    }
    // Orientation: the loop's normal (Newell, on edge midpoints) must point from inside to outside.
    Eigen::Vector3d normal = Eigen::Vector3d::Zero(), outward = Eigen::Vector3d::Zero();
    for (std::size_t i = 0; i < loop.size(); ++i) {
      const auto& ea = edges()[loop[i]];
      const auto& eb = edges()[loop[(i + 1) % loop.size()]];
      const Eigen::Vector3d p = 0.5 * (corner(ea.a) + corner(ea.b)), q = 0.5 * (corner(eb.a) + corner(eb.b));
      normal += p.cross(q);
      outward += inside(ea.a) ? corner(ea.b) - corner(ea.a) : corner(ea.a) - corner(ea.b);
    }
    if (normal.dot(outward) < 0) std::reverse(loop.begin(), loop.end());
    out.loops.emplace_back(loop.begin(), loop.end());
    for (std::size_t i = 1; i + 1 < loop.size(); ++i)
      out.triangles.push_back({std::uint8_t(loop[0]), std::uint8_t(loop[i]), std::uint8_t(loop[i + 1])});
  }
  return out;
}

}  // namespace

const std::array<Case, 256>& cases() {
  static const std::array<Case, 256> table = [] {
    std::array<Case, 256> t;
    for (int m = 0; m < 256; ++m) t[m] = build_case(m);
    return t;
  }();
  return table;
}

}  // namespace s2c::repair::mc
