#include "volumetric/dual_contouring.h"

#include <unordered_map>

#include <Eigen/Eigenvalues>

#include "s2c/core/check.h"
#include "s2c/core/distance.h"
#include "volumetric/cells.h"

namespace s2c::repair {

namespace {

struct Hermite {
  Eigen::Vector3d point, normal;
};

/// The mean of the crossing points of one sheet.
Eigen::Vector3d mass_point(const std::vector<const Hermite*>& data) {
  Eigen::Vector3d mass = Eigen::Vector3d::Zero();
  for (const auto* d : data) mass += d->point;
  return mass / double(data.size());
}

/// Minimises Σ (n_i·(x − p_i))² around the mass point with small eigenvalues truncated (a flat
/// sheet pins one direction, an edge two, a corner three); the vertex is clamped to its cell.
Eigen::Vector3d place_vertex(const std::vector<const Hermite*>& data, const Eigen::Vector3d& mass,
                             const Eigen::Vector3d& lo, double h) {
  Eigen::Matrix3d A = Eigen::Matrix3d::Zero();
  Eigen::Vector3d b = Eigen::Vector3d::Zero();
  for (const auto* d : data) {
    A += d->normal * d->normal.transpose();
    b += d->normal * d->normal.dot(d->point - mass);
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(A);
  const double top = eig.eigenvalues().maxCoeff();
  Eigen::Vector3d x = mass;
  for (int k = 0; k < 3; ++k) {
    const double ev = eig.eigenvalues()[k];
    if (ev > 0.1 * top && ev > 1e-12) x += eig.eigenvectors().col(k) * (eig.eigenvectors().col(k).dot(b) / ev);
  }
  // A corner or edge just outside the cell belongs to the neighbour's vertex; clamping to the
  // cell keeps this vertex on the sheet's side of it.
  const double slack = 1e-3 * h;
  return x.array().max(lo.array() + slack).min(lo.array() + h - slack).matrix();
}

/// The fallback per cell: where the quadric's vertices make faces intersect (cells at a sharp
/// feature the sampling does not resolve: a thin wall, two edges in one cell), those vertices go
/// back to their mass point (a Marching-Cubes-like vertex), a few rounds, each also relaxing the
/// ring of the vertices relaxed before. What is left is for the caller's check.
void relax_folds(TriangleSoup& out, const std::vector<Eigen::Vector3d>& mass_points) {
  std::vector<char> relaxed(out.vertices.size(), 0);
  for (int round = 0; round < 4; ++round) {
    const auto pairs = self_intersecting_pairs(out);
    if (pairs.empty()) return;
    std::vector<char> bad(out.faces.size(), 0);
    for (const auto& [a, b] : pairs) bad[a] = bad[b] = 1;
    // From the second round on, the faces around what was relaxed already go too.
    if (round > 0)
      for (std::size_t f = 0; f < out.faces.size(); ++f)
        for (int v : out.faces[f])
          if (relaxed[v]) bad[f] = 1;
    for (std::size_t f = 0; f < out.faces.size(); ++f)
      if (bad[f])
        for (int v : out.faces[f]) {
          out.vertices[v] = mass_points[v];
          relaxed[v] = 1;
        }
  }
}

}  // namespace

TriangleSoup dual_contouring(const SparseGrid& grid, const TriangleSoup& surface, const SurfaceQuery& query,
                             Interp interp, VolumetricStats& stats) {
  const double h = grid.voxel();
  const auto& cases = mc::cases();
  const auto& edges = mc::edges();
  // Hermite data per crossing edge, and per cell the vertex of the sheet each local edge is on.
  std::unordered_map<std::uint64_t, Hermite> hermite;
  struct CellVertices {
    std::array<int, 12> of_edge;
  };
  std::unordered_map<std::uint64_t, CellVertices> cells;
  std::vector<std::pair<std::uint64_t, int>> crossing;  // (edge key, axis-direction sign) to emit
  TriangleSoup out;
  std::vector<Eigen::Vector3d> mass_points;  // per vertex: the mean of its sheet's crossing points

  for_each_crossing_cell(grid, [&](const Cell& cell) {
    CellVertices cv;
    cv.of_edge.fill(-1);
    std::vector<const Hermite*> data;
    for (const auto& loop : cases[cell.mask].loops) {
      data.clear();
      for (int e : loop) {
        const auto& edge = edges[e];
        const std::uint64_t key = grid_edge_key(cell.corner(edge.a), edge.axis);
        auto it = hermite.find(key);
        if (it == hermite.end()) {
          Hermite hd;
          Eigen::Vector3d plane_normal = Eigen::Vector3d::Zero();
          hd.point = crossing_point(grid, cell, e, interp, stats, &plane_normal);
          auto hit = query.closest(hd.point, 2 * h);
          // The tangent planes of two closest points model one sharp edge; where a third face or
          // a corner is near, the point they give may stand off the surface (an outside vertex's
          // closest point on a convex edge gives a supporting plane, not a face): DC's vertices
          // then fold. There, the paper's point.
          if (plane_normal.squaredNorm() > 0 && (!hit || hit->distance > 1e-4 * h)) {
            plane_normal.setZero();
            VolumetricStats again;  // this edge is counted already
            hd.point = crossing_point(grid, cell, e, Interp::vector, again);
            hit = query.closest(hd.point, 2 * h);
          }
          // The normal of the tangent plane the crossing point was put on (at a sharp edge the
          // closest face is a tie), else of the face the point is closest to; inside → outside
          // direction along the edge decides its sign when the face is oriented badly.
          Eigen::Vector3d n = Eigen::Vector3d::Unit(edge.axis) * (cell.inside(edge.a) ? 1.0 : -1.0);
          if (plane_normal.squaredNorm() > 0) {
            n = plane_normal;
          } else if (hit) {
            const auto& f = surface.faces[hit->face];
            const Eigen::Vector3d fn = (surface.vertices[f[1]] - surface.vertices[f[0]])
                                           .cross(surface.vertices[f[2]] - surface.vertices[f[0]]);
            if (fn.norm() > 0) n = fn.normalized() * (fn.dot(n) < 0 ? -1.0 : 1.0);
          }
          hd.normal = n;
          it = hermite.emplace(key, hd).first;
          // Each edge is emitted once, from the cell where it is the cell's own lower edge along
          // the two other axes (offset (0,0)).
        }
        data.push_back(&it->second);
      }
      const int vid = static_cast<int>(out.vertices.size());
      mass_points.push_back(mass_point(data));
      out.vertices.push_back(place_vertex(data, mass_points.back(), grid.position(cell.min), h));
      for (int e : loop) cv.of_edge[e] = vid;
    }
    const std::uint64_t ck = grid_edge_key(cell.min, 0);
    cells.emplace(ck, cv);
    // Edges whose lower corner is this cell's corner 0 along the two other axes are local
    // edges 0 (x), 4 (y) and 8 (z): emit them from here once all four cells exist.
    for (int axis = 0; axis < 3; ++axis) {
      const int e = axis * 4;
      if (cv.of_edge[e] >= 0) crossing.emplace_back(grid_edge_key(cell.min, axis), cell.inside(edges[e].a) ? 1 : -1);
    }
  });

  for (const auto& [key, dir] : crossing) {
    const int axis = static_cast<int>(key >> 60);
    const Eigen::Vector3i base(int(key & 0xfffff), int((key >> 20) & 0xfffff), int((key >> 40) & 0xfffff));
    const int u = (axis + 1) % 3, v = (axis + 2) % 3;
    // The four cells around the edge, counter-clockwise seen from +axis: offsets (0,0), (−1,0),
    // (−1,−1), (0,−1) in (u, v); in each, the edge is the local edge at (u, v) = (−du, −dv).
    const int du[4] = {0, -1, -1, 0}, dv[4] = {0, 0, -1, -1};
    int quad[4];
    bool complete = true;
    for (int k = 0; k < 4 && complete; ++k) {
      Eigen::Vector3i cmin = base;
      cmin[u] += du[k];
      cmin[v] += dv[k];
      const auto it = cells.find(grid_edge_key(cmin, 0));
      if (it == cells.end()) {
        complete = false;
        break;
      }
      const int corner = ((-du[k]) << u) | ((-dv[k]) << v);
      int local = -1;
      for (int e = 0; e < 12; ++e)
        if (edges[e].axis == axis && edges[e].a == corner) local = e;
      quad[k] = it->second.of_edge[local];
      complete = quad[k] >= 0;
    }
    if (!complete) continue;
    if (dir < 0) std::swap(quad[1], quad[3]);
    // Split along the shorter diagonal: the flatter pair of triangles.
    const double d02 = (out.vertices[quad[0]] - out.vertices[quad[2]]).squaredNorm();
    const double d13 = (out.vertices[quad[1]] - out.vertices[quad[3]]).squaredNorm();
    if (d02 <= d13) {
      out.faces.push_back({quad[0], quad[1], quad[2]});
      out.faces.push_back({quad[0], quad[2], quad[3]});
    } else {
      out.faces.push_back({quad[0], quad[1], quad[3]});
      out.faces.push_back({quad[1], quad[2], quad[3]});
    }
  }
  relax_folds(out, mass_points);
  stats.triangles = out.faces.size();
  return out;
}

}  // namespace s2c::repair
