#include "volumetric/marching_cubes.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include "volumetric/cells.h"
#include "volumetric/mc_table.h"

namespace s2c::repair {

bool vector_edge_parameter(const Eigen::Vector3d& v1, const Eigen::Vector3d& v2, const Eigen::Vector3d& a,
                           const Eigen::Vector3d& b, double& lambda) {
  // Closest points of the lines V1 + λu and A + tv (the paper's dot-product formula). The paper
  // prints the numerator with the opposite sign; with u = V1V2, v = AB, w = V1A = A − V1 the
  // parameter of the closest point on V1V2 is ((v·v)(u·w) − (u·v)(v·w)) / ((u·u)(v·v) − (u·v)²).
  const Eigen::Vector3d u = v2 - v1, v = b - a, w = a - v1;
  const double uu = u.dot(u), vv = v.dot(v), uv = u.dot(v), uw = u.dot(w), vw = v.dot(w);
  const double denom = uu * vv - uv * uv;
  if (!(denom > 1e-12 * uu * vv)) return false;
  double t = (uv * uw - uu * vw) / denom;  // parameter on AB
  double s = (vv * uw - uv * vw) / denom;
  // AB is a segment: when its closest point falls outside it, clamp and re-project onto the edge.
  if (t < 0 || t > 1) {
    t = std::clamp(t, 0.0, 1.0);
    s = (w + t * v).dot(u) / uu;
  }
  lambda = std::clamp(s, 0.0, 1.0);
  return true;
}

Eigen::Vector3d crossing_point(const SparseGrid& grid, const Cell& cell, int e, Interp interp, VolumetricStats& stats) {
  const auto& edge = mc::edges()[e];
  const Eigen::Vector3d pa = grid.position(cell.corner(edge.a)), pb = grid.position(cell.corner(edge.b));
  const Eigen::Vector3d va = grid.vector(*cell.block[edge.a], cell.local[edge.a]);
  const Eigen::Vector3d vb = grid.vector(*cell.block[edge.b], cell.local[edge.b]);
  const bool shell_a = cell.block[edge.a]->flags[cell.local[edge.a]] & kShell;
  const bool shell_b = cell.block[edge.b]->flags[cell.local[edge.b]] & kShell;
  // Signed distance to the surface the sign describes: the input surface, or the offset surface
  // for vertices classified by the shell rule.
  const double sa = shell_a ? va.norm() - grid.shell() : cell.inside(edge.a) ? -va.norm() : va.norm();
  const double sb = shell_b ? vb.norm() - grid.shell() : cell.inside(edge.b) ? -vb.norm() : vb.norm();
  // The scalar baseline: linear in the signed distance (both ends on the surface: midpoint).
  double lambda = sa != sb ? sa / (sa - sb) : 0.5;
  if (interp == Interp::vector && !shell_a && !shell_b) {
    double lv;
    if (vector_edge_parameter(pa, pb, pa + va, pb + vb, lv)) {
      if (lv <= 0 || lv >= 1) ++stats.clamped_edges;
      lambda = lv;
    } else {
      ++stats.clamped_edges;  // edge parallel to AB: no unique closest point, keep the linear one
    }
  }
  // Keep vertices off the grid nodes: a vertex on a node would be touched by several edges'
  // triangles without being the same vertex (touching faces, zero-area triangles).
  lambda = std::clamp(lambda, 1e-3, 1 - 1e-3);
  return pa + lambda * (pb - pa);
}

TriangleSoup marching_cubes(const SparseGrid& grid, Interp interp, VolumetricStats& stats) {
  TriangleSoup out;
  std::unordered_map<std::uint64_t, int> edge_vertex;
  edge_vertex.reserve(stats.band_vertices / 2 + 16);
  const auto& cases = mc::cases();
  for_each_crossing_cell(grid, [&](const Cell& cell) {
    int ids[12];
    for (const auto& tri : cases[cell.mask].triangles) {
      for (int k = 0; k < 3; ++k) {
        const int e = tri[k];
        const auto& edge = mc::edges()[e];
        const auto [it, inserted] =
            edge_vertex.emplace(grid_edge_key(cell.corner(edge.a), edge.axis), static_cast<int>(out.vertices.size()));
        ids[e] = it->second;
        if (inserted) out.vertices.push_back(crossing_point(grid, cell, e, interp, stats));
      }
      out.faces.push_back({ids[tri[0]], ids[tri[1]], ids[tri[2]]});
    }
  });
  stats.triangles = out.faces.size();
  return out;
}

}  // namespace s2c::repair
