// Meshing oriented points through the vector field (contour_oriented_points): on the surface the
// points sample, closed where they cover it, open where they do not, and exact on planes.
#include <gtest/gtest.h>

#include <cmath>
#include <map>

#include "../test_util.h"
#include "s2c/core/check.h"
#include "s2c/core/distance.h"
#include "s2c/core/errors.h"
#include "s2c/repair/volumetric.h"

namespace s2c::repair {
namespace {

using Oriented = test::OrientedSamples;
Oriented sample(const TriangleSoup& s, double spacing, double sigma) { return test::sample_surface(s, spacing, sigma); }

TEST(PointContour, SphereSamplesGiveAClosedSphere) {
  const TriangleSoup sphere = test::icosphere({0, 0, 0}, 10, 5);
  Oriented o = sample(sphere, 0.2, 0);
  for (std::size_t i = 0; i < o.points.size(); ++i) o.normals[i] = o.points[i].normalized();  // the true normals
  PointContourOptions opt;
  opt.voxel = 0.3;
  VolumetricStats st;
  const TriangleSoup out = contour_oriented_points(o.points, o.normals, opt, &st);
  const CheckResult c = check_mesh(out);
  EXPECT_EQ(c.boundary_edges, 0u);
  EXPECT_EQ(c.nonmanifold_edges, 0u);
  EXPECT_GT(c.volume, 0);  // outward normals give an outward-facing surface
  double worst = 0;
  // The icosphere's flat facets are 0.006 mm inside the sphere at most.
  for (const auto& v : out.vertices) worst = std::max(worst, std::abs(v.norm() - 10));
  EXPECT_LT(worst, 0.03);
  EXPECT_GT(st.band_vertices, 10000u);
}

TEST(PointContour, NoisyPlanesAreAveragedAndCornersStayClose) {
  // A rotated box (faces off the grid planes), σ = 0.05 mm along the normals at 0.17 mm spacing:
  // what the fixture scans give the mesher.
  Eigen::Matrix3d R;
  const TriangleSoup box = test::obliquely_rotated(test::cube(20), &R);
  const Oriented o = sample(box, 0.17, 0.05);
  PointContourOptions opt;
  opt.voxel = 0.25;
  opt.radius = 0.625;
  const TriangleSoup out = contour_oriented_points(o.points, o.normals, opt);
  const CheckResult c = check_mesh(out);
  EXPECT_EQ(c.nonmanifold_edges, 0u);
  // Closed on the faces; at a convex edge a cell corner whose closest surface point would lie
  // past the data (the fin test) can open a small gap, never farther than the radius from an edge.
  EXPECT_LT(c.boundary_edges, c.edges / 200);
  std::map<std::pair<int, int>, int> uses;
  for (const auto& f : out.faces)
    for (int k = 0; k < 3; ++k) ++uses[std::minmax(f[k], f[(k + 1) % 3])];
  for (const auto& [e, n] : uses) {
    if (n != 1) continue;
    const Eigen::Vector3d local = R.transpose() * (0.5 * (out.vertices[e.first] + out.vertices[e.second]));
    int at_side = 0;
    for (int k = 0; k < 3; ++k) at_side += std::min(std::abs(local[k]), std::abs(local[k] - 20)) < opt.radius;
    EXPECT_GE(at_side, 2) << "an opening away from the box's edges at " << local.transpose();
  }
  const SurfaceQuery truth(box);
  double sum = 0, worst = 0;
  for (const auto& v : out.vertices) {
    const double d = truth.closest(v)->distance;
    sum += d;
    worst = std::max(worst, d);
  }
  const double mean = sum / static_cast<double>(out.vertices.size());
  EXPECT_LT(mean, 0.015) << "the noise alone is 0.04 mm on average";
  EXPECT_LT(worst, 0.2) << "edges and corners are rounded within the support radius";
}

TEST(PointContour, UnsampledRegionsStayOpen) {
  // A sphere without its cap above z = 6: no surface may be invented over the opening.
  const TriangleSoup sphere = test::icosphere({0, 0, 0}, 10, 5);
  Oriented all = sample(sphere, 0.2, 0), cut;
  for (std::size_t i = 0; i < all.points.size(); ++i)
    if (all.points[i].z() < 6) {
      cut.points.push_back(all.points[i]);
      cut.normals.push_back(all.points[i].normalized());
    }
  PointContourOptions opt;
  opt.voxel = 0.3;
  const TriangleSoup out = contour_oriented_points(cut.points, cut.normals, opt);
  const CheckResult c = check_mesh(out);
  EXPECT_GT(c.boundary_edges, 100u);
  EXPECT_EQ(c.nonmanifold_edges, 0u);
  double top = -1e9;
  for (const auto& v : out.vertices) top = std::max(top, v.z());
  EXPECT_LT(top, 6 + opt.voxel * 2.0) << "the rim may reach past the data by less than the support radius";
  EXPECT_GT(top, 5.5);
}

TEST(PointContour, TwoSidesOfAThinWallDoNotCancelIntoNothingElsewhere) {
  // Two parallel sheets 3 mm apart with opposite normals (a slab seen from both sides): two
  // surfaces, each on its sheet.
  Oriented o;
  for (double x = 0; x <= 20; x += 0.2)
    for (double y = 0; y <= 20; y += 0.2) {
      o.points.emplace_back(x, y, 0);
      o.normals.emplace_back(0, 0, -1);
      o.points.emplace_back(x, y, 3);
      o.normals.emplace_back(0, 0, 1);
    }
  PointContourOptions opt;
  opt.voxel = 0.3;
  const TriangleSoup out = contour_oriented_points(o.points, o.normals, opt);
  std::size_t low = 0, high = 0;
  for (const auto& v : out.vertices) {
    if (v.x() < 1 || v.x() > 19 || v.y() < 1 || v.y() > 19) continue;  // away from the rims
    ASSERT_TRUE(std::abs(v.z()) < 1e-3 || std::abs(v.z() - 3) < 1e-3) << v.transpose();
    (v.z() < 1.5 ? low : high)++;
  }
  EXPECT_GT(low, 1000u);
  EXPECT_GT(high, 1000u);
}

TEST(PointContour, BadInputIsRejected) {
  PointContourOptions opt;
  opt.voxel = 0.3;
  const std::vector<Eigen::Vector3d> none, one{{0, 0, 0}}, up{{0, 0, 1}}, two_normals{{0, 0, 1}, {0, 0, 1}};
  EXPECT_THROW(contour_oriented_points(none, none, opt), InvalidInput);
  EXPECT_THROW(contour_oriented_points(one, two_normals, opt), InvalidInput);
  EXPECT_THROW(contour_oriented_points({{NAN, 0, 0}}, up, opt), InvalidInput);
  PointContourOptions no_voxel;
  EXPECT_THROW(contour_oriented_points(one, up, no_voxel), InvalidInput);
  opt.radius = 10 * opt.voxel;  // beyond the neighbour blocks the gather reads
  EXPECT_THROW(contour_oriented_points(one, up, opt), InvalidInput);
  // One point has too little support for any cell: nothing, but no error.
  opt.radius = 0;
  EXPECT_TRUE(contour_oriented_points(one, up, opt).faces.empty());
}

}  // namespace
}  // namespace s2c::repair
