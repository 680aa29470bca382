#pragma once
// Small tables for the few hundred mesh vertices and edges that one hole's computations touch.
#include <climits>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

namespace s2c::repair::fill {

/// Key → value for a few hundred keys: an open-addressing table (linear probing, at most a
/// quarter full, grown by doubling). Every hole asks "is this vertex (edge) one of them, and what
/// is its value" hundreds of times; a binary search per question costs its branch misses, a
/// hash map an allocation per entry. `Key` is int (vertices, never INT_MIN) or std::uint64_t
/// (edge keys, never all ones).
template <class Key, class Value>
class SmallTable {
 public:
  explicit SmallTable(std::size_t expected = 16) { rehash(capacity_for(expected)); }
  /// The value of `k`, nullptr when `k` is not in the table.
  const Value* find(Key k) const {
    if (k == kEmpty) return nullptr;
    for (std::size_t s = slot(k);; s = (s + 1) & mask_) {
      if (keys_[s] == k) return &values_[s];
      if (keys_[s] == kEmpty) return nullptr;
    }
  }
  /// The slot of `k`, added with `value` when missing; second: whether it was added.
  std::pair<Value*, bool> insert(Key k, const Value& value) {
    if (4 * (size_ + 1) > keys_.size()) rehash(2 * keys_.size());
    std::size_t s = slot(k);
    for (; keys_[s] != kEmpty; s = (s + 1) & mask_)
      if (keys_[s] == k) return {&values_[s], false};
    keys_[s] = k;
    values_[s] = value;
    ++size_;
    return {&values_[s], true};
  }
  std::size_t size() const { return size_; }

 private:
  static constexpr Key kEmpty = std::numeric_limits<Key>::min() == 0 ? std::numeric_limits<Key>::max()
                                                                      : std::numeric_limits<Key>::min();
  static std::size_t capacity_for(std::size_t n) {
    std::size_t size = 16;
    while (size < 4 * n) size *= 2;
    return size;
  }
  std::size_t slot(Key k) const {  // Fibonacci hashing: the top bits of k · 2⁶⁴/φ
    return static_cast<std::size_t>((static_cast<std::uint64_t>(k) * 0x9E3779B97F4A7C15ull) >> shift_);
  }
  void rehash(std::size_t size) {
    std::vector<Key> keys(size, kEmpty);
    std::vector<Value> values(size);
    keys.swap(keys_);
    values.swap(values_);
    mask_ = size - 1;
    int bits = 0;
    while ((std::size_t{1} << bits) < size) ++bits;
    shift_ = 64 - bits;
    size_ = 0;
    for (std::size_t i = 0; i < keys.size(); ++i)
      if (keys[i] != kEmpty) insert(keys[i], values[i]);
  }
  std::vector<Key> keys_;
  std::vector<Value> values_;
  std::size_t mask_ = 0, size_ = 0;
  int shift_ = 60;
};

/// Vertex → non-negative int; find() gives -1 for a vertex not in the table.
class VertexTable {
 public:
  explicit VertexTable(std::size_t expected = 16) : table_(expected) {}
  int find(int v) const {
    const int* value = table_.find(v);
    return value ? *value : -1;
  }
  bool contains(int v) const { return table_.find(v) != nullptr; }
  /// Adds v with `value` unless v is there already; true when added.
  bool insert(int v, int value) { return v != INT_MIN && table_.insert(v, value).second; }
  std::size_t size() const { return table_.size(); }

 private:
  SmallTable<int, int> table_;
};

/// Numbers a sorted list of vertices 0, 1, … in their order, so that local order is vertex order.
class LocalIds {
 public:
  /// `sorted`: ascending and unique.
  explicit LocalIds(const std::vector<int>& sorted) : table_(sorted.size()) {
    for (std::size_t i = 0; i < sorted.size(); ++i) table_.insert(sorted[i], static_cast<int>(i));
  }
  /// v's number, -1 when v is not in the list.
  int find(int v) const { return table_.find(v); }
  bool contains(int v) const { return table_.contains(v); }

 private:
  VertexTable table_;
};

}  // namespace s2c::repair::fill
