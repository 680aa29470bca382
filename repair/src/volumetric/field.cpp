#include "volumetric/field.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <unordered_map>
#include <utility>

#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "s2c/core/disjoint_sets.h"
#include "s2c/core/distance.h"
#include "volumetric/winding.h"

namespace s2c::repair {

namespace {

std::vector<Eigen::Vector3i> blocks_near_surface(const TriangleSoup& soup, double radius, const SparseGrid& grid) {
  const double h = grid.voxel();
  const Eigen::Vector3d origin = grid.position(Eigen::Vector3i::Zero());
  const double block_len = h * SparseGrid::kSide;
  // A block owns vertices [8b, 8b+7]: its centre and the radius of the sphere around its vertices.
  const double half_diag = 0.5 * std::sqrt(3.0) * h * (SparseGrid::kSide - 1);
  tbb::enumerable_thread_specific<std::vector<Eigen::Vector3i>> found;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, soup.faces.size(), 256), [&](const auto& range) {
    auto& out = found.local();
    for (std::size_t fi = range.begin(); fi != range.end(); ++fi) {
      const auto& f = soup.faces[fi];
      const Eigen::Vector3d &a = soup.vertices[f[0]], &b = soup.vertices[f[1]], &c = soup.vertices[f[2]];
      const Eigen::Vector3d lo = a.cwiseMin(b).cwiseMin(c).array() - radius, hi = a.cwiseMax(b).cwiseMax(c).array() + radius;
      const Eigen::Vector3i blo = ((lo - origin) / block_len).array().floor().cast<int>();
      const Eigen::Vector3i bhi = ((hi - origin) / block_len).array().floor().cast<int>();
      const bool small = (bhi - blo).maxCoeff() <= 1;
      for (int z = blo.z(); z <= bhi.z(); ++z)
        for (int y = blo.y(); y <= bhi.y(); ++y)
          for (int x = blo.x(); x <= bhi.x(); ++x) {
            const Eigen::Vector3i bc(x, y, z);
            if (!small) {  // long triangles: skip blocks of their box that they do not come near
              const Eigen::Vector3d centre = origin + block_len * bc.cast<double>() +
                                             Eigen::Vector3d::Constant(0.5 * h * (SparseGrid::kSide - 1));
              if ((closest_point_on_triangle(centre, a, b, c) - centre).norm() > radius + half_diag) continue;
            }
            out.push_back(bc);
          }
    }
  });
  std::vector<Eigen::Vector3i> all;
  for (auto& v : found) all.insert(all.end(), v.begin(), v.end());
  return all;
}

/// Angle-weighted pseudonormals (Bærentzen & Aanæs 2005): the sign of (p − q)·n at the closest
/// point q is exact for a closed manifold when n is the face normal inside a face, the sum of the
/// two face normals on an edge, and the angle-weighted vertex normal at a vertex.
struct Pseudonormals {
  std::vector<Eigen::Vector3d> face, vertex;
  std::unordered_map<std::uint64_t, Eigen::Vector3d> edge;

  static std::uint64_t edge_key(int a, int b) { return undirected_edge_key(a, b); }

  explicit Pseudonormals(const TriangleSoup& s) : face(s.faces.size()), vertex(s.vertices.size(), Eigen::Vector3d::Zero()) {
    for (std::size_t i = 0; i < s.faces.size(); ++i) {
      const auto& f = s.faces[i];
      Eigen::Vector3d n = (s.vertices[f[1]] - s.vertices[f[0]]).cross(s.vertices[f[2]] - s.vertices[f[0]]);
      const double len = n.norm();
      face[i] = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d u = s.vertices[f[(k + 1) % 3]] - s.vertices[f[k]];
        const Eigen::Vector3d v = s.vertices[f[(k + 2) % 3]] - s.vertices[f[k]];
        const double nu = u.norm(), nv = v.norm();
        if (nu > 0 && nv > 0) vertex[f[k]] += std::acos(std::clamp(u.dot(v) / (nu * nv), -1.0, 1.0)) * face[i];
        edge.try_emplace(edge_key(f[k], f[(k + 1) % 3]), Eigen::Vector3d::Zero()).first->second += face[i];
      }
    }
  }

  /// The pseudonormal at point q of face fi.
  Eigen::Vector3d at(const TriangleSoup& s, int fi, const Eigen::Vector3d& q) const {
    const auto& f = s.faces[fi];
    const Eigen::Vector3d a = s.vertices[f[0]], b = s.vertices[f[1]], c = s.vertices[f[2]];
    const Eigen::Vector3d n = (b - a).cross(c - a);
    const double area2 = n.squaredNorm();
    if (!(area2 > 0)) return face[fi];
    // Barycentric coordinates of q; a coordinate ~0 puts q on the opposite edge.
    const double wa = (b - q).cross(c - q).dot(n) / area2, wb = (c - q).cross(a - q).dot(n) / area2;
    const double w[3] = {wa, wb, 1 - wa - wb};
    const double eps = 1e-9;
    int zeros = 0, nonzero = -1, zero = -1;
    for (int k = 0; k < 3; ++k) {
      if (w[k] <= eps) {
        ++zeros;
        zero = k;
      } else {
        nonzero = k;
      }
    }
    if (zeros >= 2) return vertex[f[nonzero]];
    if (zeros == 1) {
      const auto it = edge.find(edge_key(f[(zero + 1) % 3], f[(zero + 2) % 3]));
      if (it != edge.end()) return it->second;
    }
    return face[fi];
  }
};

