// The vector field of an oriented point cloud: every vertex of a sparse band around the points
// stores the vector to the implicit moving-least-squares surface (the weighted mean of the
// points' tangent planes, Shen, O'Brien & Shewchuk 2004), and Marching Cubes extracts it with the
// same edge points as the volumetric repair. Vertices with too little data nearby stay out of the
// band, so where the scanner saw nothing no surface is invented: those regions stay holes.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <vector>

#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "s2c/core/clock.h"
#include "s2c/core/errors.h"
#include "s2c/repair/volumetric.h"
#include "volumetric/marching_cubes.h"
#include "volumetric/sparse_grid.h"

namespace s2c::repair {

namespace {

constexpr int S = SparseGrid::kSide;

/// Points sorted by the block their grid cell is in, with each block's range: what the gather
/// reads around a block.
struct BinnedPoints {
  std::vector<std::uint32_t> order;  ///< point indices, grouped by block
  std::vector<std::uint64_t> keys;   ///< block key of each group, ascending
  std::vector<std::uint32_t> begin;  ///< group g is order[begin[g], begin[g+1])

  /// The group of the block at these coordinates, or -1.
  std::int64_t find(const Eigen::Vector3i& block) const {
    const std::uint64_t k = SparseGrid::key(block);
    const auto it = std::lower_bound(keys.begin(), keys.end(), k);
    return it != keys.end() && *it == k ? it - keys.begin() : -1;
  }
};

Eigen::Vector3i cell_of(const Eigen::Vector3d& p, const Eigen::Vector3d& origin, double h) {
  return ((p - origin) / h).array().floor().cast<int>();
}

BinnedPoints bin_points(const std::vector<Eigen::Vector3d>& points, const Eigen::Vector3d& origin, double h) {
  std::vector<std::pair<std::uint64_t, std::uint32_t>> keyed(points.size());
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, points.size(), 4096), [&](const auto& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i)
      keyed[i] = {SparseGrid::key(SparseGrid::block_of(cell_of(points[i], origin, h))), static_cast<std::uint32_t>(i)};
  });
  std::sort(keyed.begin(), keyed.end());
  BinnedPoints b;
  b.order.reserve(keyed.size());
  for (std::size_t i = 0; i < keyed.size(); ++i) {
    if (i == 0 || keyed[i].first != keyed[i - 1].first) {
      b.keys.push_back(keyed[i].first);
      b.begin.push_back(static_cast<std::uint32_t>(i));
    }
    b.order.push_back(keyed[i].second);
  }
  b.begin.push_back(static_cast<std::uint32_t>(keyed.size()));
  return b;
}

/// Every block with a vertex within `radius` of a point: the point blocks and their neighbours
/// (the radius is below one block side), with repeats (SparseGrid::allocate drops them).
std::vector<Eigen::Vector3i> blocks_near_points(const BinnedPoints& bins) {
  std::vector<Eigen::Vector3i> all;
  all.reserve(bins.keys.size() * 8);
  for (const std::uint64_t k : bins.keys) {
    const Eigen::Vector3i b = SparseGrid::block_from_key(k);
    for (int z = -1; z <= 1; ++z)
      for (int y = -1; y <= 1; ++y)
        for (int x = -1; x <= 1; ++x) all.push_back(b + Eigen::Vector3i(x, y, z));
  }
  return all;
}

/// The weighted sums of one block's vertices: Σw, Σw·n·(x − p), Σw·n and Σw·(p − x).
struct BlockSums {
  std::array<float, SparseGrid::kCount> w{}, dist{}, nx{}, ny{}, nz{}, cx{}, cy{}, cz{};
};

void gather_block(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals,
                  const BinnedPoints& bins, const SparseGrid& grid, const Eigen::Vector3i& bc, double radius,
                  BlockSums& sums) {
  const double h = grid.voxel(), r2 = radius * radius;
  const Eigen::Vector3d origin = grid.position(Eigen::Vector3i::Zero());
  const Eigen::Vector3i lo_block = bc * S, hi_block = lo_block + Eigen::Vector3i::Constant(S - 1);
  for (int z = -1; z <= 1; ++z)
    for (int y = -1; y <= 1; ++y)
      for (int x = -1; x <= 1; ++x) {
        const std::int64_t g = bins.find(bc + Eigen::Vector3i(x, y, z));
        if (g < 0) continue;
        for (std::uint32_t o = bins.begin[g]; o < bins.begin[g + 1]; ++o) {
          const std::uint32_t i = bins.order[o];
          const Eigen::Vector3d& p = points[i];
          const Eigen::Vector3d& n = normals[i];
          const Eigen::Vector3i lo = ((p.array() - radius - origin.array()) / h).ceil().cast<int>().max(lo_block.array());
          const Eigen::Vector3i hi = ((p.array() + radius - origin.array()) / h).floor().cast<int>().min(hi_block.array());
          for (int vz = lo.z(); vz <= hi.z(); ++vz)
            for (int vy = lo.y(); vy <= hi.y(); ++vy)
              for (int vx = lo.x(); vx <= hi.x(); ++vx) {
                const Eigen::Vector3i v(vx, vy, vz);
                const Eigen::Vector3d d = grid.position(v) - p;
                const double d2 = d.squaredNorm();
                if (d2 >= r2) continue;
                // Wendland-like compact weight: smooth, no exp, zero at the radius.
                const double t = 1.0 - d2 / r2, w = t * t * t * t;
                const int li = SparseGrid::local_index(v);
                sums.w[li] += static_cast<float>(w);
                sums.dist[li] += static_cast<float>(w * n.dot(d));
                sums.nx[li] += static_cast<float>(w * n.x());
                sums.ny[li] += static_cast<float>(w * n.y());
                sums.nz[li] += static_cast<float>(w * n.z());
                sums.cx[li] -= static_cast<float>(w * d.x());
                sums.cy[li] -= static_cast<float>(w * d.y());
                sums.cz[li] -= static_cast<float>(w * d.z());
              }
        }
      }
}

