// The part's unseen end face (trim_end_caps): a turned part whose bottom a scan never saw, its
// rim left jagged by the reconstruction's trimming, is cut flush with one plane and filled flat;
// holes that only look like it (a sphere's pole, a hole in a wall) are left alone.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numeric>

#include <Eigen/Eigenvalues>

#include "s2c/core/check.h"
#include "s2c/repair/fill.h"
#include "s2c/repair/holes.h"
#include "../test_util.h"

namespace s2c::repair {
namespace {

// The fixture shaft's lower end: a 45° chamfer from r = 8 at z = 0 to the r = 10 body at z = 2,
// up to z = 12; the chamfer continues below z = 0 as a Poisson surface does past the data, and
// the faces below a jagged line around z ≈ -0.2 (the trimming) are gone.
TriangleSoup trimmed_shaft() {
  std::vector<double> zs;
  for (double z = -0.5; z < 2 - 1e-9; z += 0.1) zs.push_back(z);
  for (double z = 2; z <= 12 + 1e-9; z += 0.5) zs.push_back(z);
  TriangleSoup s = test::revolved([](double z) { return z < 2 ? 8 + z : 10.0; }, zs, 160, false, true);
  const auto jag = [](const Eigen::Vector3d& c) {
    const double a = std::atan2(c.y(), c.x());
    return -0.2 + 0.08 * std::sin(5 * a) + 0.04 * std::sin(13 * a);
  };
  std::vector<std::array<int, 3>> kept;
  for (const auto& t : s.faces) {
    const Eigen::Vector3d c = (s.vertices[t[0]] + s.vertices[t[1]] + s.vertices[t[2]]) / 3;
    if (c.z() >= jag(c)) kept.push_back(t);
  }
  s.faces = kept;
  return s;
}

// Largest distance of `loop`'s vertices from their least-squares plane.
double off_plane(const TriangleSoup& s, const std::vector<int>& loop) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int v : loop) c += s.vertices[v] / double(loop.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int v : loop) cov += (s.vertices[v] - c) * (s.vertices[v] - c).transpose();
  const Eigen::Vector3d n = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(cov).eigenvectors().col(0);
  double worst = 0;
  for (int v : loop) worst = std::max(worst, std::abs((s.vertices[v] - c).dot(n)));
  return worst;
}

TEST(EndCap, JaggedBottomOfAChamferedShaftIsTrimmedToOnePlaneAndFilledFlat) {
  TriangleSoup s = trimmed_shaft();
  std::vector<Hole> holes = find_holes(s);
  ASSERT_EQ(holes.size(), 1u);
  double highest = -1e9, lowest = 1e9;
  for (int v : holes[0].loop) highest = std::max(highest, s.vertices[v].z()), lowest = std::min(lowest, s.vertices[v].z());
  ASSERT_GT(off_plane(s, holes[0].loop), 0.05);  // jagged: 1.3 % of its diameter, like the scan's

  const auto caps = trim_end_caps(s, holes, {});
  ASSERT_EQ(caps.size(), 1u);
  ASSERT_EQ(holes.size(), 1u);
  EXPECT_TRUE(holes[0].end_cap);
  EXPECT_EQ(caps[0].hole, 0u);
  EXPECT_NEAR(caps[0].depth_mm, highest - lowest, 0.03);
  EXPECT_GT(caps[0].faces_removed, 0u);
  EXPECT_GT(caps[0].faces_clipped, 0u);
  // The new rim lies in one plane through the old rim's highest point (the plane is fitted to
  // the jagged rim: level to 0.1°, measured 0.04°).
  EXPECT_LT(off_plane(s, holes[0].loop), 1e-9);
  for (int v : holes[0].loop) EXPECT_NEAR(s.vertices[v].z(), highest, 0.03);

  const std::size_t before = s.vertices.size();
  const auto r = fill_holes(s, holes);
  ASSERT_TRUE(r[0].filled) << r[0].reason;
  EXPECT_EQ(r[0].method, FillMethod::liepa) << r[0].choice;
  EXPECT_NE(r[0].choice.find("end face"), std::string::npos) << r[0].choice;
  const CheckResult c = check_mesh(s);
  EXPECT_TRUE(c.closed) << to_json(c);
  EXPECT_EQ(c.nonmanifold_edges + c.nonmanifold_vertices + c.orientation_conflicts, 0u) << to_json(c);
  EXPECT_EQ(c.self_intersections + c.degenerate_faces, 0u) << to_json(c);
  EXPECT_EQ(c.components, 1u);  // the bumps of the jagged rim that came loose were removed
  // The fill is flat: every new vertex in the rim's plane.
  ASSERT_GT(s.vertices.size(), before + 100);
  std::vector<int> fill_vertices(s.vertices.size() - before);
  std::iota(fill_vertices.begin(), fill_vertices.end(), static_cast<int>(before));
  fill_vertices.insert(fill_vertices.end(), holes[0].loop.begin(), holes[0].loop.end());
  EXPECT_LT(off_plane(s, fill_vertices), 1e-9);
}