/// The closest point within `radius` for every vertex of block `bi`, from a short list of faces
/// (CAD meshes, coarse scans): each face visits only the vertices inside its box grown by the
/// radius, and skips those farther from its plane than the best distance so far. Faces are tried
/// in list order and the last one at the smallest distance wins, as a plain loop would.
void closest_from_faces(const TriangleSoup& soup, const std::vector<int>& faces, SparseGrid& grid, std::size_t bi,
                        double radius, std::size_t& count) {
  constexpr int S = SparseGrid::kSide, N = SparseGrid::kCount;
  auto& block = grid.block(bi);
  const Eigen::Vector3i base = grid.block_coords(bi) * S;
  const Eigen::Vector3d corner = grid.position(base);
  const double h = grid.voxel();
  std::array<double, N> best_d;
  best_d.fill(radius);
  std::array<Eigen::Vector3d, N> best;
  std::array<bool, N> found{};
  for (int fi : faces) {
    const auto& f = soup.faces[fi];
    const Eigen::Vector3d &a = soup.vertices[f[0]], &b = soup.vertices[f[1]], &c = soup.vertices[f[2]];
    // Vertex index range of the grown box; the margin keeps a vertex at exactly `radius` in.
    const Eigen::Vector3d lo = (a.cwiseMin(b).cwiseMin(c).array() - radius - corner.array()) / h - 1e-9;
    const Eigen::Vector3d hi = (a.cwiseMax(b).cwiseMax(c).array() + radius - corner.array()) / h + 1e-9;
    Eigen::Vector3i from, to;
    for (int k = 0; k < 3; ++k) {
      from[k] = static_cast<int>(std::max(0.0, std::ceil(lo[k])));
      to[k] = static_cast<int>(std::min(double(S - 1), std::floor(hi[k])));
    }
    if ((to.array() < from.array()).any()) continue;
    Eigen::Vector3d n = (b - a).cross(c - a);
    const double len = n.norm();
    const bool planar = len > 0;
    if (planar) n /= len;
    for (int z = from.z(); z <= to.z(); ++z)
      for (int y = from.y(); y <= to.y(); ++y)
        for (int x = from.x(); x <= to.x(); ++x) {
          const Eigen::Vector3i l(x, y, z);
          const int i = SparseGrid::local_index(l);
          const Eigen::Vector3d p = grid.position(base + l);
          // The distance to the triangle is at least the distance to its plane.
          if (planar && std::abs(n.dot(p - a)) > best_d[i] * (1 + 1e-12) + 1e-12 * h) continue;
          const Eigen::Vector3d q = closest_point_on_triangle(p, a, b, c);
          const double d = (q - p).norm();
          if (d <= best_d[i]) {
            best_d[i] = d;
            best[i] = q;
            found[i] = true;
          }
        }
  }
  for (int i = 0; i < N; ++i) {
    if (!found[i]) continue;
    grid.set_vector(block, i, best[i] - grid.position(base + SparseGrid::local_coords(i)));
    block.flags[i] = kInBand;
    ++count;
  }
}

}  // namespace

