// Bilateral filtering of the face normals of a noisy mesh (segment.h), guided by the vector
// median of each 1-ring in the first iterations.
#include "segment.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/parallel_for.h>

#include "fit_passes.h"
#include "vector_math.h"
#include "vector_median.h"

namespace s2c::features {
namespace {

/// Faces sharing a vertex with f (f excluded), appended to `out`.
void face_ring(const MeshArrays& m, int f, std::vector<int>& out) {
  out.clear();
  for (int v : m.tri[f])
    for (int k = m.vf_start[v]; k < m.vf_start[v + 1]; ++k)
      if (m.vf[k] != f) out.push_back(m.vf[k]);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

}  // namespace

std::vector<Eigen::Vector3d> filter_normals(const MeshArrays& m, int iterations, double sigma_r) {
  std::vector<Eigen::Vector3d> n = m.fnormal, next(m.faces()), centroid(m.faces());
  // (Every face's centroid is read once per ring it is in and iteration: stored for the filter.)
  tbb::parallel_for(0, m.faces(), [&](int f) { centroid[f] = m.centroid(f); });
  const double sigma_s = std::max(m.mean_edge, 1e-12);
  const double inv_s2 = 1.0 / (sigma_s * sigma_s), inv_r2 = 1.0 / (sigma_r * sigma_r);
  // Plain bilateral filtering keeps outliers: a sliver whose noisy normal is 50° off its
  // neighbours sees them all as "across a crease" and stays as it is. The first iterations
  // therefore compare neighbours with a guide, the vector median of the 1-ring (the ring normal
  // closest to all others, area-weighted), which ignores outliers yet stays on one side of a crease.
  constexpr int kGuidedIterations = 2;
  const bool avx = fit::have_avx_passes();
  // The rings (faces sharing a vertex with f, sorted), built once for all iterations: CSR.
  std::vector<int> ring_start(m.faces() + 1, 0), rings;
  {
    std::vector<std::vector<int>> per_block((m.faces() + 4095) / 4096);
    tbb::parallel_for(0, static_cast<int>(per_block.size()), [&](int b) {
      std::vector<int> ring;
      const int end = std::min(m.faces(), (b + 1) * 4096);
      for (int f = b * 4096; f < end; ++f) {
        face_ring(m, f, ring);
        ring_start[f + 1] = static_cast<int>(ring.size());
        per_block[b].insert(per_block[b].end(), ring.begin(), ring.end());
      }
    });
    for (int f = 0; f < m.faces(); ++f) ring_start[f + 1] += ring_start[f];
    rings.reserve(ring_start.back());
    for (auto& block : per_block) rings.insert(rings.end(), block.begin(), block.end());
  }
  for (int it = 0; it < iterations; ++it) {
    const bool guided = it < kGuidedIterations;
    tbb::parallel_for(tbb::blocked_range<int>(0, m.faces(), 512), [&](const tbb::blocked_range<int>& range) {
      std::vector<int> ring;
      RingColumns columns;
      std::vector<double> weight;
      for (int f = range.begin(); f < range.end(); ++f) {
        // The ring, then f itself: the faces the guide is chosen from and the weights are taken over.
        ring.assign(rings.begin() + ring_start[f], rings.begin() + ring_start[f + 1]);
        ring.push_back(f);
        Eigen::Vector3d guide = n[f];
        if (guided) {
          columns.clear();
          for (int g : ring) columns.add(n[g], m.farea[g]);
          const int median = columns.median(avx);
          if (median >= 0) guide = n[ring[median]];
        }
        // The weights' exponents, then all their exponentials in one call to the vectorised exp
        // (as the tensor vote takes its weights).
        weight.resize(ring.size());
        for (std::size_t i = 0; i < ring.size(); ++i) {
          const int g = ring[i];
          weight[i] = -0.5 * ((centroid[f] - centroid[g]).squaredNorm() * inv_s2 + (guide - n[g]).squaredNorm() * inv_r2);
        }
        exp_in_place(weight.data(), weight.size());
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (std::size_t i = 0; i < ring.size(); ++i) sum += m.farea[ring[i]] * weight[i] * n[ring[i]];
        const double len = sum.norm();
        next[f] = len > 0 ? Eigen::Vector3d(sum / len) : n[f];
      }
    });
    n.swap(next);
  }
  return n;
}

}  // namespace s2c::features
