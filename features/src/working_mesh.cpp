// Vertex clustering of a large noisy mesh for the analysis, and the mapping of the working
// mesh's segmentation back onto the fine mesh (working_mesh.h).
#include "working_mesh.h"

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>

#include <Eigen/Eigenvalues>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include "s2c/features/shape.h"

namespace s2c::features {
namespace {

/// A plane's eigenvalue counts in a cluster's quadric when it is at least this share of the
/// largest: two planes crossing at 37° or more (tan²(φ/2) ≥ 0.1), not the spread of noisy normals
/// in one plane (σ = 0.2 edge: about 0.03), which would throw the vertex about within its plane.
constexpr double kQuadricRank = 0.1;

/// The cell is sqrt(kCellArea · area / target): a plane crosses 1.5 grid cells per cell area on
/// average over orientations, and seeds 0.7 cell apart keep about 0.6 of the cells' candidates
/// (measured: 58,260 clusters for 1.5 · area / 100,000 on the pocket at 0.9 M vertices; 56,152
/// and 56,590 on the plate and bracket).
constexpr double kCellArea = 0.87;

/// Mode filter passes over the mapped borders (map_back).
constexpr int kModePasses = 3;

std::uint64_t cell_key(const Eigen::Vector3d& p, const Eigen::Vector3d& origin, double cell) {
  const Eigen::Vector3d q = (p - origin) / cell;
  auto c = [](double x) { return static_cast<std::uint64_t>(std::clamp(std::floor(x), 0.0, 2097151.0)); };
  return c(q.x()) << 42 | c(q.y()) << 21 | c(q.z());
}

/// The candidates for seeds: per occupied grid cell, its vertex nearest the cell's centre, in the
/// order of the cells' keys.
std::vector<int> grid_candidates(const MeshArrays& m, double cell) {
  const int nv = m.vertices();
  std::vector<std::pair<std::uint64_t, int>> order(nv);
  tbb::parallel_for(0, nv, [&](int v) { order[v] = {cell_key(m.pos[v], m.box.min, cell), v}; });
  tbb::parallel_sort(order.begin(), order.end());
  std::vector<int> starts;  // where each cell's run of vertices starts in `order`
  for (int i = 0; i < nv; ++i)
    if (i == 0 || order[i].first != order[i - 1].first) starts.push_back(i);
  starts.push_back(nv);
  std::vector<int> candidates(starts.size() - 1);
  tbb::parallel_for(std::size_t{0}, candidates.size(), [&](std::size_t c) {
    const std::uint64_t key = order[starts[c]].first;
    const auto at = [&](int shift) { return (static_cast<double>((key >> shift) & 2097151u) + 0.5) * cell; };
    const Eigen::Vector3d centre = m.box.min + Eigen::Vector3d(at(42), at(21), at(0));
    int best = order[starts[c]].second;
    for (int i = starts[c] + 1; i < starts[c + 1]; ++i)
      if ((m.pos[order[i].second] - centre).squaredNorm() < (m.pos[best] - centre).squaredNorm()) best = order[i].second;
    candidates[c] = best;
  });
  return candidates;
}

/// Per fine vertex its cluster, a connected piece of the surface about a cell wide (Valette's
/// ACVD clusters without the energy minimisation): seeds at least 0.7 cell apart, taken among the
/// vertices nearest their grid cell's centre, then every vertex joins the seed the fewest edges
/// away (a breadth-first search from all seeds at once). Connected, compact clusters give a
/// coarse mesh that is closed and manifold where the mesh is; a grid's cells cut the surface into
/// slivers and folds (tried: 3,971 boundary loops and 38,512 intersecting face pairs on the
/// pocket at 0.9 M vertices).
std::vector<int> cluster_vertices(const MeshArrays& m, double cell, int& clusters) {
  const int nv = m.vertices();
  const std::vector<int> candidates = grid_candidates(m, cell);
  const std::vector<int> seeds = spaced_seeds(m.pos, m.box.min, candidates, 0.7 * cell);
  // Breadth-first from all seeds, level by level on all cores: a vertex first reached at level
  // L + 1 joins the smallest-numbered cluster among its neighbours at level L (a minimum, so the
  // result does not depend on the threads' order). Vertices no seed reaches (none on a mesh whose
  // every piece has a vertex nearest some cell's centre) seed clusters of their own.
  constexpr int kUnset = std::numeric_limits<int>::max();
  std::vector<std::atomic<int>> label(nv), level(nv);
  tbb::parallel_for(0, nv, [&](int v) {
    label[v].store(kUnset, std::memory_order_relaxed);
    level[v].store(kUnset, std::memory_order_relaxed);
  });
  clusters = 0;
  auto flood = [&](std::vector<int> frontier) {
    for (int l = level[frontier.front()].load() + 1; !frontier.empty(); ++l) {
      tbb::enumerable_thread_specific<std::vector<int>> reached;
      tbb::parallel_for(tbb::blocked_range<std::size_t>(0, frontier.size(), 256), [&](const auto& range) {
        std::vector<int>& mine = reached.local();
        for (std::size_t i = range.begin(); i < range.end(); ++i) {
          const int v = frontier[i], id = label[v].load(std::memory_order_relaxed);
          for (int k = m.vf_start[v]; k < m.vf_start[v + 1]; ++k)
            for (int u : m.tri[m.vf[k]]) {
              const int seen = level[u].load(std::memory_order_relaxed);
              if (seen != kUnset && seen != l) continue;  // reached earlier: no atomic operation
              int expected = kUnset;
              if (level[u].compare_exchange_strong(expected, l, std::memory_order_relaxed)) mine.push_back(u);
              else if (expected != l) continue;
              int now = label[u].load(std::memory_order_relaxed);
              while (id < now && !label[u].compare_exchange_weak(now, id, std::memory_order_relaxed)) {
              }
            }
        }
      });
      frontier.clear();
      for (auto& part : reached) frontier.insert(frontier.end(), part.begin(), part.end());
    }
  };
  for (int s : seeds) label[s].store(clusters++), level[s].store(0);
  if (!seeds.empty()) flood(seeds);
  for (int v = 0; v < nv; ++v)
    if (level[v].load(std::memory_order_relaxed) == kUnset) {
      label[v].store(clusters++), level[v].store(0);
      flood({v});
    }
  std::vector<int> cluster(nv);
  tbb::parallel_for(0, nv, [&](int v) { cluster[v] = label[v].load(std::memory_order_relaxed); });
  return cluster;
}

/// Each cluster's position: the point nearest the mean of its vertices that the planes of its
/// faces (area-weighted) pin down; kept within a cell of the mean.
/// With `mean_flat`, a cluster whose faces lie in one plane (a single eigenvalue of their
/// quadric counts) stays at its mean: on a smooth mesh each face's plane, tilted by the bumps of a
/// Poisson surface, is off by its tilt times its distance from the mean (the pocket scan at
/// Poisson depth 9: the working mesh's noise 0.0126 mm at the quadric points, 0.0074 mm with flat
/// clusters at their means, the fine mesh's 0.0024 mm). A noisy mesh keeps the quadric points:
/// the means gave the same recall, line F1 and constraints on the million-vertex sweep.
std::vector<Eigen::Vector3d> place_clusters(const MeshArrays& m, const std::vector<int>& cluster, int clusters, double cell,
                                           bool mean_flat) {
  struct Quadric {
    Eigen::Matrix3d a = Eigen::Matrix3d::Zero();
    Eigen::Vector3d b = Eigen::Vector3d::Zero(), sum = Eigen::Vector3d::Zero();
    int count = 0;
  };
  // The faces in order (a stream through memory), in kChunks fixed ranges side by side, each
  // summed in face order into its own sums, which are then added in chunk order: the same bits
  // whatever the threads (TBB's own partial sums would follow its scheduling). A face counts once
  // per cluster it touches.
  constexpr int kChunks = 2;
  std::vector<std::vector<Quadric>> partial(kChunks, std::vector<Quadric>(clusters));
  tbb::parallel_for(0, kChunks, [&](int chunk) {
    std::vector<Quadric>& q = partial[chunk];
    const int end = static_cast<int>(static_cast<long>(m.faces()) * (chunk + 1) / kChunks);
    for (int f = static_cast<int>(static_cast<long>(m.faces()) * chunk / kChunks); f < end; ++f) {
      const Eigen::Vector3d& n = m.fnormal[f];
      const double w = m.farea[f], d = n.dot(m.pos[m.tri[f][0]]);
      const Eigen::Matrix3d nn = w * n * n.transpose();
      const std::array<int, 3> c{cluster[m.tri[f][0]], cluster[m.tri[f][1]], cluster[m.tri[f][2]]};
      for (int k = 0; k < 3; ++k) {
        if ((k > 0 && c[k] == c[0]) || (k > 1 && c[k] == c[1])) continue;
        q[c[k]].a += nn;
        q[c[k]].b += w * d * n;
      }
    }
  });
  std::vector<Quadric>& q = partial[0];
  for (int chunk = 1; chunk < kChunks; ++chunk)
    tbb::parallel_for(0, clusters, [&](int k) { q[k].a += partial[chunk][k].a, q[k].b += partial[chunk][k].b; });
  for (int v = 0; v < m.vertices(); ++v) q[cluster[v]].sum += m.pos[v], ++q[cluster[v]].count;
  std::vector<Eigen::Vector3d> pos(clusters);
  tbb::parallel_for(0, clusters, [&](int k) {
    const Quadric& c = q[k];
    const Eigen::Vector3d mean = c.sum / c.count;
    pos[k] = mean;
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig;
    eig.computeDirect(c.a);
    const Eigen::Vector3d lambda = eig.eigenvalues();  // ascending
    if (!(lambda(2) > 0) || (mean_flat && lambda(1) < kQuadricRank * lambda(2))) return;
    const Eigen::Vector3d r = c.b - c.a * mean;
    Eigen::Vector3d x = mean;
    for (int i = 0; i < 3; ++i)
      if (lambda(i) >= kQuadricRank * lambda(2)) x += eig.eigenvectors().col(i) * (eig.eigenvectors().col(i).dot(r) / lambda(i));
    if ((x - mean).norm() <= cell && x.allFinite()) pos[k] = x;
  });
  return pos;
}

/// Adds `n` to the count of `region` in a short list of (region, count), in order of first
/// appearance (a face or a cluster has few regions about it).
void tally(std::vector<std::pair<int, int>>& counts, int region, int n) {
  auto it = counts.begin();
  while (it != counts.end() && it->first != region) ++it;
  if (it == counts.end()) counts.emplace_back(region, n);
  else it->second += n;
}

/// Faces with a neighbour across an edge in another region, in increasing order.
std::vector<int> border_faces(const MeshArrays& m, const std::vector<int>& region) {
  std::vector<char> border(m.faces(), 0);
  tbb::parallel_for(0, m.faces(), [&](int f) {
    for (int e : m.face_edges[f]) {
      const int g = m.across(e, f);
      if (g >= 0 && region[g] != region[f]) border[f] = 1;
    }
  });
  std::vector<int> faces;
  for (int f = 0; f < m.faces(); ++f)
    if (border[f]) faces.push_back(f);
  return faces;
}

/// Up to `passes` rounds of relabelling: every face of `active` decides its region (`decide`,
/// reading the labels as the round found them), then those that changed move together; the next
/// round looks at the faces sharing a vertex with them, the only ones whose decision can change.
template <class Decide>
void relabel(const MeshArrays& m, std::vector<int>& region, std::vector<int> active, int passes, Decide decide) {
  for (int pass = 0; pass < passes && !active.empty(); ++pass) {
    std::vector<int> to(active.size());
    tbb::parallel_for(std::size_t{0}, active.size(), [&](std::size_t i) { to[i] = decide(active[i]); });
    std::vector<int> next;
    for (std::size_t i = 0; i < active.size(); ++i) {
      if (to[i] == region[active[i]]) continue;
      region[active[i]] = to[i];
      for (int v : m.tri[active[i]]) next.insert(next.end(), m.vf.begin() + m.vf_start[v], m.vf.begin() + m.vf_start[v + 1]);
    }
    std::sort(next.begin(), next.end());
    next.erase(std::unique(next.begin(), next.end()), next.end());
    active.swap(next);
  }
}

}  // namespace

std::vector<int> spaced_seeds(const std::vector<Eigen::Vector3d>& pos, const Eigen::Vector3d& origin,
                              const std::vector<int>& candidates, double spacing) {
  // The seeds are kept in a grid of cells two spacings wide, so a candidate's near seeds lie in
  // the 2×2×2 cells nearest it; those cells are found for every candidate beforehand, on all
  // cores, among the sorted keys of the cells that hold candidates, and the pass in order only
  // follows each cell's chain of seeds (a hash map looked up in 27 cells a spacing wide took
  // 0.16 s, one core, for the 280 k candidates of a smooth mesh's working mesh).
  const int n = static_cast<int>(candidates.size());
  const double width = 2 * spacing;
  // Keys of the grid shifted by one cell, so that a candidate's lower neighbours at the corner
  // have keys too; cell_key clamps points far beyond the grid (stray vertices of debris) into its
  // last cells, which only lengthens those cells' chains.
  const Eigen::Vector3d corner = origin - Eigen::Vector3d::Constant(width);
  auto key = [&](const Eigen::Vector3d& p) { return cell_key(p, corner, width); };
  std::vector<std::uint64_t> own(n);
  tbb::parallel_for(0, n, [&](int i) { own[i] = key(pos[candidates[i]]); });
  std::vector<std::uint64_t> cells = own;
  tbb::parallel_sort(cells.begin(), cells.end());
  cells.erase(std::unique(cells.begin(), cells.end()), cells.end());
  auto index = [&](std::uint64_t k) {
    const auto it = std::lower_bound(cells.begin(), cells.end(), k);
    return it != cells.end() && *it == k ? static_cast<int>(it - cells.begin()) : -1;
  };
  // Per candidate its own cell and the eight within half a cell (-1: no candidate there); cells
  // differing in z only are neighbours in the sorted keys.
  std::vector<std::array<int, 9>> near(n);
  tbb::parallel_for(0, n, [&](int i) {
    const Eigen::Vector3d& p = pos[candidates[i]];
    int k = 0;
    for (int dx = 0; dx <= 1; ++dx)
      for (int dy = 0; dy <= 1; ++dy) {
        const std::uint64_t lower = key(p + width * Eigen::Vector3d(dx - 0.5, dy - 0.5, -0.5));
        const auto it = std::lower_bound(cells.begin(), cells.end(), lower);
        const bool found = it != cells.end() && *it == lower;
        near[i][k++] = found ? static_cast<int>(it - cells.begin()) : -1;
        const auto above = found ? it + 1 : it;
        near[i][k++] = above != cells.end() && *above == lower + 1 ? static_cast<int>(above - cells.begin()) : -1;
      }
    near[i][8] = index(own[i]);
  });
  std::vector<int> last(cells.size(), -1);  // per cell its last seed's index in `seeds`
  std::vector<int> seeds, before;           // before[s]: the seed taken before seeds[s] in its cell, or -1
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d& p = pos[candidates[i]];
    bool close = false;
    for (int k = 0; k < 8 && !close; ++k)
      for (int s = near[i][k] >= 0 ? last[near[i][k]] : -1; s >= 0 && !close; s = before[s])
        close = (pos[seeds[s]] - p).squaredNorm() < spacing * spacing;
    if (close) continue;
    before.push_back(last[near[i][8]]);
    last[near[i][8]] = static_cast<int>(seeds.size());
    seeds.push_back(candidates[i]);
  }
  return seeds;
}

