#pragma once
// What Marching Cubes and dual contouring share: visiting the complete cells of the sparse band
// (all eight corners in the band) with their inside mask, and the point where a crossing edge
// meets the surface.
#include <array>
#include <cstdint>

#include "s2c/repair/volumetric.h"
#include "volumetric/mc_table.h"
#include "volumetric/sparse_grid.h"

namespace s2c::repair {

struct Cell {
  Eigen::Vector3i min;  ///< global index of corner 0
  int mask = 0;         ///< bit c: corner c inside
  std::array<const SparseGrid::Block*, 8> block;
  std::array<std::int64_t, 8> block_index;  ///< of each corner's block in the grid
  std::array<int, 8> local;

  Eigen::Vector3i corner(int c) const { return min + Eigen::Vector3i(c & 1, (c >> 1) & 1, (c >> 2) & 1); }
  bool inside(int c) const { return (mask >> c) & 1; }
};

/// Calls f(cell) for every complete cell with a sign change that block `bi` owns (whose corner 0
/// is in it).
template <class F>
void for_each_crossing_cell_of_block(const SparseGrid& grid, std::size_t bi, F&& f) {
  constexpr int S = SparseGrid::kSide;
  const Eigen::Vector3i bc = grid.block_coords(bi);
  // The block and its 7 upper neighbours hold every corner of the cells this block owns.
  const SparseGrid::Block* nb[8];
  std::int64_t nbi[8];
  for (int n = 0; n < 8; ++n) {
    nbi[n] = grid.find_index(bc + Eigen::Vector3i(n & 1, (n >> 1) & 1, (n >> 2) & 1));
    nb[n] = nbi[n] < 0 ? nullptr : grid.block_if_kept(static_cast<std::size_t>(nbi[n]));
  }
  for (int li = 0; li < SparseGrid::kCount; ++li) {
    const Eigen::Vector3i l = SparseGrid::local_coords(li);
    Cell cell;
    cell.min = bc * S + l;
    bool complete = true;
    for (int c = 0; c < 8 && complete; ++c) {
      const Eigen::Vector3i q = l + Eigen::Vector3i(c & 1, (c >> 1) & 1, (c >> 2) & 1);
      const int n = (q.x() >= S) | ((q.y() >= S) << 1) | ((q.z() >= S) << 2);
      const SparseGrid::Block* blk = nb[n];
      if (!blk) {
        complete = false;
        break;
      }
      const int qi = SparseGrid::local_index(q);
      complete = blk->flags[qi] & kInBand;
      cell.block[c] = blk;
      cell.block_index[c] = nbi[n];
      cell.local[c] = qi;
      if (blk->flags[qi] & kInside) cell.mask |= 1 << c;
    }
    if (complete && cell.mask != 0 && cell.mask != 255) f(cell);
  }
}

/// Calls f(cell) for every complete cell with a sign change, block by block.
template <class F>
void for_each_crossing_cell(const SparseGrid& grid, F&& f) {
  for (std::size_t bi = 0; bi < grid.block_count(); ++bi) for_each_crossing_cell_of_block(grid, bi, f);
}

/// Key of the grid edge from global vertex `ijk` along `axis` (20 bits per coordinate).
inline std::uint64_t grid_edge_key(const Eigen::Vector3i& ijk, int axis) {
  return std::uint64_t(ijk.x()) | (std::uint64_t(ijk.y()) << 20) | (std::uint64_t(ijk.z()) << 40) |
         (std::uint64_t(axis) << 60);
}

/// Where crossing edge `e` of `cell` meets the surface: the VDF paper's closest point to the
/// segment between the corners' closest surface points, or linear in the signed distance.
Eigen::Vector3d crossing_point(const SparseGrid& grid, const Cell& cell, int e, Interp interp, VolumetricStats& stats,
                               Eigen::Vector3d* normal = nullptr);

}  // namespace s2c::repair
