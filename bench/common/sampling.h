#pragma once
// Shared by the benchmarks: deterministic area-uniform surface samples and point-to-surface
// distances on all cores (Embree closest-point queries).
#include <cstdint>
#include <vector>

#include <Eigen/Core>

#include "s2c/core/distance.h"
#include "s2c/core/mesh.h"

namespace s2c::bench {

// SplitMix64 → doubles in [0, 1): identical on every platform and standard library.
struct Rng {
  std::uint64_t s;
  std::uint64_t next() {
    std::uint64_t z = (s += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
};

struct Samples {
  std::vector<Eigen::Vector3d> points;
  double area = 0;
};

/// `n` points uniformly distributed by area over the soup's triangles. \throw InvalidInput for zero area.
Samples sample_surface(const TriangleSoup& soup, std::size_t n, std::uint64_t seed);

/// Distance of every point to the surface (unbounded queries), on all cores; optionally the
/// closest points (on the queried surface).
std::vector<double> distances(const SurfaceQuery& q, const std::vector<Eigen::Vector3d>& pts,
                              std::vector<Eigen::Vector3d>* closest = nullptr);

/// Symmetric Chamfer distance (mean of both directions' mean distances) and Hausdorff distance
/// between two surfaces, from `n` area samples on each.
struct SurfaceDistance {
  double chamfer = 0, hausdorff = 0, mean_ab = 0, mean_ba = 0;
};
SurfaceDistance surface_distance(const TriangleSoup& a, const TriangleSoup& b, std::size_t n = 200000,
                                 std::uint64_t seed = 1);

}  // namespace s2c::bench
