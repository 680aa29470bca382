#include "kth_value.h"

#include <algorithm>

#include <tbb/parallel_for.h>

namespace s2c::features {
namespace {

/// Below this many values one nth_element is as fast.
constexpr std::size_t kParallelFrom = std::size_t{1} << 16;
/// Sample size, and how far either side of the k-th sample the bracket reaches: the k-th
/// value's rank in the sample has a spread of at most sqrt(kSample) / 2 = 32 samples, so the
/// bracket misses it about once in 10^5 calls.
constexpr std::size_t kSample = 4096, kReach = 140;
/// Values per block gathered on one core.
constexpr std::size_t kBlock = std::size_t{1} << 16;

}  // namespace

double kth_value(std::vector<double>& values, std::size_t k) {
  const std::size_t n = values.size();
  auto whole = [&] {
    std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(k), values.end());
    return values[k];
  };
  if (n < kParallelFrom) return whole();
  std::vector<double> sample(kSample);
  for (std::size_t i = 0; i < kSample; ++i) sample[i] = values[i * (n / kSample)];
  std::sort(sample.begin(), sample.end());
  const std::size_t at = std::min(kSample - 1, k / (n / kSample));
  const double lo = sample[at > kReach ? at - kReach : 0], hi = sample[std::min(kSample - 1, at + kReach)];
  // Per block: how many lie below the bracket and above it, and those inside it.
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::size_t> below(blocks, 0), above(blocks, 0);
  std::vector<std::vector<double>> inside(blocks);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const std::size_t end = std::min(n, (b + 1) * kBlock);
    for (std::size_t i = b * kBlock; i < end; ++i) {
      const double v = values[i];
      if (v < lo) ++below[b];
      else if (v > hi) ++above[b];
      else if (v <= hi) inside[b].push_back(v);
    }
  });
  std::size_t under = 0, over = 0, count = 0;
  for (std::size_t b = 0; b < blocks; ++b) under += below[b], over += above[b], count += inside[b].size();
  // Values that compare as none of the three (NaN) leave the counts short: then, as when the
  // bracket misses, the whole set decides.
  if (under + count + over != n || k < under || k >= under + count) return whole();
  std::vector<double> bracket;
  bracket.reserve(count);
  for (const auto& part : inside) bracket.insert(bracket.end(), part.begin(), part.end());
  const std::size_t j = k - under;
  std::nth_element(bracket.begin(), bracket.begin() + static_cast<std::ptrdiff_t>(j), bracket.end());
  return bracket[j];
}

}  // namespace s2c::features
