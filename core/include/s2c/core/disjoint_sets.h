#pragma once
/// \file Union-find over 0..n-1 with path halving: components of faces, vertices, grid vertices.
#include <cstddef>
#include <numeric>
#include <vector>

namespace s2c {

struct DisjointSets {
  std::vector<int> parent;
  explicit DisjointSets(std::size_t n = 0) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
};

}  // namespace s2c
