// The small tables of the hole fill (fill/local_ids.h) against std::map.
#include <gtest/gtest.h>

#include <climits>
#include <cstdint>
#include <map>
#include <random>
#include <set>
#include <vector>

#include "fill/local_ids.h"

namespace s2c::repair::fill {
namespace {

TEST(LocalIds, VertexTableAgreesWithAMapThroughGrowth) {
  std::mt19937 rng(5);
  std::uniform_int_distribution<int> vertex(-3, 40000);  // negative keys too, and repeats
  VertexTable table(4);                                  // grows many times
  std::map<int, int> truth;
  for (int i = 0; i < 5000; ++i) {
    const int v = vertex(rng);
    EXPECT_EQ(table.insert(v, i), truth.emplace(v, i).second) << v;
  }
  EXPECT_EQ(table.size(), truth.size());
  for (int v = -3; v <= 40000; ++v) {
    const auto it = truth.find(v);
    ASSERT_EQ(table.find(v), it == truth.end() ? -1 : it->second) << v;
  }
  // The empty marker is never a key.
  EXPECT_FALSE(table.insert(INT_MIN, 1));
  EXPECT_EQ(table.find(INT_MIN), -1);
}

TEST(LocalIds, EdgeTableSumsInInsertionOrder) {
  SmallTable<std::uint64_t, double> table;
  const std::uint64_t a = (std::uint64_t(7) << 32) | 9, b = (std::uint64_t(1) << 40) | 3;
  for (double x : {0.1, 0.2, 0.3}) {
    const auto [sum, added] = table.insert(a, x);
    if (!added) *sum += x;
  }
  table.insert(b, 2.0);
  ASSERT_NE(table.find(a), nullptr);
  EXPECT_EQ(*table.find(a), (0.1 + 0.2) + 0.3);  // bit for bit: the order of a sequential sum
  EXPECT_EQ(*table.find(b), 2.0);
  EXPECT_EQ(table.find(a + 1), nullptr);
  EXPECT_EQ(table.size(), 2u);
}

TEST(LocalIds, NumbersASortedListInItsOrder) {
  const std::vector<int> sorted{2, 3, 17, 100, 4096, 70000};
  const LocalIds local(sorted);
  for (std::size_t i = 0; i < sorted.size(); ++i) EXPECT_EQ(local.find(sorted[i]), static_cast<int>(i));
  for (int v : {0, 1, 4, 99, 101, 69999})
    EXPECT_FALSE(local.contains(v)) << v;
  const LocalIds none({});
  EXPECT_EQ(none.find(2), -1);
}

}  // namespace
}  // namespace s2c::repair::fill