void build_vector_field(const TriangleSoup& soup, const SurfaceQuery& query, double radius, SparseGrid& grid,
                        VolumetricStats& stats) {
  grid.allocate(blocks_near_surface(soup, radius, grid));
  const double h = grid.voxel();
  // Every vertex of a block is within this distance of the block's centre.
  const double half_diag = 0.5 * std::sqrt(3.0) * h * (SparseGrid::kSide - 1);
  tbb::enumerable_thread_specific<std::size_t> in_band(0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, grid.block_count(), 4), [&](const auto& range) {
    auto& count = in_band.local();
    for (std::size_t bi = range.begin(); bi != range.end(); ++bi) {
      auto& block = grid.block(bi);
      const Eigen::Vector3i base = grid.block_coords(bi) * SparseGrid::kSide;
      const Eigen::Vector3d centre = grid.position(base) + Eigen::Vector3d::Constant(0.5 * h * (SparseGrid::kSide - 1));
      // The faces that can be within the band of any vertex of this block. When they are few
      // (CAD meshes, coarse scans), testing them directly beats 512 BVH traversals.
      const std::vector<int> near = query.faces_within(centre, radius + half_diag);
      if (near.size() <= 48) {
        closest_from_faces(soup, near, grid, bi, radius, count);
        continue;
      }
      for (int i = 0; i < SparseGrid::kCount; ++i) {
        const Eigen::Vector3d p = grid.position(base + SparseGrid::local_coords(i));
        const auto hit = query.closest(p, radius);
        if (!hit) continue;
        grid.set_vector(block, i, hit->point - p);
        block.flags[i] = kInBand;
        ++count;
      }
    }
  });
  stats.band_vertices = in_band.combine(std::plus<>());
  stats.blocks = grid.block_count();
  stats.bytes = grid.bytes();
}

namespace {

/// The paper's dot rule per vertex, with pseudonormals.
void classify_by_dot(const TriangleSoup& soup, const SurfaceQuery& query, SparseGrid& grid) {
  const Pseudonormals normals(soup);
  const double h = grid.voxel();
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, grid.block_count(), 2), [&](const auto& range) {
    for (std::size_t bi = range.begin(); bi != range.end(); ++bi) {
      auto& block = grid.block(bi);
      const Eigen::Vector3i base = grid.block_coords(bi) * SparseGrid::kSide;
      for (int i = 0; i < SparseGrid::kCount; ++i) {
        if (!(block.flags[i] & kInBand)) continue;
        const Eigen::Vector3d p = grid.position(base + SparseGrid::local_coords(i));
        // The stored vector is quantised; re-query for the face so the pseudonormal is exact.
        const auto hit = query.closest(p, grid.vector(block, i).norm() * (1 + 1e-3) + 1e-3 * h);
        if (hit && (hit->point - p).dot(normals.at(soup, hit->face, hit->point)) > 0) block.flags[i] |= kInside;
      }
    }
  });
}

/// Band vertices (index bi·N + i) grouped by region, each group in index order: one flat array
/// sorted by region (a counting sort), regions numbered by their first member. A map of vectors
/// cost a third of the sign step.
struct BandRegions {
  std::vector<std::size_t> first;  ///< region r is list[first[r] .. first[r + 1])
  std::vector<int> list;
  std::size_t count() const { return first.size() - 1; }
  std::pair<const int*, const int*> members(std::size_t r) const {
    return {list.data() + first[r], list.data() + first[r + 1]};
  }
};

/// The regions of the union-find `uf` (consumed) over the band vertices of `grid`. Two passes over
/// the band vertices: their roots, renumbered to regions; then their slots in the sorted array
/// (a list of the band vertices is not kept: at 1024³ it would be 70 MB).
BandRegions group_regions(const SparseGrid& grid, DisjointSets&& uf, std::size_t band_vertices) {
  constexpr int N = SparseGrid::kCount;
  auto for_each_band_vertex = [&](auto&& f) {
    for (std::size_t bi = 0; bi < grid.block_count(); ++bi)
      for (int i = 0; i < N; ++i)
        if (grid.block(bi).flags[i] & kInBand) f(static_cast<int>(bi * N + i));
  };
  std::vector<int> region;
  region.reserve(band_vertices);
  for_each_band_vertex([&](int v) { region.push_back(uf.find(v)); });
  std::vector<int>& id = uf.parent;  // roots only from here on: root -> −2 − region
  for (int r : region) id[r] = -1;
  int n_regions = 0;
  for (int& r : region) {
    if (id[r] == -1) id[r] = -2 - n_regions++;
    r = -2 - id[r];
  }
  std::vector<int>().swap(uf.parent);  // swap, not `= {}`, which keeps the capacity
  BandRegions out;
  out.first.assign(static_cast<std::size_t>(n_regions) + 1, 0);
  for (int r : region) ++out.first[static_cast<std::size_t>(r) + 1];
  for (int r = 0; r < n_regions; ++r) out.first[r + 1] += out.first[r];
  out.list.resize(region.size());
  std::vector<std::size_t> fill(out.first.begin(), out.first.end() - 1);
  std::size_t k = 0;
  for_each_band_vertex([&](int v) { out.list[fill[region[k++]]++] = v; });
  return out;
}

