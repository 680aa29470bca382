#pragma once
// The vector median of a face's ring of normals (filter_normals.cpp's guide), on SSE2 or, where
// the CPU has it, four distances per instruction with AVX. Both paths do the same operations in
// the same order (AVX without FMA rounds as SSE2 does), so they pick the same normal.
#include <vector>

#include <Eigen/Core>

namespace s2c::features {

/// A ring of normals by coordinate, with their areas, and the scratch of their distances.
class RingColumns {
 public:
  /// Empties the ring (keeping its memory).
  void clear() { k_ = 0, x_.clear(), y_.clear(), z_.clear(), a_.clear(); }
  void add(const Eigen::Vector3d& n, double area) { x_.push_back(n.x()), y_.push_back(n.y()), z_.push_back(n.z()), a_.push_back(area), ++k_; }
  int size() const { return k_; }

  /// The index of the normal with the least area-weighted sum of distances |n_i − n_j| to all of
  /// the ring (the first of equals), −1 for an empty ring. `avx` only where have_avx_passes().
  int median(bool avx);

 private:
  int median_sse2();
  int median_avx();

  int k_ = 0;
  std::vector<double> x_, y_, z_, a_, apart_, cost_;
};

}  // namespace s2c::features
