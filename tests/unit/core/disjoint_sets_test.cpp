// ConcurrentDisjointSets: united from many threads at once, the same sets as DisjointSets.
#include "s2c/core/disjoint_sets.h"

#include <gtest/gtest.h>

#include <random>
#include <utility>
#include <vector>

#include <tbb/parallel_for.h>

namespace {

/// Each element's set, named by its smallest member: comparable between two union-finds whose
/// roots differ.
template <class Sets>
std::vector<int> smallest_member(Sets& sets, int n) {
  std::vector<int> smallest(n, n), out(n);
  for (int i = 0; i < n; ++i) smallest[sets.find(i)] = std::min(smallest[sets.find(i)], i);
  for (int i = 0; i < n; ++i) out[i] = smallest[sets.find(i)];
  return out;
}

}  // namespace

TEST(DisjointSets, ConcurrentUnionsGiveTheSequentialSets) {
  constexpr int kElements = 200000;
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> pick(0, kElements - 1);
  // Long chains (neighbours) and random links: both orders of linking, many shared roots.
  std::vector<std::pair<int, int>> pairs;
  for (int i = 0; i + 1 < kElements; i += 3) pairs.emplace_back(i + 1, i);
  for (int k = 0; k < kElements / 4; ++k) pairs.emplace_back(pick(rng), pick(rng));
  s2c::DisjointSets sequential(kElements);
  for (auto [a, b] : pairs) sequential.unite(a, b);
  for (int round = 0; round < 3; ++round) {
    s2c::ConcurrentDisjointSets concurrent(kElements);
    tbb::parallel_for(std::size_t{0}, pairs.size(), [&](std::size_t k) { concurrent.unite(pairs[k].first, pairs[k].second); });
    tbb::parallel_for(0, kElements, [&](int i) { concurrent.flatten(i); });
    for (int i = 0; i < kElements; ++i)
      ASSERT_EQ(concurrent.parent[i].load(), concurrent.find(i)) << "element " << i << " not flattened";
    EXPECT_EQ(smallest_member(concurrent, kElements), smallest_member(sequential, kElements)) << "round " << round;
  }
}