/// The generalised winding number decides inside/outside, but evaluating it at every band vertex
/// costs ~100× the distance field. The sign cannot change between two neighbouring vertices
/// unless the surface passes between them, so the band is cut into regions that no surface
/// separates, and the winding number is evaluated at a few samples per region. Two neighbours are
/// surely connected when their distances add up to more than their spacing (a crossing point
/// would be closer to both); otherwise a ray along the grid edge decides. A region whose samples
/// disagree or sit near w = 1/2 (it leaks through a hole or overlap) gets the winding number at
/// every vertex, or, with `shell` > 0, becomes a closed shell of that half-thickness around the
/// surface.
void classify_by_winding(const TriangleSoup& soup, const SurfaceQuery& query, double shell, SparseGrid& grid,
                         VolumetricStats& stats) {
  const WindingNumber winding(soup);
  const double h = grid.voxel();
  const std::size_t nb = grid.block_count();
  constexpr int S = SparseGrid::kSide, N = SparseGrid::kCount;
  std::vector<std::array<std::int64_t, 3>> next_block(nb);
  for (std::size_t bi = 0; bi < nb; ++bi)
    for (int a = 0; a < 3; ++a) next_block[bi][a] = grid.find_index(grid.block_coords(bi) + Eigen::Vector3i::Unit(a));
  // The +a neighbour of local vertex i of block bi: (block, local) or block -1.
  auto neighbour = [&](std::size_t bi, int i, int a) -> std::pair<std::int64_t, int> {
    Eigen::Vector3i l = SparseGrid::local_coords(i);
    if (++l[a] < S) return {static_cast<std::int64_t>(bi), SparseGrid::local_index(l)};
    l[a] = 0;
    return {next_block[bi][a], SparseGrid::local_index(l)};
  };
  // Quantisation can shorten each stored distance by up to √3·quantum: keep the test conservative.
  const double slack = h * (1 + 1e-6) + 2e-4 * h;
  // A vertex this close to the surface is linked to no neighbour across which the surface might
  // pass: a ray starting on the surface can miss it in float arithmetic, and one such missed
  // crossing joined inside and outside of abc_00000009 at 448³ into one region, which made every
  // band vertex need its own winding number (sign step 38 s for 5.1 M vertices). It forms its
  // own region.
  constexpr double kOnSurface = 1e-3;
  std::vector<std::uint8_t> linked(nb * N, 0);  // bit a: no surface between it and its +a neighbour
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 2), [&](const auto& range) {
    for (std::size_t bi = range.begin(); bi != range.end(); ++bi) {
      const auto& block = grid.block(bi);
      const Eigen::Vector3i base = grid.block_coords(bi) * S;
      for (int i = 0; i < N; ++i) {
        if (!(block.flags[i] & kInBand)) continue;
        const double d1 = grid.vector(block, i).norm();
        for (int a = 0; a < 3; ++a) {
          const auto [nbi, ni] = neighbour(bi, i, a);
          if (nbi < 0) continue;
          const auto& other = grid.block(static_cast<std::size_t>(nbi));
          if (!(other.flags[ni] & kInBand)) continue;
          const double d2 = grid.vector(other, ni).norm();
          bool connected = d1 + d2 > slack;
          if (!connected && std::min(d1, d2) < kOnSurface * h) continue;  // see kOnSurface
          if (!connected) {
            const Eigen::Vector3d p = grid.position(base + SparseGrid::local_coords(i));
            connected = !query.raycast(p, Eigen::Vector3d::Unit(a), 0, h);
          }
          if (connected) linked[bi * N + i] |= std::uint8_t(1u << a);
        }
      }
    }
  });
  // Links inside a block first, blocks in parallel (a union inside one block only writes that
  // block's entries), then the links across block faces, an eighth of them, in one thread.
  DisjointSets uf(nb * N);
  auto unite_links = [&](std::size_t bi, bool across) {
    for (int i = 0; i < N; ++i) {
      if (!linked[bi * N + i]) continue;
      const Eigen::Vector3i l = SparseGrid::local_coords(i);
      for (int a = 0; a < 3; ++a)
        if ((linked[bi * N + i] & (1u << a)) && (l[a] == S - 1) == across) {
          const auto [nbi, ni] = neighbour(bi, i, a);
          uf.unite(static_cast<int>(bi * N + i), static_cast<int>(nbi * N + ni));
        }
    }
  };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, nb, 8), [&](const auto& range) {
    for (std::size_t bi = range.begin(); bi != range.end(); ++bi) unite_links(bi, false);
  });
  for (std::size_t bi = 0; bi < nb; ++bi) unite_links(bi, true);
  // swap, not `= {}`: assigning an empty list keeps the capacity (hundreds of MB at 1024³).
  std::vector<std::uint8_t>().swap(linked);
  const BandRegions regions = group_regions(grid, std::move(uf), stats.band_vertices);
  auto position = [&](int v) {
    const std::size_t bi = static_cast<std::size_t>(v) / N;
    return grid.position(grid.block_coords(bi) * S + SparseGrid::local_coords(v % N));
  };
  auto set_inside = [&](int v, bool inside) {
    if (inside) grid.block(static_cast<std::size_t>(v) / N).flags[v % N] |= kInside;
  };
  // Sample every region first, regions in parallel: a leaky band falls into many small regions.
  struct Votes {
    int in = 0, out = 0, unsure = 0;
  };
  std::vector<Votes> votes(regions.count());
  constexpr std::size_t kSamples = 33;
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, votes.size(), 16), [&](const auto& r) {
    for (std::size_t ri = r.begin(); ri != r.end(); ++ri) {
      const auto [begin, end] = regions.members(ri);
      const std::size_t size = static_cast<std::size_t>(end - begin);
      const std::size_t step = std::max<std::size_t>(1, size / kSamples);
      Votes& v = votes[ri];
      for (std::size_t k = 0; k < size; k += step) {
        const double w = winding(position(begin[k]));
        if (std::abs(w - 0.5) < 0.25) ++v.unsure;
        (w >= 0.5 ? v.in : v.out)++;
      }
    }
  });
  std::size_t evaluations = 0, mixed = 0;
  for (std::size_t ri = 0; ri < votes.size(); ++ri) {
    const auto [begin, end] = regions.members(ri);
    const std::size_t size = static_cast<std::size_t>(end - begin);
    const auto [in, out, unsure] = votes[ri];
    evaluations += static_cast<std::size_t>(in + out);
    const bool decisive = unsure == 0 && (in == 0 || out == 0);
    if (shell > 0) {
      // The shell fallback extracts one consistent field everywhere: the signed distance minus
      // the shell offset, where only decisive inside regions count as inside (depth −d) and
      // everything else, including regions that leak through holes the band cannot bridge,
      // counts as outside (+d). Its zero set is closed in the band and never meets itself.
      const bool deep = decisive && in > 0;
      for (const int* it = begin; it != end; ++it) {
        const int v = *it;
        auto& block = grid.block(static_cast<std::size_t>(v) / N);
        block.flags[v % N] |= deep ? (kShell | kDeep) : kShell;
        set_inside(v, deep || grid.vector(block, v % N).norm() < shell);
      }
      mixed += !decisive;
      continue;
    }
    if (decisive) {
      for (const int* it = begin; it != end; ++it) set_inside(*it, in > 0);
      continue;
    }
    ++mixed;
    evaluations += size;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, size, 256), [&, begin = begin](const auto& r) {
      for (std::size_t k = r.begin(); k != r.end(); ++k) set_inside(begin[k], winding(position(begin[k])) >= 0.5);
    });
  }
  stats.sign_queries = evaluations;
  stats.sign_regions = regions.count();
  stats.sign_regions_mixed = mixed;
}

}  // namespace

void classify_inside(const TriangleSoup& soup, const SurfaceQuery& query, SignMode mode, double shell,
                     SparseGrid& grid, VolumetricStats& stats) {
  grid.set_shell(shell);
  if (mode == SignMode::dot) {
    classify_by_dot(soup, query, grid);
    stats.sign_queries = stats.band_vertices;
  } else {
    classify_by_winding(soup, query, shell, grid, stats);
  }
}

}  // namespace s2c::repair
