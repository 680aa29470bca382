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

// Rows padded to a multiple of four with zero normals, the whole matrix computed (|n_j − n_i| is
// |n_i − n_j| to the bit): row j holds the distances of all i, so four costs sum side by side,
// each over j in order.
S2C_AVX int RingColumns::median_avx() {
  const int k = k_, kp = (k + 3) & ~3;
  x_.resize(kp, 0.0), y_.resize(kp, 0.0), z_.resize(kp, 0.0);
  apart_.resize(static_cast<std::size_t>(kp) * kp);
  for (int j = 0; j < k; ++j) {
    const __m256d xj = _mm256_set1_pd(x_[j]), yj = _mm256_set1_pd(y_[j]), zj = _mm256_set1_pd(z_[j]);
    for (int i = 0; i < kp; i += 4) {
      const __m256d dx = _mm256_sub_pd(_mm256_loadu_pd(&x_[i]), xj);
      const __m256d dy = _mm256_sub_pd(_mm256_loadu_pd(&y_[i]), yj);
      const __m256d dz = _mm256_sub_pd(_mm256_loadu_pd(&z_[i]), zj);
      const __m256d sq = _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(dx, dx), _mm256_mul_pd(dy, dy)), _mm256_mul_pd(dz, dz));
      _mm256_storeu_pd(&apart_[static_cast<std::size_t>(j) * kp + i], _mm256_sqrt_pd(sq));
    }
    apart_[static_cast<std::size_t>(j) * kp + j] = 0.0;  // (as on SSE2, even for a normal that is not finite)
  }
  double cost[4];
  int best = -1;
  double least = std::numeric_limits<double>::infinity();
  for (int i = 0; i < k; i += 4) {
    __m256d c = _mm256_setzero_pd();
    for (int j = 0; j < k; ++j)
      c = _mm256_add_pd(c, _mm256_mul_pd(_mm256_set1_pd(a_[j]), _mm256_loadu_pd(&apart_[static_cast<std::size_t>(j) * kp + i])));
    _mm256_storeu_pd(cost, c);
    const int here = first_least(cost, std::min(4, k - i));
    if (here >= 0 && cost[here] < least) least = cost[here], best = i + here;
  }
  x_.resize(k), y_.resize(k), z_.resize(k);
  return best;
}

}  // namespace s2c::features