WorkingMesh coarsen(const MeshArrays& fine, int target_vertices, double max_cell, bool mean_flat) {
  WorkingMesh w;
  double area = 0;
  for (double a : fine.farea) area += a;
  w.cell = std::max(std::min(std::sqrt(kCellArea * area / std::max(target_vertices, 1)), max_cell), fine.median_edge);
  int clusters = 0;
  w.vertex_cluster = cluster_vertices(fine, w.cell, clusters);
  TriangleSoup soup;
  soup.vertices = place_clusters(fine, w.vertex_cluster, clusters, w.cell, mean_flat);

  // Each surviving fine face as its clusters, rotated to start at the smallest, with the
  // orientation apart: (a, b, c, flipped, face) sorted brings one triangle's copies together.
  struct Corner {
    std::array<int, 3> c;
    bool flipped;
    int face;
    bool operator<(const Corner& o) const { return std::tie(c, flipped, face) < std::tie(o.c, o.flipped, o.face); }
  };
  std::vector<Corner> kept;  // (a few per cent of the faces: not reserved for all)
  for (int f = 0; f < fine.faces(); ++f) {
    std::array<int, 3> c{w.vertex_cluster[fine.tri[f][0]], w.vertex_cluster[fine.tri[f][1]], w.vertex_cluster[fine.tri[f][2]]};
    if (c[0] == c[1] || c[1] == c[2] || c[0] == c[2]) continue;
    std::rotate(c.begin(), std::min_element(c.begin(), c.end()), c.end());
    const bool flipped = c[2] < c[1];
    if (flipped) std::swap(c[1], c[2]);
    kept.push_back({c, flipped, f});
  }
  tbb::parallel_sort(kept.begin(), kept.end());
  w.face_of.assign(fine.faces(), -1);
  for (std::size_t i = 0; i < kept.size();) {
    std::size_t j = i;
    while (j < kept.size() && kept[j].c == kept[i].c) ++j;
    // Copies facing both ways are a sheet folded flat by the clustering: dropped.
    if (kept[i].flipped == kept[j - 1].flipped) {
      const int id = static_cast<int>(soup.faces.size());
      std::array<int, 3> t = kept[i].c;
      if (kept[i].flipped) std::swap(t[1], t[2]);
      soup.faces.push_back(t);
      for (std::size_t k = i; k < j; ++k) w.face_of[kept[k].face] = id;
    }
    i = j;
  }
  w.arrays = build_arrays(std::move(soup));
  return w;
}

