#include "volumetric/marching_cubes.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <vector>

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

bool tangent_plane_edge_parameter(const Eigen::Vector3d& v1, const Eigen::Vector3d& v2, const Eigen::Vector3d& a,
                                  const Eigen::Vector3d& na, const Eigen::Vector3d& b, const Eigen::Vector3d& nb,
                                  bool v1_inside, double& lambda, int* plane) {
  // f(x) = (x − P)·n ≤ 0 inside the half-space of a tangent plane; along the edge it is linear.
  auto side = [](const Eigen::Vector3d& x, const Eigen::Vector3d& p, const Eigen::Vector3d& n) { return (x - p).dot(n); };
  const double scale = (v2 - v1).norm();
  const double ab = side(b, a, na), ba = side(a, b, nb);
  // Coplanar (A's plane through B and B's through A): the paper's λ is exact already. Mixed signs
  // (a curved surface or a corner of more than two planes): no two-plane model fits.
  const double eps = 1e-6 * scale;
  // One of them may lie on the other's plane: the closest point of an outside vertex beside a
  // convex edge is on the edge itself.
  const bool convex = ab < eps && ba < eps && (ab < -eps || ba < -eps);
  const bool concave = ab > -eps && ba > -eps && (ab > eps || ba > eps);
  if (!convex && !concave) return false;
  // Walk from the inside end to the outside end; each plane's exit parameter along that walk.
  const Eigen::Vector3d& from = v1_inside ? v1 : v2;
  const Eigen::Vector3d& to = v1_inside ? v2 : v1;
  const double inf = std::numeric_limits<double>::infinity();
  auto exit_of = [&](const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
    const double f0 = side(from, p, n), f1 = side(to, p, n);
    if (f0 <= 0 && f1 <= 0) return inf;   // never leaves this half-space
    if (f0 > 0 && f1 > 0) return -inf;    // never in it
    if (f0 > 0) return std::nan("");      // enters it: the walk would go out → in
    return f0 / (f0 - f1);
  };
  const double ta = exit_of(a, na), tb = exit_of(b, nb);
  if (std::isnan(ta) || std::isnan(tb)) return false;
  // A convex edge is the intersection of the half-spaces (the walk leaves at the first exit), a
  // concave one their union (at the last).
  const double t = convex ? std::min(ta, tb) : std::max(ta, tb);
  if (!(t >= 0.0 && t <= 1.0)) return false;
  lambda = v1_inside ? t : 1.0 - t;
  if (plane) *plane = t == ta ? 0 : 1;
  return true;
}

Eigen::Vector3d crossing_point(const SparseGrid& grid, const Cell& cell, int e, Interp interp, VolumetricStats& stats,
                               Eigen::Vector3d* normal) {
  const auto& edge = mc::edges()[e];
  const Eigen::Vector3d pa = grid.position(cell.corner(edge.a)), pb = grid.position(cell.corner(edge.b));
  const Eigen::Vector3d va = grid.vector(*cell.block[edge.a], cell.local[edge.a]);
  const Eigen::Vector3d vb = grid.vector(*cell.block[edge.b], cell.local[edge.b]);
  const std::uint8_t fa = cell.block[edge.a]->flags[cell.local[edge.a]];
  const std::uint8_t fb = cell.block[edge.b]->flags[cell.local[edge.b]];
  const bool shell_a = fa & kShell, shell_b = fb & kShell;
  // Signed distance to the surface the sign describes: the input surface, or the offset surface
  // of the shell fallback.
  auto value = [&](std::uint8_t f, const Eigen::Vector3d& v, bool inside) {
    if (f & kShell) return ((f & kDeep) ? -v.norm() : v.norm()) - grid.shell();
    return inside ? -v.norm() : v.norm();
  };
  const double sa = value(fa, va, cell.inside(edge.a)), sb = value(fb, vb, cell.inside(edge.b));
  // The scalar baseline: linear in the signed distance (both ends on the surface: midpoint).
  double lambda = sa != sb ? sa / (sa - sb) : 0.5;
  if (interp != Interp::linear && !shell_a && !shell_b) {
    double lv;
    if (vector_edge_parameter(pa, pb, pa + va, pb + vb, lv)) {
      if (lv <= 0 || lv >= 1) ++stats.clamped_edges;
      lambda = lv;
    } else {
      ++stats.clamped_edges;  // edge parallel to AB: no unique closest point, keep the linear one
    }
    // Beyond the paper: where A and B lie on two different planes (a sharp edge of the input
    // between the cube edge's ends), segment AB cuts the corner and so does λ; the crossing of
    // the cube edge with the two tangent planes is on the surface. The outward normal at a
    // closest point is ±v/|v| (v points outward from an inside vertex).
    const double la = va.norm(), lb = vb.norm();
    if (interp == Interp::hermite && la > 0 && lb > 0) {
      const bool in_a = cell.inside(edge.a), in_b = cell.inside(edge.b);
      const Eigen::Vector3d na = (in_a ? 1.0 : -1.0) * va / la, nb = (in_b ? 1.0 : -1.0) * vb / lb;
      double lt;
      int plane;
      if (in_a != in_b && tangent_plane_edge_parameter(pa, pb, pa + va, na, pb + vb, nb, in_a, lt, &plane)) {
        lambda = lt;
        if (normal) *normal = plane == 0 ? na : nb;
      }
    }
  }
  // Keep vertices off the grid nodes: a vertex on a node would be touched by several edges'
  // triangles without being the same vertex (touching faces, zero-area triangles).
  lambda = std::clamp(lambda, 1e-3, 1 - 1e-3);
  return pa + lambda * (pb - pa);
}

