// Implementation of the shared test helpers, linked into every test executable.
#include <cmath>
#include <map>
#include <random>

#include "test_util.h"

namespace s2c::test {

TriangleSoup grid(int n, const std::function<bool(int, int)>& keep,
                  const std::function<Eigen::Vector3d(double, double)>& place) {
  TriangleSoup s;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; j <= n; ++j) s.vertices.push_back(place ? place(i, j) : Eigen::Vector3d(i, j, 0));
  auto v = [n](int i, int j) { return i * (n + 1) + j; };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      if (!keep(i, j)) continue;
      s.faces.push_back({v(i, j), v(i + 1, j), v(i + 1, j + 1)});
      s.faces.push_back({v(i, j), v(i + 1, j + 1), v(i, j + 1)});
    }
  return s;
}

TriangleSoup icosphere(const Eigen::Vector3d& center, double radius, int levels) {
  TriangleSoup s;
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                       {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                                       {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    auto midpoint = [&](int a, int b) {
      auto key = std::minmax(a, b);
      auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      g.push_back({tri[0], a, c});
      g.push_back({tri[1], b, a});
      g.push_back({tri[2], c, b});
      g.push_back({a, b, c});
    }
    f.swap(g);
  }
  for (auto& p : v) s.vertices.push_back(center + radius * p);
  s.faces = f;
  return s;
}

TriangleSoup revolved(const std::function<double(double)>& r, const std::vector<double>& zs, int segments,
                      bool close_bottom, bool close_top) {
  TriangleSoup s;
  const int rows = static_cast<int>(zs.size());
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < segments; ++i) {
      const double a = 2 * M_PI * i / segments + (j % 2) * M_PI / segments;
      s.vertices.push_back({r(zs[j]) * std::cos(a), r(zs[j]) * std::sin(a), zs[j]});
    }
  const auto id = [&](int i, int j) { return j * segments + (i % segments); };
  for (int j = 0; j + 1 < rows; ++j)
    for (int i = 0; i < segments; ++i) {
      if (j % 2 == 0) {
        s.faces.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
        s.faces.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      } else {
        s.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        s.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      }
    }
  const int bottom = static_cast<int>(s.vertices.size()), top = bottom + (close_bottom ? 1 : 0);
  if (close_bottom) s.vertices.push_back({0, 0, zs.front()});
  if (close_top) s.vertices.push_back({0, 0, zs.back()});
  for (int i = 0; i < segments; ++i) {
    if (close_bottom) s.faces.push_back({bottom, id(i + 1, 0), id(i, 0)});
    if (close_top) s.faces.push_back({top, id(i, rows - 1), id(i + 1, rows - 1)});
  }
  return s;
}

OrientedSamples sample_surface(const TriangleSoup& soup, double spacing, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> noise(0, sigma > 0 ? sigma : 1);
  OrientedSamples o;
  for (const auto& f : soup.faces) {
    const Eigen::Vector3d a = soup.vertices[f[0]], b = soup.vertices[f[1]], c = soup.vertices[f[2]];
    const Eigen::Vector3d cr = (b - a).cross(c - a);
    const Eigen::Vector3d n = cr.normalized();
    const double expected = 0.5 * cr.norm() / (spacing * spacing);
    int count = static_cast<int>(expected);
    if (u(rng) < expected - count) ++count;
    for (int k = 0; k < count; ++k) {
      double r1 = u(rng), r2 = u(rng);
      if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
      o.points.push_back(a + r1 * (b - a) + r2 * (c - a) + (sigma > 0 ? noise(rng) : 0.0) * n);
      o.normals.push_back(n);
    }
  }
  return o;
}

}  // namespace s2c::test
