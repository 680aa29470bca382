// The defect report: check_mesh's exact counts plus the classes only repair cares about.
#include "s2c/repair/defects.h"

#include <algorithm>
#include <cmath>
#include <unordered_set>

#include <nlohmann/json.hpp>

#include "s2c/core/distance.h"
#include "soup_topology.h"

namespace s2c::repair {

namespace {

struct EdgeGrid {
  double cell;
  std::unordered_map<std::uint64_t, std::vector<int>> cells;
  static std::uint64_t key(long x, long y, long z) {
    return (std::uint64_t(x & 0x1fffff)) | (std::uint64_t(y & 0x1fffff) << 21) | (std::uint64_t(z & 0x1fffff) << 42);
  }
};

/// Boundary vertices that lie within `tol` of a boundary edge they are not an end of, and whose
/// nearest such edge is not one of their own two neighbours' edges: sides of a crack or seam.
std::size_t count_gap_vertices(const TriangleSoup& s, const std::vector<std::pair<int, int>>& boundary, double tol) {
  if (boundary.empty() || !(tol > 0)) return 0;
  EdgeGrid grid{tol, {}};
  auto cell_of = [&](const Eigen::Vector3d& p) {
    return Eigen::Vector3i((p / tol).array().floor().cast<int>());
  };
  for (std::size_t i = 0; i < boundary.size(); ++i) {
    const Eigen::Vector3d a = s.vertices[boundary[i].first], b = s.vertices[boundary[i].second];
    const Eigen::Vector3i lo = cell_of(a.cwiseMin(b)), hi = cell_of(a.cwiseMax(b));
    if ((hi - lo).maxCoeff() > 64) continue;  // an edge far longer than the tolerance: not a crack side
    for (int z = lo.z(); z <= hi.z(); ++z)
      for (int y = lo.y(); y <= hi.y(); ++y)
        for (int x = lo.x(); x <= hi.x(); ++x) grid.cells[EdgeGrid::key(x, y, z)].push_back(static_cast<int>(i));
  }
  std::unordered_map<int, std::vector<int>> neighbours;  // boundary vertex → its boundary neighbours
  for (const auto& [a, b] : boundary) {
    neighbours[a].push_back(b);
    neighbours[b].push_back(a);
  }
  std::size_t gaps = 0;
  for (const auto& [v, nbrs] : neighbours) {
    const Eigen::Vector3d p = s.vertices[v];
    const Eigen::Vector3i c = cell_of(p);
    bool near = false;
    for (int dz = -1; dz <= 1 && !near; ++dz)
      for (int dy = -1; dy <= 1 && !near; ++dy)
        for (int dx = -1; dx <= 1 && !near; ++dx) {
          const auto it = grid.cells.find(EdgeGrid::key(c.x() + dx, c.y() + dy, c.z() + dz));
          if (it == grid.cells.end()) continue;
          for (int ei : it->second) {
            const auto [a, b] = boundary[ei];
            if (a == v || b == v) continue;
            if (std::find(nbrs.begin(), nbrs.end(), a) != nbrs.end() || std::find(nbrs.begin(), nbrs.end(), b) != nbrs.end())
              continue;
            const Eigen::Vector3d pa = s.vertices[a], ab = s.vertices[b] - pa;
            const double t = std::clamp((p - pa).dot(ab) / std::max(ab.squaredNorm(), 1e-300), 0.0, 1.0);
            if ((pa + t * ab - p).norm() <= tol) {
              near = true;
              break;
            }
          }
        }
    gaps += near;
  }
  return gaps;
}

}  // namespace

DefectReport find_defects(const TriangleSoup& soup, bool self_intersections) {
  DefectReport r;
  CheckOptions co;
  co.self_intersections = self_intersections;
  r.check = check_mesh(soup, co);
  for (std::size_t fi = 0; fi < soup.faces.size(); ++fi) {
    if (zero_area(soup, static_cast<int>(fi))) {
      ++r.zero_area_faces;
      continue;
    }
    const auto& f = soup.faces[fi];
    double len[3], lo = 1e300, hi = 0;
    for (int k = 0; k < 3; ++k) {
      len[k] = (soup.vertices[f[(k + 1) % 3]] - soup.vertices[f[k]]).norm();
      lo = std::min(lo, len[k]);
      hi = std::max(hi, len[k]);
    }
    if (lo < 0.01 * hi) {
      ++r.needles;
      continue;
    }
    for (int k = 0; k < 3; ++k) {  // angle opposite edge k by the law of cosines
      const double a = len[k], b = len[(k + 1) % 3], c = len[(k + 2) % 3];
      if ((b * b + c * c - a * a) / (2 * b * c) < std::cos(177.0 * M_PI / 180)) {
        ++r.caps;
        break;
      }
    }
  }
  const auto edges = edge_faces(soup);
  std::vector<std::pair<int, int>> boundary;
  double boundary_len = 0;
  for (const auto& [key, faces] : edges) {
    if (faces.size() != 1) continue;
    const int a = int(key >> 32), b = int(key & 0xffffffffu);
    boundary.emplace_back(a, b);
    boundary_len += (soup.vertices[a] - soup.vertices[b]).norm();
  }
  int count = 0;
  const std::vector<int> comp = face_components(soup, count);
  if (count > 1) {
    const std::vector<char> tiny = tiny_open_components(soup, comp, count);
    r.tiny_components = static_cast<std::size_t>(std::count(tiny.begin(), tiny.end(), 1));
  }
  r.gap_tolerance = boundary.empty() ? 0 : 0.5 * boundary_len / double(boundary.size());
  r.gaps = count_gap_vertices(soup, boundary, r.gap_tolerance);
  return r;
}

nlohmann::json to_json(const DefectReport& r) {
  nlohmann::json j = nlohmann::json::parse(s2c::to_json(r.check));
  j["zero_area_faces"] = r.zero_area_faces;
  j["needles"] = r.needles;
  j["caps"] = r.caps;
  j["tiny_components"] = r.tiny_components;
  j["gap_vertices"] = r.gaps;
  j["gap_tolerance_mm"] = r.gap_tolerance;
  return j;
}

}  // namespace s2c::repair
