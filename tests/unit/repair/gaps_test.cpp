// close_gaps: cracks between surface pieces with non-matching vertices are zipped shut.
#include <cmath>
#include <map>
#include <tuple>

#include "../test_util.h"
#include "s2c/core/check.h"
#include "s2c/repair/gaps.h"
#include "s2c/repair/holes.h"

using namespace s2c;
using repair::close_gaps;
using repair::GapOptions;
using repair::GapStats;

namespace {

/// Adds an (nu x nv) grid over the parallelogram o + s*u + t*v (s, t in [0,1]), triangles
/// counter-clockwise about u x v. Vertices are welded by position within one `weld` map.
void add_grid(TriangleSoup& soup, std::map<std::tuple<long, long, long>, int>& weld, const Eigen::Vector3d& o,
              const Eigen::Vector3d& u, const Eigen::Vector3d& v, int nu, int nv) {
  auto index = [&](int i, int j) {
    const Eigen::Vector3d p = o + u * (double(i) / nu) + v * (double(j) / nv);
    const auto key = std::make_tuple(std::lround(p.x() * 1e6), std::lround(p.y() * 1e6), std::lround(p.z() * 1e6));
    auto it = weld.find(key);
    if (it != weld.end()) return it->second;
    soup.vertices.push_back(p);
    return weld[key] = static_cast<int>(soup.vertices.size()) - 1;
  };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const int a = index(i, j), b = index(i + 1, j), c = index(i + 1, j + 1), d = index(i, j + 1);
      soup.faces.push_back({a, b, c});
      soup.faces.push_back({a, c, d});
    }
}

/// A 10 mm cube whose 5 lower faces are an n1-grid and whose top face is a separate n2-grid
/// shifted up by `lift` (its own vertices, not welded): a crack all around the top rim.
TriangleSoup cube_with_loose_lid(int n1, int n2, double lift) {
  TriangleSoup s;
  std::map<std::tuple<long, long, long>, int> box, lid;
  const double a = 10;
  const Eigen::Vector3d X(a, 0, 0), Y(0, a, 0), Z(0, 0, a), O = Eigen::Vector3d::Zero();
  add_grid(s, box, O, Y, X, n1, n1);          // bottom, normal -z
  add_grid(s, box, O, X, Z, n1, n1);          // y = 0, normal -y
  add_grid(s, box, Y, Z, X, n1, n1);          // y = a, normal +y
  add_grid(s, box, O, Z, Y, n1, n1);          // x = 0, normal -x
  add_grid(s, box, X, Y, Z, n1, n1);          // x = a, normal +x
  add_grid(s, lid, Z + Eigen::Vector3d(0, 0, lift), X, Y, n2, n2);  // top, normal +z
  return s;
}

}  // namespace

TEST(Gaps, TestShapeIsWhatItClaims) {
  const auto welded = cube_with_loose_lid(4, 4, 0);  // separate weld maps: still a crack
  auto r = check_mesh(welded);
  EXPECT_EQ(r.boundary_edges, 32u);
  EXPECT_TRUE(r.oriented);
  const auto lid = cube_with_loose_lid(10, 7, 0.01);
  r = check_mesh(lid);
  EXPECT_EQ(r.boundary_edges, 40u + 28u);
  EXPECT_EQ(r.boundary_loops, 2u);
}

TEST(Gaps, CubeWithShiftedResubdividedLidIsClosed) {
  auto s = cube_with_loose_lid(10, 7, 0.01);
  const GapStats st = close_gaps(s);
  const auto r = check_mesh(s);
  EXPECT_EQ(r.boundary_edges, 0u);
  EXPECT_TRUE(r.closed);
  EXPECT_EQ(r.nonmanifold_edges, 0u);
  EXPECT_EQ(r.nonmanifold_vertices, 0u);
  EXPECT_EQ(r.orientation_conflicts, 0u);
  EXPECT_TRUE(r.oriented);
  EXPECT_EQ(r.degenerate_faces, 0u);
  EXPECT_EQ(r.self_intersections, 0u);
  EXPECT_GT(r.volume, 1000.0 - 1e-9);  // between the box and the box up to the lifted lid
  EXPECT_LT(r.volume, 1001.0 + 1e-9);
  EXPECT_GT(st.contractions, 0u);
  EXPECT_GT(st.edge_splits, 0u);  // 10 vs 7 divisions: most of the rim cannot be welded vertex to vertex
  EXPECT_LE(st.max_distance, 0.0101 * std::sqrt(2.0));
}