TEST(EndCap, ANonFiniteVertexInTheBandLeavesTheSoupAsItWas) {
  // A NaN corner next to the rim: no cut goes through it, and nothing is changed. A NaN far
  // from the rim does not stop the trim.
  TriangleSoup s = trimmed_shaft();
  std::vector<Hole> holes = find_holes(s);
  ASSERT_EQ(holes.size(), 1u);
  TriangleSoup far = s;
  far.vertices[far.faces.back()[1]] = Eigen::Vector3d::Constant(std::nan(""));  // at the top
  std::vector<Hole> far_holes = holes;
  EXPECT_EQ(trim_end_caps(far, far_holes, {}).size(), 1u);

  int next_to_rim = -1;  // a vertex of a face at the rim that is not on the rim
  const auto on_rim = [&](int v) { return std::find(holes[0].loop.begin(), holes[0].loop.end(), v) != holes[0].loop.end(); };
  for (const auto& t : s.faces) {
    if (!on_rim(t[0])) continue;
    for (int v : t) {
      if (!on_rim(v) && s.vertices[v].z() < s.vertices[t[0]].z() + 0.2) next_to_rim = v;
    }
  }
  ASSERT_GE(next_to_rim, 0);
  s.vertices[static_cast<std::size_t>(next_to_rim)] = Eigen::Vector3d::Constant(std::nan(""));
  const TriangleSoup before = s;
  EXPECT_TRUE(trim_end_caps(s, holes, {}).empty());
  EXPECT_EQ(s.faces, before.faces);
  ASSERT_EQ(s.vertices.size(), before.vertices.size());
  for (std::size_t v = 0; v < s.vertices.size(); ++v) {
    if (before.vertices[v].allFinite()) {
      EXPECT_EQ(s.vertices[v], before.vertices[v]);
    }
  }
}

TEST(EndCap, WithoutTheRuleTheSameHoleBulges) {
  // The test above can fail: with the rule off the hole keeps its jagged rim and RBF domes it.
  TriangleSoup s = trimmed_shaft();
  std::vector<Hole> holes = find_holes(s);
  FillOptions o;
  o.end_cap_tolerance = 0;
  EXPECT_TRUE(trim_end_caps(s, holes, o).empty());
  EXPECT_FALSE(holes[0].end_cap);
  const std::size_t before = s.vertices.size();
  const auto r = fill_holes(s, holes, o);
  ASSERT_TRUE(r[0].filled) << r[0].reason;
  EXPECT_EQ(r[0].method, FillMethod::rbf) << r[0].choice;
  std::vector<int> fill_vertices(s.vertices.size() - before);
  std::iota(fill_vertices.begin(), fill_vertices.end(), static_cast<int>(before));
  EXPECT_GT(off_plane(s, fill_vertices), 0.1);
}

// Faces of `s` whose centroid satisfies `drop` removed.
void remove_faces(TriangleSoup& s, const std::function<bool(const Eigen::Vector3d&)>& drop) {
  std::vector<std::array<int, 3>> kept;
  for (const auto& t : s.faces)
    if (!drop((s.vertices[t[0]] + s.vertices[t[1]] + s.vertices[t[2]]) / 3)) kept.push_back(t);
  s.faces = kept;
}

TEST(EndCap, ARoundHoleAtASpherePoleIsNotAnEndCap) {
  // Planar rim, the whole sphere on one side of it, but the surface around it keeps turning:
  // RBF's job. Nothing is trimmed.
  TriangleSoup s = test::icosphere({0, 0, 0}, 10, 4);
  remove_faces(s, [](const Eigen::Vector3d& c) { return c.normalized().z() > std::cos(25 * M_PI / 180); });
  const TriangleSoup before = s;
  std::vector<Hole> holes = find_holes(s);
  ASSERT_EQ(holes.size(), 1u);
  EXPECT_TRUE(trim_end_caps(s, holes, {}).empty());
  EXPECT_FALSE(holes[0].end_cap);
  EXPECT_EQ(s.faces, before.faces);
  EXPECT_EQ(s.vertices, before.vertices);
}

TEST(EndCap, AHoleInTheWallIsNotAnEndCapButTheBottomStillIs) {
  // Mesh on both sides of the wall hole's plane.
  TriangleSoup s = trimmed_shaft();
  const auto in_wall = [](const Eigen::Vector3d& c) { return c.x() > 5 && std::abs(c.y()) < 2 && std::abs(c.z() - 7) < 2; };
  remove_faces(s, in_wall);
  std::vector<Hole> holes = find_holes(s);
  ASSERT_EQ(holes.size(), 2u);
  const auto caps = trim_end_caps(s, holes, {});
  ASSERT_EQ(caps.size(), 1u);
  ASSERT_EQ(holes.size(), 2u);
  for (const Hole& h : holes) {
    const bool wall = s.vertices[h.loop[0]].z() > 3;
    EXPECT_EQ(h.end_cap, !wall);
  }
  EXPECT_FALSE(holes[caps[0].hole].loop.empty());
  EXPECT_TRUE(holes[caps[0].hole].end_cap);
}

}  // namespace
}  // namespace s2c::repair
