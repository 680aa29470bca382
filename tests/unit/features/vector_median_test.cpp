// The ring's vector median (vector_median.h), the guide of filter_normals' first iterations: both
// paths against the definition written out with Eigen, as filter_normals computed it before.
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "fit_passes.h"
#include "vector_median.h"

namespace s2c::features {
namespace {

/// The index of the first normal with the least area-weighted sum of |n_i − n_j| over j ≠ i
/// (Eigen's norm), as filter_normals chose its guide.
int reference_median(const std::vector<Eigen::Vector3d>& n, const std::vector<double>& area) {
  int best = -1;
  double least = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n.size(); ++i) {
    double cost = 0;
    for (std::size_t j = 0; j < n.size(); ++j)
      if (j != i) cost += area[j] * (n[i] - n[j]).norm();
    if (cost < least) least = cost, best = static_cast<int>(i);
  }
  return best;
}

/// Rings of 1 to 24 noisy unit normals about one or two directions (a face on a crease), with
/// uneven areas; some rings repeat a normal, so that ties are taken by the first.
TEST(VectorMedian, BothPathsPickTheNormalTheDefinitionPicks) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 0.2);
  std::uniform_real_distribution<double> area(0.1, 2.0);
  RingColumns ring;
  int rings = 0, moved = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const int k = 1 + trial % 24;
    const bool crease = trial % 3 == 0;
    std::vector<Eigen::Vector3d> n;
    std::vector<double> a;
    for (int i = 0; i < k; ++i) {
      if (trial % 7 == 0 && i > 0 && i % 4 == 0) {
        n.push_back(n[i - 2]), a.push_back(a[i - 2]);  // an exact tie with an earlier normal
        continue;
      }
      const Eigen::Vector3d axis = crease && i % 2 ? Eigen::Vector3d(1, 0, 0.3) : Eigen::Vector3d(0, 0, 1);
      n.push_back((axis + Eigen::Vector3d(noise(rng), noise(rng), noise(rng))).normalized());
      a.push_back(area(rng));
    }
    const int expected = reference_median(n, a);
    ring.clear();
    for (int i = 0; i < k; ++i) ring.add(n[i], a[i]);
    ASSERT_EQ(ring.size(), k);
    EXPECT_EQ(ring.median(false), expected) << "ring " << trial << " of " << k;
    if (fit::have_avx_passes()) {
      EXPECT_EQ(ring.median(true), expected) << "ring " << trial << " of " << k;
    }
    ++rings;
    moved += expected != k - 1;
  }
  // (Not all medians are the last normal: the test tells an index from a constant.)
  EXPECT_GT(moved, rings / 2);
}

TEST(VectorMedian, AnEmptyRingHasNoneAndNormalsThatAreNotFiniteAreTakenAsBefore) {
  RingColumns ring;
  EXPECT_EQ(ring.median(false), -1);
  const double nan = std::numeric_limits<double>::quiet_NaN();
  std::vector<Eigen::Vector3d> n{Eigen::Vector3d(nan, 0, 1)};
  std::vector<double> a{1.0};
  for (int k = 1; k <= 3; ++k) {
    // One NaN normal alone is its own median (no distance to another); with others, every cost
    // holds a NaN distance and none is chosen, so the caller keeps the face's own normal.
    ring.clear();
    for (std::size_t i = 0; i < n.size(); ++i) ring.add(n[i], a[i]);
    const int expected = reference_median(n, a);
    EXPECT_EQ(expected, k == 1 ? 0 : -1);
    EXPECT_EQ(ring.median(false), expected) << k;
    if (fit::have_avx_passes()) {
      EXPECT_EQ(ring.median(true), expected) << k;
    }
    n.push_back(Eigen::Vector3d(0, 0.1 * k, 1).normalized()), a.push_back(1.0);
  }
}

}  // namespace
}  // namespace s2c::features
