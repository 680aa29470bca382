#pragma once
// A sparse narrow-band grid of 8³-vertex blocks in a hash map: memory grows with the surface
// area, not with the bounding box. A vertex stores the vector to its closest surface point as
// three 16-bit integers scaled to the band radius (the vector is never longer than the band, so
// the quantum is radius/32767, about 1e-4 voxel) and two flag bits: 7 bytes per vertex.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <memory>
#include <unordered_map>
#include <vector>

#include <Eigen/Core>

namespace s2c::repair {

/// kShell: the shell fallback's field (signed distance minus the shell offset; kDeep: inside a
/// decisive inside region, where the signed distance is −d), so crossings lie on the offset surface.
constexpr std::uint8_t kInBand = 1, kInside = 2, kShell = 4, kDeep = 8;

class SparseGrid {
 public:
  static constexpr int kBits = 3, kSide = 1 << kBits, kCount = kSide * kSide * kSide;
  struct Block {
    std::array<std::array<std::int16_t, 3>, kCount> vec;
    std::array<std::uint8_t, kCount> flags{};
  };

  /// \param radius the band radius, mm: the longest vector a vertex can store.
  SparseGrid(const Eigen::Vector3d& origin, double voxel, double radius)
      : origin_(origin), voxel_(voxel), quantum_(radius / 32000.0) {}

  Eigen::Vector3d vector(const Block& b, int i) const {
    return quantum_ * Eigen::Vector3d(b.vec[i][0], b.vec[i][1], b.vec[i][2]);
  }
  void set_vector(Block& b, int i, const Eigen::Vector3d& v) const {
    for (int k = 0; k < 3; ++k) {
      const double q = std::round(v[k] / quantum_);
      b.vec[i][k] = static_cast<std::int16_t>(q < -32767 ? -32767 : q > 32767 ? 32767 : q);
    }
  }

  double voxel() const { return voxel_; }
  /// Offset of the shell fallback, mm (0 when unused); see kShell.
  double shell() const { return shell_; }
  void set_shell(double shell) { shell_ = shell; }
  Eigen::Vector3d position(const Eigen::Vector3i& ijk) const { return origin_ + voxel_ * ijk.cast<double>(); }

  static std::uint64_t key(const Eigen::Vector3i& block) {
    // 21 bits per axis, offset so negative block coordinates stay positive.
    auto u = [](int x) { return std::uint64_t(x + (1 << 20)) & 0x1fffff; };
    return u(block.x()) | (u(block.y()) << 21) | (u(block.z()) << 42);
  }
  /// The block coordinates of a key (the inverse of key()).
  static Eigen::Vector3i block_from_key(std::uint64_t k) {
    auto c = [&](int shift) { return static_cast<int>((k >> shift) & 0x1fffff) - (1 << 20); };
    return {c(0), c(21), c(42)};
  }
  static Eigen::Vector3i block_of(const Eigen::Vector3i& ijk) {
    return {ijk.x() >> kBits, ijk.y() >> kBits, ijk.z() >> kBits};
  }
  static int local_index(const Eigen::Vector3i& ijk) {
    const int m = kSide - 1;
    return (ijk.x() & m) | ((ijk.y() & m) << kBits) | ((ijk.z() & m) << (2 * kBits));
  }
  static Eigen::Vector3i local_coords(int i) { return {i & (kSide - 1), (i >> kBits) & (kSide - 1), i >> (2 * kBits)}; }

  /// Creates the blocks (empty vertices) at the given block coordinates, repeats allowed; call
  /// before filling, not concurrently. Blocks are ordered by key, that is by z, then y, then x
  /// (Marching Cubes sweeps them in that order).
  void allocate(std::vector<Eigen::Vector3i> block_coords) {
    std::sort(block_coords.begin(), block_coords.end(),
              [](const Eigen::Vector3i& p, const Eigen::Vector3i& q) { return key(p) < key(q); });
    block_coords.erase(std::unique(block_coords.begin(), block_coords.end()), block_coords.end());
    blocks_.reserve(block_coords.size());
    for (const auto& b : block_coords) {
      const auto [it, inserted] = map_.emplace(key(b), static_cast<std::int64_t>(blocks_.size()));
      if (!inserted) continue;
      blocks_.push_back(std::make_unique<Block>());
      coords_.push_back(b);
    }
  }
  std::size_t block_count() const { return blocks_.size(); }
  Block& block(std::size_t i) { return *blocks_[i]; }
  const Block& block(std::size_t i) const { return *blocks_[i]; }
  const Eigen::Vector3i& block_coords(std::size_t i) const { return coords_[i]; }
  std::size_t bytes() const { return blocks_.size() * (sizeof(Block) + sizeof(Eigen::Vector3i) + 32); }

  /// Frees a block's storage; block_if_kept then returns nullptr for it. For sweeps that are done
  /// with part of the grid (Marching Cubes frees the z-slabs behind it).
  void release(std::size_t i) { blocks_[i].reset(); }
  /// Block i, or nullptr once released.
  const Block* block_if_kept(std::size_t i) const { return blocks_[i].get(); }

  /// Index of the block at these block coordinates, or -1.
  std::int64_t find_index(const Eigen::Vector3i& block) const {
    const auto it = map_.find(key(block));
    return it == map_.end() ? -1 : it->second;
  }

 private:
  Eigen::Vector3d origin_;
  double voxel_;
  double quantum_;
  double shell_ = 0;
  std::unordered_map<std::uint64_t, std::int64_t> map_{};
  std::vector<std::unique_ptr<Block>> blocks_;
  std::vector<Eigen::Vector3i> coords_;
};

}  // namespace s2c::repair
