// kth_value (kth_value.h): the value std::nth_element places at k, on sets large enough for the
// bracketed search, including those where the bracket must fall back.
#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

#include <gtest/gtest.h>

#include "kth_value.h"

namespace s2c::features {
namespace {

double by_nth_element(std::vector<double> values, std::size_t k) {
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
  return values[k];
}

void expect_same(const std::vector<double>& values, const char* what) {
  const std::size_t n = values.size();
  for (std::size_t k : {std::size_t{0}, n / 4, n / 2, n - 1, std::size_t{4097}, n - 4097}) {
    std::vector<double> copy = values;
    EXPECT_EQ(kth_value(copy, k), by_nth_element(values, k)) << what << ", k = " << k << " of " << n;
  }
}

TEST(KthValue, IsTheValueNthElementPlacesThereOnLargeAndSmallSets) {
  std::mt19937 rng(3);
  std::lognormal_distribution<double> spread(0.0, 1.0);
  for (std::size_t n : {std::size_t{10}, std::size_t{70000}, std::size_t{1000003}}) {
    std::vector<double> values(n);
    for (double& v : values) v = spread(rng);
    if (n < 4100) {
      std::vector<double> copy = values;
      EXPECT_EQ(kth_value(copy, n / 2), by_nth_element(values, n / 2));
      continue;
    }
    expect_same(values, "log-normal");
    // Sorted input: the strided sample then sits exactly on the ranks.
    std::sort(values.begin(), values.end());
    expect_same(values, "sorted");
  }
}

TEST(KthValue, ManyEqualValuesAndSkewedSetsStillGiveTheExactValue) {
  // A CAD tessellation's edges: most of one length (the bracket holds them all).
  std::vector<double> equal(300000, 0.25);
  for (std::size_t i = 0; i < equal.size(); i += 7) equal[i] = 0.5;
  expect_same(equal, "two lengths");
  // The values the strided sample sees are all small, the rest large: the bracket misses the
  // upper ranks, and the whole set decides.
  std::vector<double> skewed(200000);
  for (std::size_t i = 0; i < skewed.size(); ++i) skewed[i] = i % (skewed.size() / 4096) == 0 ? 1e-3 * i : 1e3 + i;
  expect_same(skewed, "skewed");
}

TEST(KthValue, ANaNAmongTheValuesLeavesTheAnswerToNthElement) {
  std::vector<double> values(100000);
  for (std::size_t i = 0; i < values.size(); ++i) values[i] = static_cast<double>((i * 7919) % 100000);
  values[12345] = std::numeric_limits<double>::quiet_NaN();
  std::vector<double> copy = values;
  // Whatever nth_element makes of it, kth_value makes the same (it falls back to it).
  const double mine = kth_value(copy, 50000), theirs = by_nth_element(values, 50000);
  EXPECT_TRUE(mine == theirs || (std::isnan(mine) && std::isnan(theirs)));
}

}  // namespace
}  // namespace s2c::features