TEST(Gaps, TwoGridPatchesWithNonMatchingSpacing) {
  TriangleSoup s;
  std::map<std::tuple<long, long, long>, int> w1, w2;
  add_grid(s, w1, {0, 0, 0}, {10, 0, 0}, {0, 5, 0}, 10, 5);         // y in [0, 5], spacing 1
  add_grid(s, w2, {0, 5.01, 0}, {10, 0, 0}, {0, 5, 0}, 7, 4);       // y in [5.01, 10.01], spacing 1.43 x 1.25
  auto before = check_mesh(s, {false});
  EXPECT_EQ(before.boundary_loops, 2u);
  const GapStats st = close_gaps(s);
  const auto r = check_mesh(s);
  EXPECT_EQ(r.boundary_loops, 1u);  // only the outer rim of the joined rectangle
  EXPECT_EQ(r.boundary_edges, 10u + 7u + 2u * (5u + 4u));
  EXPECT_EQ(r.nonmanifold_edges, 0u);
  EXPECT_EQ(r.nonmanifold_vertices, 0u);
  EXPECT_EQ(r.orientation_conflicts, 0u);
  EXPECT_EQ(r.degenerate_faces, 0u);
  EXPECT_EQ(r.components, 1u);
  EXPECT_GT(st.edge_splits, 0u);
  // The seam is gone: the one hole left is the rim of the 10 x 10.01 rectangle.
  const auto holes = repair::find_holes(s);
  ASSERT_EQ(holes.size(), 1u);
  EXPECT_NEAR(holes[0].perimeter, 40.02, 0.03);
}

TEST(Gaps, UnweldedSeamIsWelded) {
  // An icosphere cut in two along the equator with its seam vertices duplicated (as an STL
  // writer that does not weld would leave it): distance 0, vertex-to-vertex merges.
  auto s = test::icosphere(Eigen::Vector3d::Zero(), 10, 3);
  const int n = static_cast<int>(s.vertices.size());
  std::vector<int> copy(n, -1);
  for (auto& f : s.faces) {
    const double z = s.vertices[f[0]].z() + s.vertices[f[1]].z() + s.vertices[f[2]].z();
    if (z <= 0) continue;
    for (int& v : f) {
      if (copy[v] < 0) {
        copy[v] = static_cast<int>(s.vertices.size());
        s.vertices.push_back(s.vertices[v]);
      }
      v = copy[v];
    }
  }
  ASSERT_GT(check_mesh(s, {false}).boundary_edges, 0u);
  const GapStats st = close_gaps(s);
  const auto r = check_mesh(s);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.oriented);
  EXPECT_EQ(r.nonmanifold_vertices, 0u);
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(st.edge_splits, 0u);
  EXPECT_EQ(st.max_distance, 0.0);
}

TEST(Gaps, LeavesHolesWiderThanTheTolerance) {
  auto s = test::icosphere(Eigen::Vector3d::Zero(), 10, 3);
  std::vector<std::array<int, 3>> kept;
  for (const auto& f : s.faces)
    if (s.vertices[f[0]].z() + s.vertices[f[1]].z() + s.vertices[f[2]].z() < 24) kept.push_back(f);
  s.faces = kept;
  const auto before = check_mesh(s, {false});
  ASSERT_EQ(before.boundary_loops, 1u);
  GapOptions o;
  o.tolerance = 0.05;
  const GapStats st = close_gaps(s, o);
  EXPECT_EQ(st.contractions, 0u);
  EXPECT_EQ(check_mesh(s, {false}).boundary_edges, before.boundary_edges);
}

TEST(Gaps, ClosedMeshIsUntouched) {
  auto s = test::cube(10);
  const auto faces = s.faces;
  const GapStats st = close_gaps(s);
  EXPECT_EQ(st.contractions, 0u);
  EXPECT_EQ(s.faces, faces);
}

TEST(Gaps, NeverCreatesNonManifoldEdgesOnRandomCracks) {
  // Random faces removed from a sphere, generous tolerance: whatever it closes, it must leave an
  // edge-manifold, consistently oriented mesh without degenerate faces.
  for (unsigned seed = 1; seed <= 4; ++seed) {
    auto s = test::icosphere(Eigen::Vector3d::Zero(), 10, 3);
    std::mt19937 rng(seed);
    std::vector<std::array<int, 3>> kept;
    for (const auto& f : s.faces)
      if (std::generate_canonical<double, 32>(rng) < 0.8) kept.push_back(f);
    s.faces = kept;
    GapOptions o;
    o.tolerance = 1.5;
    close_gaps(s, o);
    const auto r = check_mesh(s, {false});
    SCOPED_TRACE(seed);
    EXPECT_EQ(r.nonmanifold_edges, 0u);
    EXPECT_EQ(r.orientation_conflicts, 0u);
    EXPECT_EQ(r.degenerate_faces, 0u);
  }
}
