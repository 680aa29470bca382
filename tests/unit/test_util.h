#pragma once
// Shared helpers for the unit tests: scratch folders, small meshes with known answers.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <string>

#include "s2c/core/errors.h"
#include "s2c/core/mesh.h"

namespace s2c::test {

inline std::filesystem::path source_dir() { return S2C_SOURCE_DIR; }
inline std::filesystem::path shared_dir() { return S2C_SHARED_DIR; }
inline std::filesystem::path bin_dir() { return S2C_BIN_DIR; }

/// A fresh, empty folder per test (removed at the start of the next run, kept for inspection).
inline std::filesystem::path scratch_dir() {
  const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
  auto dir = std::filesystem::temp_directory_path() / "s2c_tests" /
             (std::string(info->test_suite_name()) + "." + info->name());
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

inline void write_text(const std::filesystem::path& p, const std::string& s) {
  std::ofstream f(p, std::ios::binary);
  f << s;
}

/// Axis-aligned cube [lo, lo+size]³, 8 vertices, 12 outward triangles. Vertex indices start at `base`.
inline void add_cube(TriangleSoup& s, const Eigen::Vector3d& lo, double size, bool inward = false) {
  const int b = static_cast<int>(s.vertices.size());
  for (int i = 0; i < 8; ++i)
    s.vertices.push_back(lo + size * Eigen::Vector3d(i & 1, (i >> 1) & 1, (i >> 2) & 1));
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    std::array<int, 3> t1{b + q[0], b + q[1], b + q[2]}, t2{b + q[0], b + q[2], b + q[3]};
    if (inward) {
      std::swap(t1[1], t1[2]);
      std::swap(t2[1], t2[2]);
    }
    s.faces.push_back(t1);
    s.faces.push_back(t2);
  }
}

inline TriangleSoup cube(double size = 10.0) {
  TriangleSoup s;
  add_cube(s, Eigen::Vector3d::Zero(), size);
  return s;
}

/// Expects `f` to throw InvalidInput whose message contains every string of `parts`.
inline void expect_invalid_input(const std::function<void()>& f, std::initializer_list<std::string> parts) {
  try {
    f();
    ADD_FAILURE() << "expected InvalidInput containing '" << *parts.begin() << "'";
  } catch (const InvalidInput& e) {
    for (const auto& part : parts) EXPECT_NE(std::string(e.what()).find(part), std::string::npos) << e.what();
  }
}

/// A flat (n x n)-square grid in z = 0, vertex (i, j) at index i * (n + 1) + j, each square
/// split into two counter-clockwise triangles; squares with keep(i, j) == false are left out.
/// `place` maps grid coordinates to space (to tilt or bend the grid).
TriangleSoup grid(int n, const std::function<bool(int, int)>& keep,
                  const std::function<Eigen::Vector3d(double, double)>& place = nullptr);

/// `s` rotated so that none of an axis-aligned part's faces lies in a grid plane (faces on grid
/// planes make linear interpolation exact and hide what a test is after).
inline TriangleSoup obliquely_rotated(TriangleSoup s, Eigen::Matrix3d* rotation = nullptr) {
  const Eigen::Matrix3d R = (Eigen::AngleAxisd(0.3, Eigen::Vector3d::UnitZ()) *
                             Eigen::AngleAxisd(0.5, Eigen::Vector3d(1, 1, 0).normalized())).toRotationMatrix();
  for (auto& v : s.vertices) v = R * v;
  if (rotation) *rotation = R;
  return s;
}

/// Icosphere: subdivided icosahedron projected to the sphere (outward).
TriangleSoup icosphere(const Eigen::Vector3d& center, double radius, int levels);

/// A surface of revolution about z (outward): rows of `segments` vertices at the heights `zs`
/// (ascending) with radius r(z), every other row staggered by half a segment; closed by a fan
/// at the bottom and/or the top when asked (centre vertices after the rows, bottom first).
TriangleSoup revolved(const std::function<double(double)>& r, const std::vector<double>& zs, int segments,
                      bool close_bottom, bool close_top);

/// Area-uniform samples of a soup, about one per spacing², with the face normal of each; moved
/// along it by Gaussian noise of `sigma` (0: on the surface). Deterministic for a seed.
struct OrientedSamples {
  std::vector<Eigen::Vector3d> points, normals;
};
OrientedSamples sample_surface(const TriangleSoup& soup, double spacing, double sigma = 0, unsigned seed = 1);

}  // namespace s2c::test