Segmentation map_back(const MeshArrays& fine, const WorkingMesh& w, const Segmentation& coarse, double tolerance,
                      int passes) {
  const int nf = fine.faces();
  Segmentation seg;
  seg.merges = coarse.merges, seg.seeds = coarse.seeds, seg.grown_faces = coarse.grown_faces;
  seg.splits = coarse.splits, seg.absorbed = coarse.absorbed;
  std::vector<int>& region = seg.face_region;
  region.assign(nf, -1);
  tbb::parallel_for(0, nf, [&](int f) {
    if (w.face_of[f] >= 0) region[f] = coarse.face_region[w.face_of[f]];
  });
  std::vector<Region> regions = coarse.regions;

  auto fitted = [&](int r) { return regions[r].fit.ok && is_surface(regions[r].fit.shape.type); };
  // A collapsed face lies in the clusters of its corners: the regions of the working mesh's faces
  // around those are its candidates. Of two or more, the fitted shape nearest its centroid takes
  // it if within three tolerances (a crease then runs where the shapes meet), else the region of
  // most faces around (a freeform band beside a fitted patch keeps its faces).
  const MeshArrays& c = w.arrays;
  // Each cluster's regions with their face counts, and the one region of a cluster inside a patch.
  std::vector<std::vector<std::pair<int, int>>> around(c.vertices());
  std::vector<int> only(c.vertices(), -1);
  tbb::parallel_for(0, c.vertices(), [&](int k) {
    for (int i = c.vf_start[k]; i < c.vf_start[k + 1]; ++i) tally(around[k], coarse.face_region[c.vf[i]], 1);
    if (around[k].size() == 1) only[k] = around[k].front().first;
  });
  tbb::parallel_for(tbb::blocked_range<int>(0, nf, 4096), [&](const tbb::blocked_range<int>& range) {
    std::vector<std::pair<int, int>> candidates;  // (region, faces)
    for (int f = range.begin(); f < range.end(); ++f) {
      if (region[f] >= 0) continue;
      const auto& t = fine.tri[f];
      const int k0 = w.vertex_cluster[t[0]], k1 = w.vertex_cluster[t[1]], k2 = w.vertex_cluster[t[2]];
      if (only[k0] >= 0 && only[k0] == only[k1] && only[k0] == only[k2]) {
        region[f] = only[k0];
        continue;
      }
      candidates.clear();
      for (int k : {k0, k1, k2})
        for (const auto& [r, faces] : around[k]) tally(candidates, r, faces);
      if (candidates.empty()) continue;
      int best = -1, most = candidates.front().first, most_faces = 0;
      double nearest = 3 * tolerance;
      for (const auto& [r, faces] : candidates) {
        if (faces > most_faces) most = r, most_faces = faces;
        if (!fitted(r)) continue;
        const double d = distance(regions[r].fit.shape, fine.centroid(f));
        if (d <= nearest) best = r, nearest = d;
      }
      region[f] = best >= 0 ? best : most;
    }
  });

  // Faces no cluster's faces reach take the region of a labelled neighbour across an edge (the
  // smallest region number among them, ring by ring); a piece that collapsed whole is a freeform
  // region of its own.
  std::vector<int> open;
  for (int f = 0; f < nf; ++f)
    if (region[f] < 0) open.push_back(f);
  while (!open.empty()) {
    std::vector<int> label(open.size(), -1);
    tbb::parallel_for(std::size_t{0}, open.size(), [&](std::size_t i) {
      for (int e : fine.face_edges[open[i]]) {
        const int g = fine.across(e, open[i]);
        if (g >= 0 && region[g] >= 0 && (label[i] < 0 || region[g] < label[i])) label[i] = region[g];
      }
    });
    std::vector<int> still;
    for (std::size_t i = 0; i < open.size(); ++i)
      if (label[i] >= 0) region[open[i]] = label[i];
      else still.push_back(open[i]);
    if (still.size() == open.size()) {
      regions.emplace_back();  // freeform
      for (int f : still) region[f] = static_cast<int>(regions.size()) - 1;
      break;
    }
    open.swap(still);
  }

  // The borders between fitted patches: a face moves to the neighbouring patch whose shape is
  // nearer its centroid.
  relabel(fine, region, border_faces(fine, region), passes, [&](int f) {
    const int own = region[f];
    if (!fitted(own)) return own;
    int to = own;
    double best = -1;
    for (int e : fine.face_edges[f]) {
      const int g = fine.across(e, f);
      if (g < 0 || region[g] == own || !fitted(region[g])) continue;
      if (best < 0) best = distance(regions[own].fit.shape, fine.centroid(f));
      const double d = distance(regions[region[g]].fit.shape, fine.centroid(f));
      if (d < best) best = d, to = region[g];
    }
    return to;
  });

  // Noise along a crease leaves faces on the wrong side, each a notch or an island, and where two
  // notches touch at a corner the border pinches into a run of two-vertex lines. A border face
  // whose vertices' faces are mostly of one other region joins it (a mode filter over the faces
  // around its three vertices, a face across an edge counted twice).
  relabel(fine, region, border_faces(fine, region), kModePasses, [&](int f) {
    thread_local std::vector<std::pair<int, int>> count;  // (region, faces)
    count.clear();
    int total = 0;
    for (int v : fine.tri[f])
      for (int k = fine.vf_start[v]; k < fine.vf_start[v + 1]; ++k) tally(count, region[fine.vf[k]], 1), ++total;
    for (const auto& [r, n] : count)
      if (r != region[f] && 2 * n > total) return r;
    return region[f];
  });

  // The regions' fine faces and areas; regions left without faces are dropped.
  for (auto& r : regions) r.faces.clear(), r.area = 0;
  for (int f = 0; f < nf; ++f) regions[region[f]].faces.push_back(f), regions[region[f]].area += fine.farea[f];
  std::vector<int> renumber(regions.size(), -1);
  for (std::size_t r = 0; r < regions.size(); ++r)
    if (!regions[r].faces.empty()) {
      renumber[r] = static_cast<int>(seg.regions.size());
      seg.regions.push_back(std::move(regions[r]));
    }
  tbb::parallel_for(0, nf, [&](int f) { region[f] = renumber[region[f]]; });
  return seg;
}

MappedNormals::MappedNormals(const MeshArrays& fine, const WorkingMesh& w, const std::vector<Eigen::Vector3d>& coarse_normals)
    : fine_(fine), w_(w), coarse_normals_(coarse_normals), at_cluster_(w.arrays.vertices()) {
  // A collapsed face (most of them: a cluster holds many faces) takes the area-weighted normal
  // around its first vertex's cluster: its own is as noisy as the mesh, and trace_lines orients
  // the patches' normals by it, so one that is far off makes a line edge of a tangent junction.
  const MeshArrays& c = w.arrays;
  tbb::parallel_for(0, c.vertices(), [&](int v) {
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    for (int k = c.vf_start[v]; k < c.vf_start[v + 1]; ++k) sum += c.farea[c.vf[k]] * coarse_normals[c.vf[k]];
    at_cluster_[v] = sum.normalized();
  });
}

Eigen::Vector3d MappedNormals::operator()(int face) const {
  if (w_.face_of[face] >= 0) return coarse_normals_[w_.face_of[face]];
  const Eigen::Vector3d& around = at_cluster_[w_.vertex_cluster[fine_.tri[face][0]]];
  return around.allFinite() ? around : fine_.fnormal[face];
}

}  // namespace s2c::features
