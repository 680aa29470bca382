#include "vector_median.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <immintrin.h>

// Compiled for AVX (without FMA) function by function; called only when have_avx_passes().
#define S2C_AVX __attribute__((target("avx")))

namespace s2c::features {
namespace {

/// The first index of the least of costs[0, k).
int first_least(const double* costs, int k) {
  int best = -1;
  double least = std::numeric_limits<double>::infinity();
  for (int i = 0; i < k; ++i)
    if (costs[i] < least) least = costs[i], best = i;
  return best;
}

}  // namespace

int RingColumns::median(bool avx) {
  if (k_ == 0) return -1;
  return avx ? median_avx() : median_sse2();
}

// The distances as Eigen's (n_i − n_j).norm(): sqrt((dx² + dy²) + dz²); each cost sums
// area_j · |n_i − n_j| over j in order.
int RingColumns::median_sse2() {
  const int k = k_;
  apart_.assign(static_cast<std::size_t>(k) * k, 0.0);
  for (int i = 0; i < k; ++i)
    for (int j = i + 1; j < k; ++j) {
      const double dx = x_[i] - x_[j], dy = y_[i] - y_[j], dz = z_[i] - z_[j];
      apart_[i * k + j] = apart_[j * k + i] = std::sqrt((dx * dx + dy * dy) + dz * dz);
    }
  cost_.resize(k);
  for (int i = 0; i < k; ++i) {
    double c = 0;
    for (int j = 0; j < k; ++j) c += a_[j] * apart_[i * k + j];
    cost_[i] = c;
  }
  return first_least(cost_.data(), k);
}

// Rows padded to a multiple of four with zero normals: row j holds the distances of all i, so
// four costs sum side by side, each over j in order. Row j computes the blocks of four from its
// own on; the blocks before it are copied from the rows they hold (|n_j − n_i| is |n_i − n_j| to
// the bit): 37 square roots of four instead of 52 for a ring of 13.
S2C_AVX int RingColumns::median_avx() {
  const int k = k_, kp = (k + 3) & ~3;
  x_.resize(kp, 0.0), y_.resize(kp, 0.0), z_.resize(kp, 0.0);
  apart_.resize(static_cast<std::size_t>(kp) * kp);
  for (int j = 0; j < k; ++j) {
    const __m256d xj = _mm256_set1_pd(x_[j]), yj = _mm256_set1_pd(y_[j]), zj = _mm256_set1_pd(z_[j]);
    for (int i = 0; i < (j & ~3); ++i)
      apart_[static_cast<std::size_t>(j) * kp + i] = apart_[static_cast<std::size_t>(i) * kp + j];
    for (int i = j & ~3; i < kp; i += 4) {
      const __m256d dx = _mm256_sub_pd(_mm256_loadu_pd(&x_[i]), xj);
      const __m256d dy = _mm256_sub_pd(_mm256_loadu_pd(&y_[i]), yj);
      const __m256d dz = _mm256_sub_pd(_mm256_loadu_pd(&z_[i]), zj);
      const __m256d sq = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
      _mm256_storeu_pd(&apart_[static_cast<std::size_t>(j) * kp + i], _mm256_sqrt_pd(sq));
    }
    apart_[static_cast<std::size_t>(j) * kp + j] = 0.0;  // (as on SSE2, even for a normal that is not finite)
  }
  // Up to four blocks' sums at once: each is a chain of dependent additions, and side by side
  // they overlap.
  double cost[4];
  int best = -1;
  double least = std::numeric_limits<double>::infinity();
  for (int i0 = 0; i0 < k; i0 += 16) {
    const int blocks = std::min(4, (kp - i0) / 4);
    __m256d c[4] = {_mm256_setzero_pd(), _mm256_setzero_pd(), _mm256_setzero_pd(), _mm256_setzero_pd()};
    for (int j = 0; j < k; ++j) {
      const __m256d aj = _mm256_set1_pd(a_[j]);
      const double* row = &apart_[static_cast<std::size_t>(j) * kp + i0];
      for (int b = 0; b < blocks; ++b) c[b] = _mm256_add_pd(c[b], _mm256_mul_pd(aj, _mm256_loadu_pd(row + 4 * b)));
    }
    for (int b = 0; b < blocks; ++b) {
      const int i = i0 + 4 * b;
      _mm256_storeu_pd(cost, c[b]);
      const int here = first_least(cost, std::min(4, k - i));
      if (here >= 0 && cost[here] < least) least = cost[here], best = i + here;
    }
  }
  x_.resize(k), y_.resize(k), z_.resize(k);
  return best;
}

}  // namespace s2c::features
