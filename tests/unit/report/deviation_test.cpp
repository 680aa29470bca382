#include <gtest/gtest.h>

#include <cmath>
#include <numeric>

#include "s2c/report/deviation.h"
#include "s2c/report/layers.h"
#include "test_util.h"

namespace s2c::report {
namespace {

TEST(Deviation, SphereOutsideIsPositiveInsideNegative) {
  const TriangleSoup reference = test::icosphere(Eigen::Vector3d::Zero(), 10, 5);
  const Deviation out = signed_deviation(test::icosphere(Eigen::Vector3d::Zero(), 10.2, 3), reference);
  EXPECT_NEAR(out.stats.mean, 0.2, 0.01);
  EXPECT_NEAR(out.stats.rms, 0.2, 0.01);
  EXPECT_GT(out.stats.min, 0.0);
  const Deviation in = signed_deviation(test::icosphere(Eigen::Vector3d::Zero(), 9.7, 3), reference);
  EXPECT_NEAR(in.stats.mean, -0.3, 0.01);
  EXPECT_NEAR(in.stats.mean_abs, 0.3, 0.01);
  EXPECT_LT(in.stats.max, 0.0);
  EXPECT_NEAR(in.stats.area, 4 * M_PI * 9.7 * 9.7, 0.02 * 4 * M_PI * 9.7 * 9.7);
}

TEST(Deviation, SignIsRightAtCornersAndEdges) {
  // A cube grown by 0.1 about its centre: every vertex lies off a corner of the reference,
  // where only the pseudo-normal of the corner (not one face's normal) is sure to give the sign.
  const TriangleSoup reference = test::cube(10);
  TriangleSoup grown = reference, shrunk = reference;
  for (auto& p : grown.vertices) p = Eigen::Vector3d::Constant(5) + (p - Eigen::Vector3d::Constant(5)) * 1.02;
  for (auto& p : shrunk.vertices) p = Eigen::Vector3d::Constant(5) + (p - Eigen::Vector3d::Constant(5)) * 0.98;
  const Deviation g = signed_deviation(grown, reference), s = signed_deviation(shrunk, reference);
  for (double d : g.distance) EXPECT_NEAR(d, 0.1 * std::sqrt(3.0), 1e-9);
  for (double d : s.distance) EXPECT_NEAR(d, -0.1, 1e-9);  // inside: the nearest face is 0.1 away
}

TEST(Deviation, HistogramSharesSumToOne) {
  const Deviation d = signed_deviation(test::icosphere(Eigen::Vector3d::Zero(), 10.05, 3), test::icosphere(Eigen::Vector3d::Zero(), 10, 5));
  const double range = default_range(d.stats);
  const auto h = histogram(d, range, 40);
  ASSERT_EQ(h.size(), 42u);
  EXPECT_NEAR(std::accumulate(h.begin(), h.end(), 0.0), 1.0, 1e-9);
  // Everything is about +0.05: in the bins right of zero, none beyond the range.
  EXPECT_EQ(h.front(), 0.0);
  EXPECT_EQ(h.back(), 0.0);
  EXPECT_NEAR(std::accumulate(h.begin() + 21, h.end(), 0.0), 1.0, 1e-9);
}

TEST(Deviation, RangeIsRoundAndCoversTheBulk) {
  DeviationStats s;
  s.p95_abs = 0.037;
  EXPECT_DOUBLE_EQ(default_range(s), 0.05);
  s.p95_abs = 0.3;
  EXPECT_DOUBLE_EQ(default_range(s), 0.5);
  s.p95_abs = 1.7;
  EXPECT_DOUBLE_EQ(default_range(s), 5.0);
  s.p95_abs = 0;
  EXPECT_DOUBLE_EQ(default_range(s), 0.001);
}

TEST(Deviation, ColourScaleGoesBlueGreenRed) {
  const Colour lo = deviation_colour(-1, 1), mid = deviation_colour(0, 1), hi = deviation_colour(1, 1);
  EXPECT_GT(lo.z(), lo.x() + 0.5f);
  EXPECT_GT(mid.y(), mid.x() + 0.4f);
  EXPECT_GT(hi.x(), hi.z() + 0.5f);
  EXPECT_EQ(deviation_colour(5, 1), hi);  // clamped
}

TEST(Deviation, RefusesAnEmptyReference) {
  test::expect_invalid_input([] { signed_deviation(test::cube(), TriangleSoup{}); }, {"reference", "no faces"});
}

TEST(ChangedRegions, FindsTheSurfaceThatIsNew) {
  // A sphere against the same sphere with its top cap cut away: only the cap is "added".
  const TriangleSoup full = test::icosphere(Eigen::Vector3d::Zero(), 10, 3);
  TriangleSoup cut = full;
  cut.faces.clear();
  for (const auto& t : full.faces) {
    bool cap = true;
    for (int v : t) cap &= full.vertices[v].z() > 8;
    if (!cap) cut.faces.push_back(t);
  }
  const ChangedRegions r = changed_regions(full, cut, 1.0, kFilledOrange);
  EXPECT_GT(r.faces, 0u);
  EXPECT_LT(r.faces, full.faces.size() - cut.faces.size());  // the cap's rim is within 1 mm of the cut edge
  EXPECT_EQ(r.layer.face_colours.size(), full.faces.size());
  EXPECT_EQ(changed_regions(full, full, 0.01, kFilledOrange).faces, 0u);
}

}  // namespace
}  // namespace s2c::report

namespace s2c::report {
namespace {

TEST(Deviation, InwardWoundReferenceGivesTheSameSigns) {
  TriangleSoup inward;
  test::add_cube(inward, Eigen::Vector3d::Zero(), 10, /*inward=*/true);
  TriangleSoup grown = test::cube(10);
  for (auto& p : grown.vertices) p = Eigen::Vector3d::Constant(5) + (p - Eigen::Vector3d::Constant(5)) * 1.02;
  for (double d : signed_deviation(grown, inward).distance) EXPECT_GT(d, 0.0);
}

TEST(Deviation, HistogramOfABadRangeIsEmptyNotACrash) {
  const Deviation d = signed_deviation(test::cube(10), test::cube(10));
  for (double range : {0.0, -1.0, std::nan(""), HUGE_VAL}) {
    const auto h = histogram(d, range, 10);
    EXPECT_EQ(h.size(), 12u);
  }
}

}  // namespace
}  // namespace s2c::report
