// The ARAP solver alone: rigid motions of the constraints are reproduced exactly (rotations of
// planar and curved cells alike), and a reused factorisation gives the same answer as a fresh one.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "arap.h"
#include "test_util.h"

namespace s2c::edit {
namespace {

// A w×h grid of unit squares bent into a cylinder strip when `bend` (curved cells), flat otherwise.
void grid(int w, int h, bool bend, std::vector<Eigen::Vector3d>& p, std::vector<std::array<int, 3>>& f) {
  for (int j = 0; j <= h; ++j)
    for (int i = 0; i <= w; ++i) {
      const double a = 0.15 * i;
      p.push_back(bend ? Eigen::Vector3d(5 * std::cos(a), 5 * std::sin(a), j) : Eigen::Vector3d(i, j, 0.1 * i * j * 0));
    }
  auto id = [&](int i, int j) { return j * (w + 1) + i; };
  for (int j = 0; j < h; ++j)
    for (int i = 0; i < w; ++i) {
      f.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      f.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
    }
}

void expect_rigid_motion_reproduced(bool bend) {
  std::vector<Eigen::Vector3d> rest;
  std::vector<std::array<int, 3>> faces;
  const int w = 12, h = 8;
  grid(w, h, bend, rest, faces);
  std::vector<int> unknowns;
  for (int j = 1; j < h; ++j)
    for (int i = 1; i < w; ++i) unknowns.push_back(j * (w + 1) + i);
  ArapSolver solver(rest, faces, unknowns);
  const Eigen::Matrix3d r = Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  const Eigen::Vector3d t(3, -1, 2);
  std::vector<Eigen::Vector3d> p = rest;
  for (std::size_t v = 0; v < p.size(); ++v) p[v] = r * rest[v] + t;  // boundary: rigidly moved
  for (int v : unknowns) p[v] = rest[v];                             // interior: left behind
  solver.solve(p, 100, 1e-14);
  for (int v : unknowns) EXPECT_LT((p[v] - (r * rest[v] + t)).norm(), 1e-4) << v;  // linear convergence
}

TEST(Arap, RigidMotionOfAPlanarRegion) { expect_rigid_motion_reproduced(false); }
TEST(Arap, RigidMotionOfACurvedRegion) { expect_rigid_motion_reproduced(true); }

TEST(Arap, ReusedFactorisationMatchesAFreshOne) {
  std::vector<Eigen::Vector3d> rest;
  std::vector<std::array<int, 3>> faces;
  grid(10, 10, false, rest, faces);
  std::vector<int> unknowns;
  for (int j = 1; j < 10; ++j)
    for (int i = 1; i < 10; ++i) unknowns.push_back(j * 11 + i);
  ArapSolver a(rest, faces, unknowns);
  auto lifted = [&](double dz) {
    std::vector<Eigen::Vector3d> p = rest;
    for (int i = 0; i <= 10; ++i) p[10 * 11 + i].z() += dz;  // the top row rises
    return p;
  };
  std::vector<Eigen::Vector3d> p1 = lifted(1.0), p2 = lifted(2.0), q = lifted(2.0);
  a.solve(p1, 50, 1e-12);
  a.solve(p2, 50, 1e-12);
  ArapSolver b(rest, faces, unknowns);
  b.solve(q, 50, 1e-12);
  for (int v : unknowns) EXPECT_LT((p2[v] - q[v]).norm(), 1e-4) << v;
  EXPECT_THROW(ArapSolver(rest, faces, {9999}), ProcessingError);
}

}  // namespace
}  // namespace s2c::edit