namespace {

/// Whether two cube edges lie on a common face of the cube.
bool share_face(int e0, int e1) {
  static const auto table = [] {
    std::array<std::array<bool, 12>, 12> t{};
    const auto& edges = mc::edges();
    for (int i = 0; i < 12; ++i)
      for (int j = 0; j < 12; ++j)
        for (int axis = 0; axis < 3; ++axis) {
          const int bit = 1 << axis, v = edges[i].a & bit;
          if ((edges[i].b & bit) == v && (edges[j].a & bit) == v && (edges[j].b & bit) == v) t[i][j] = true;
        }
    return t;
  }();
  return table[e0][e1];
}

/// Fans a loop of edge points from the root that keeps every triangle facing the loop's own
/// normal (a fan from a fixed corner folds over when the points sit near the cube's corners).
/// A diagonal between two points on the same cube face would lie in that face, where the
/// neighbouring cell draws its own segment: such roots are not used. When no root is left, the
/// loop is fanned from its centroid, which is added as a vertex.
void triangulate_loop(TriangleSoup& out, const std::vector<int>& ids, const std::vector<std::uint8_t>& loop) {
  const std::size_t n = ids.size();
  auto P = [&](std::size_t i) -> const Eigen::Vector3d& { return out.vertices[ids[i % n]]; };
  if (n == 3) {
    out.faces.push_back({ids[0], ids[1], ids[2]});
    return;
  }
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) normal += P(i).cross(P(i + 1));
  int best_root = -1;
  double best = 0;
  for (std::size_t r = 0; r < n; ++r) {
    bool in_face = false;
    for (std::size_t i = 2; i + 1 < n && !in_face; ++i) in_face = share_face(loop[r], loop[(r + i) % n]);
    if (in_face) continue;
    double worst = 1e300;
    for (std::size_t i = 1; i + 1 < n; ++i) {
      const Eigen::Vector3d t = (P(r + i) - P(r)).cross(P(r + i + 1) - P(r));
      const double len = t.norm();
      worst = std::min(worst, len > 0 ? t.dot(normal) / len : -1.0);
    }
    if (worst > best) {
      best = worst;
      best_root = static_cast<int>(r);
    }
  }
  if (best_root >= 0) {
    for (std::size_t i = 1; i + 1 < n; ++i)
      out.faces.push_back({ids[best_root], ids[(best_root + i) % n], ids[(best_root + i + 1) % n]});
    return;
  }
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) c += P(i);
  const int ci = static_cast<int>(out.vertices.size());
  out.vertices.push_back(c / double(n));
  for (std::size_t i = 0; i < n; ++i) out.faces.push_back({ci, ids[i], ids[(i + 1) % n]});
}

}  // namespace

TriangleSoup marching_cubes(SparseGrid&& grid, Interp interp, VolumetricStats& stats) {
  TriangleSoup out;
  const auto& cases = mc::cases();
  // Blocks come sorted by z (SparseGrid::allocate). A block at z is read by the cells of the
  // blocks at z − 1 and z, and an edge's vertex is filed under the block of its lower corner,
  // which lies in the owner's z-slab or the next: two slabs of blocks and of edge vertices are
  // all that is live.
  constexpr int N = SparseGrid::kCount;
  using EdgeIds = std::array<int, 3 * N>;  // vertex of the +x, +y, +z edge of each block vertex
  std::vector<std::unique_ptr<EdgeIds>> edge_ids(grid.block_count());
  std::vector<std::size_t> done;  // blocks of the slab the sweep has left, freed when it moves on
  int slab = std::numeric_limits<int>::min();
  std::vector<int> ids;
  for (std::size_t bi = 0; bi < grid.block_count(); ++bi) {
    const int z = grid.block_coords(bi).z();
    if (z != slab) {
      for (std::size_t b : done) {
        grid.release(b);
        edge_ids[b].reset();
      }
      done.clear();
      slab = z;
    }
    for_each_crossing_cell_of_block(grid, bi, [&](const Cell& cell) {
      for (const auto& loop : cases[cell.mask].loops) {
        ids.clear();
        for (int e : loop) {
          const auto& edge = mc::edges()[e];
          auto& table = edge_ids[static_cast<std::size_t>(cell.block_index[edge.a])];
          if (!table) {
            table = std::make_unique<EdgeIds>();
            table->fill(-1);
          }
          int& id = (*table)[edge.axis * N + cell.local[edge.a]];
          if (id < 0) {
            id = static_cast<int>(out.vertices.size());
            out.vertices.push_back(crossing_point(grid, cell, e, interp, stats));
          }
          ids.push_back(id);
        }
        triangulate_loop(out, ids, loop);
      }
    });
    done.push_back(bi);
  }
  stats.triangles = out.faces.size();
  return out;
}

}  // namespace s2c::repair