/// The support the vertex's closest surface point has, estimated from the vertex's own: over a
/// plane sampled evenly, the sum of (1 − d²/r²)⁴ at height f is (1 − f²/r²)⁵ times the sum at the
/// plane. Whether a vertex belongs to the band must not depend on its height: the corners of a
/// cell the surface crosses lie up to √3 voxels off it, where a vertex's own sum is a few percent
/// of the surface's, and cutting there would punch holes wherever the surface runs diagonally.
double support_at_surface(double w, double f, double radius) {
  const double t = std::max(1.0 - f * f / (radius * radius), 0.0);
  const double t2 = t * t;
  return w / std::max(t2 * t2 * t, 1e-4);
}

}  // namespace

TriangleSoup contour_oriented_points(const std::vector<Eigen::Vector3d>& points,
                                     const std::vector<Eigen::Vector3d>& normals, const PointContourOptions& options,
                                     VolumetricStats* stats_out) {
  if (points.empty() || points.size() != normals.size())
    throw InvalidInput("point contouring: needs at least one point and one normal per point");
  const double h = options.voxel;
  if (!(h > 0)) throw InvalidInput("point contouring: the voxel must be positive");
  const double radius = options.radius > 0 ? options.radius : 2.0 * h;
  if (radius >= S * h) throw InvalidInput(fmt::format("point contouring: the support radius {:.3g} mm must stay below "
                                                      "{} voxels", radius, S));
  Eigen::Vector3d lo = points[0], hi = points[0];
  for (const auto& p : points) {
    if (!p.allFinite()) throw InvalidInput("point contouring: a point is not finite");
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  if ((hi - lo).maxCoeff() / h + 2 * S > (1 << 20) - 16)
    throw ProcessingError(fmt::format("point contouring: voxel {:.3g} mm is far too small for a {:.3g} mm cloud", h,
                                      (hi - lo).maxCoeff()));
  VolumetricStats stats;
  stats.voxel = h;
  stats.attempts = 1;
  stats.band = radius / h;
  auto t0 = std::chrono::steady_clock::now();
  // An odd fraction of a voxel off the data: grid planes through flat regions of round
  // coordinates would put vertices exactly on the surface.
  const Eigen::Vector3d origin = lo - Eigen::Vector3d::Constant((std::ceil(radius / h) + 2 + 0.3719) * h);
  // The stored vector is −f·n̄ with |f| below the radius; twice it leaves room for rounding.
  SparseGrid grid(origin, h, 2.0 * radius);
  const BinnedPoints bins = bin_points(points, origin, h);
  grid.allocate(blocks_near_points(bins));
  const double min_support = options.min_support, max_offset = options.max_offset * radius;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, grid.block_count(), 4), [&](const auto& range) {
    BlockSums sums;
    for (std::size_t bi = range.begin(); bi < range.end(); ++bi) {
      sums = BlockSums{};
      gather_block(points, normals, bins, grid, grid.block_coords(bi), radius, sums);
      SparseGrid::Block& block = grid.block(bi);
      for (int li = 0; li < SparseGrid::kCount; ++li) {
        const double w = sums.w[li];
        if (!(w > 0)) continue;
        const Eigen::Vector3d nsum(sums.nx[li], sums.ny[li], sums.nz[li]);
        // Normals that cancel (the two sides of a wall thinner than the radius) give no sign.
        if (nsum.norm() < 0.5 * w) continue;
        const double f = sums.dist[li] / w;
        if (!(support_at_surface(w, f, radius) >= min_support)) continue;
        // The surface point must lie among its points, not beyond them (Adamson & Alexa's domain
        // of a point-set surface): past a rim of the data, or past a convex edge along one
        // face's plane, the weighted centroid of the points stays behind while the projection
        // goes on — a fin the data does not support.
        const Eigen::Vector3d n = nsum.normalized();
        const Eigen::Vector3d offset = Eigen::Vector3d(sums.cx[li], sums.cy[li], sums.cz[li]) / w + f * n;
        if ((offset - offset.dot(n) * n).norm() > max_offset) continue;
        grid.set_vector(block, li, -f * n);
        block.flags[li] = kInBand | (f < 0 ? kInside : 0);
      }
    }
  });
  for (std::size_t bi = 0; bi < grid.block_count(); ++bi)
    for (const auto f : grid.block(bi).flags) stats.band_vertices += (f & kInBand) != 0;
  stats.blocks = grid.block_count();
  stats.bytes = grid.bytes();
  stats.seconds_field = seconds_since(t0);
  t0 = std::chrono::steady_clock::now();
  TriangleSoup out = marching_cubes(std::move(grid), options.interp, stats);
  stats.seconds_extract = seconds_since(t0);
  if (stats_out) *stats_out = stats;
  return out;
}

}  // namespace s2c::repair
