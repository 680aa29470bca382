#include "kth_value.h"

#include <algorithm>
#include <array>

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
  // Per block: how many lie below the bracket, inside it, above it, and compare as none (NaN).
  const std::size_t blocks = (n + kBlock - 1) / kBlock;
  std::vector<std::array<std::size_t, 4>> counts(blocks, {0, 0, 0, 0});
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const std::size_t end = std::min(n, (b + 1) * kBlock);
    for (std::size_t i = b * kBlock; i < end; ++i) {
      const double v = values[i];
      ++counts[b][v < lo ? 0 : v > hi ? 2 : v >= lo ? 1 : 3];
    }
  });
  std::size_t under = 0, count = 0, nan = 0;
  for (const auto& c : counts) under += c[0], count += c[1], nan += c[3];
  // With a NaN among them, or a bracket that misses the k-th, the whole set decides.
  if (nan > 0 || k < under || k >= under + count) return whole();
  if (lo == hi) return lo;  // (a CAD mesh's flat edges: most of the values are one)
  // A bracket holding a large share of the values saves nothing.
  if (count > n / 4) return whole();
  std::vector<std::vector<double>> inside(blocks);
  tbb::parallel_for(std::size_t{0}, blocks, [&](std::size_t b) {
    const std::size_t end = std::min(n, (b + 1) * kBlock);
    inside[b].reserve(counts[b][1]);
    for (std::size_t i = b * kBlock; i < end; ++i)
      if (values[i] >= lo && values[i] <= hi) inside[b].push_back(values[i]);
  });
  std::vector<double> bracket;
  bracket.reserve(count);
  for (const auto& part : inside) bracket.insert(bracket.end(), part.begin(), part.end());
  const std::size_t j = k - under;
  std::nth_element(bracket.begin(), bracket.begin() + static_cast<std::ptrdiff_t>(j), bracket.end());
  return bracket[j];
}

}  // namespace s2c::features
