#pragma once
/// \file Union-find over 0..n-1 with path halving: components of faces, vertices, grid vertices.
#include <atomic>
#include <cstddef>
#include <numeric>
#include <utility>
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

/// DisjointSets for many threads at once: unite() and find() may run side by side. A root is
/// linked by compare-and-swap, always to a smaller index, so parents only decrease and no cycle
/// can form; the sets are those a sequential union of the same pairs gives (their roots may
/// differ).
struct ConcurrentDisjointSets {
  explicit ConcurrentDisjointSets(std::size_t n) : parent(n) {
    for (std::size_t i = 0; i < n; ++i) parent[i].store(static_cast<int>(i), std::memory_order_relaxed);
  }
  int find(int x) {
    for (;;) {
      const int p = parent[x].load(std::memory_order_relaxed);
      if (p == x) return x;
      const int gp = parent[p].load(std::memory_order_relaxed);
      if (gp != p) {  // path halving; if another thread moved x on meanwhile, its value stands
        int expected = p;
        parent[x].compare_exchange_weak(expected, gp, std::memory_order_relaxed);
      }
      x = gp;
    }
  }
  void unite(int a, int b) {
    for (;;) {
      a = find(a), b = find(b);
      if (a == b) return;
      if (a < b) std::swap(a, b);
      int expected = a;  // a is a root unless another thread linked it meanwhile
      if (parent[a].compare_exchange_strong(expected, b, std::memory_order_relaxed)) return;
    }
  }
  /// Points x straight at its root and returns it: once the unions are done, flattening every
  /// element (on any threads) leaves each one step from its root.
  int flatten(int x) {
    const int root = find(x);
    parent[x].store(root, std::memory_order_relaxed);
    return root;
  }
  std::vector<std::atomic<int>> parent;
};

}  // namespace s2c
