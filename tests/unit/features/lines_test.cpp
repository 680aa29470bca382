// Feature lines along a freeform band: on a scan, a rounded edge that no shape explains stays a
// freeform patch between the two faces it joins, and the chain traced along it meets only one of
// them. Its curve is that face's intersection with the shape across the band.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "lines.h"
#include "mesh_arrays.h"
#include "segment.h"

namespace s2c::features {
namespace {

constexpr int kSectors = 96;
constexpr double kHole = 5.0, kBand = 5.3, kOuter = 9.0, kDepth = 4.0, kDrop = 0.3;

/// A plane (z = 0, band ≤ r ≤ kOuter) around a hole of radius kHole, the two joined by a band
/// from r = band at z = 0 down to r = kHole at z = −drop (the rounded rim of a scan; 45° by
/// default), the hole's wall down to z = −kDepth. Faces: plane, then band, then wall, kSectors × 2
/// each.
TriangleSoup rim_with_band(double band = kBand, double drop = kDrop) {
  TriangleSoup s;
  const double rings[4][2] = {{kOuter, 0}, {band, 0}, {kHole, -drop}, {kHole, -kDepth}};
  for (const auto& ring : rings)
    for (int k = 0; k < kSectors; ++k) {
      const double a = 2 * M_PI * k / kSectors;
      s.vertices.emplace_back(ring[0] * std::cos(a), ring[0] * std::sin(a), ring[1]);
    }
  for (int ring = 0; ring < 3; ++ring)
    for (int k = 0; k < kSectors; ++k) {
      const int a = ring * kSectors + k, b = ring * kSectors + (k + 1) % kSectors;
      const int c = a + kSectors, d = b + kSectors;
      // Oriented so that the normals point up out of the plane and into the hole.
      s.faces.push_back({a, c, b});
      s.faces.push_back({b, c, d});
    }
  return s;
}

Segmentation three_patches(const MeshArrays& m) {
  Segmentation seg;
  seg.regions.resize(3);
  seg.face_region.resize(m.faces());
  for (int f = 0; f < m.faces(); ++f) {
    const int r = f / (2 * kSectors);
    seg.face_region[f] = r;
    seg.regions[r].faces.push_back(f);
  }
  Shape& plane = seg.regions[0].fit.shape;
  plane.type = ShapeType::plane;
  plane.point = Eigen::Vector3d::Zero();
  plane.dir = Eigen::Vector3d::UnitZ();
  seg.regions[1].fit.shape.type = ShapeType::freeform;
  Shape& wall = seg.regions[2].fit.shape;
  wall.type = ShapeType::cylinder;
  wall.point = Eigen::Vector3d::Zero();
  wall.dir = Eigen::Vector3d::UnitZ();
  wall.radius = kHole;
  for (auto& r : seg.regions) r.fit.ok = r.fit.shape.type != ShapeType::freeform;
  return seg;
}

/// The rim traced between the plane (region 0) and the band (region 1). A copy: callers pass
/// trace_lines' temporary result.
TracedLine rim(const std::vector<TracedLine>& lines) {
  for (const auto& l : lines)
    if (l.region_a == 0 && l.region_b == 1) return l;
  ADD_FAILURE() << "no line between the plane and the band";
  return {};
}

TEST(FeatureLines, ARimAlongAFreeformBandIsThePlaneMeetingTheShapeAcrossIt) {
  const MeshArrays m = build_arrays(rim_with_band());
  const Segmentation seg = three_patches(m);
  const std::vector<Eigen::Vector3d> normals = m.fnormal;
  const double tolerance = 0.05;
  // Noisy: the chain (r = 5.3) is taken as the plane's circle with the wall (r = 5), within
  // twice the line tolerance of it.
  const TracedLine noisy = rim(trace_lines(m, normals, seg, 25.0, tolerance, true));
  ASSERT_TRUE(noisy.closed);
  EXPECT_EQ(noisy.fit.shape.type, ShapeType::circle);
  EXPECT_NEAR(noisy.fit.shape.radius, kHole, 1e-9);
  EXPECT_NEAR(noisy.fit.shape.point.norm(), 0.0, 1e-9);
  // A clean mesh has no such bands: the chain is fitted as it lies.
  const TracedLine clean = rim(trace_lines(m, normals, seg, 25.0, tolerance, false));
  EXPECT_EQ(clean.fit.shape.type, ShapeType::circle);
  EXPECT_NEAR(clean.fit.shape.radius, kBand, 1e-6);
}

TEST(FeatureLines, TheShapeAcrossTheBandMustMeetThePlaneNearTheChain) {
  // The same rim with a wall of radius 3: its circle lies 2.3 mm inside the chain, far beyond the
  // tolerance, so the chain keeps its own fit.
  const MeshArrays m = build_arrays(rim_with_band());
  Segmentation seg = three_patches(m);
  seg.regions[2].fit.shape.radius = 3.0;
  const TracedLine line = rim(trace_lines(m, m.fnormal, seg, 25.0, 0.05, true));
  EXPECT_EQ(line.fit.shape.type, ShapeType::circle);
  EXPECT_NEAR(line.fit.shape.radius, kBand, 1e-6);
}

TEST(FeatureLines, ThroughAWorkingMeshTheChainsAreAsPreciseAsItsEdge) {
  // A wider band at 45°: the chain (r = 7.5) lies 2.5 mm off the plane's circle with the wall,
  // beyond twice the line tolerance on this mesh's own edges (median 1.5 mm). A segmentation made
  // on a working mesh of 6 mm edges and mapped back draws its borders no closer than that: the
  // circle is taken.
  const MeshArrays m = build_arrays(rim_with_band(7.5, 2.5));
  const Segmentation seg = three_patches(m);
  const TracedLine own = rim(trace_lines(m, m.fnormal, seg, 25.0, 0.05, true));
  EXPECT_EQ(own.fit.shape.type, ShapeType::circle);
  EXPECT_NEAR(own.fit.shape.radius, 7.5, 1e-6);
  const TracedLine working = rim(trace_lines(m, m.fnormal, seg, 25.0, 0.05, true, 6.0));
  EXPECT_EQ(working.fit.shape.type, ShapeType::circle);
  EXPECT_NEAR(working.fit.shape.radius, kHole, 1e-9);
}

TEST(FeatureLines, ANoisyChainThatTurnsACornerIsSplitThereAndEachSideFitted) {
  // A flat 20 × 20 grid whose quadrant x > 10, y > 10 is another patch: the border between the two
  // runs along y = 10, then turns 90° up x = 10, one pair of patches all the way (no junction). The
  // patches' shapes stand square to each other, so the border is a crease. Only its x = 10 half is
  // their intersection (the plane x = 10).
  constexpr int kCells = 20;
  TriangleSoup soup;
  for (int j = 0; j <= kCells; ++j)
    for (int i = 0; i <= kCells; ++i) soup.vertices.emplace_back(i, j, 0);
  for (int j = 0; j < kCells; ++j)
    for (int i = 0; i < kCells; ++i) {
      const int a = j * (kCells + 1) + i, b = a + 1, c = b + kCells + 1, d = a + kCells + 1;
      soup.faces.push_back({a, b, c});
      soup.faces.push_back({a, c, d});
    }
  const MeshArrays m = build_arrays(std::move(soup));
  Segmentation seg;
  seg.regions.resize(2);
  seg.face_region.resize(m.faces());
  for (int f = 0; f < m.faces(); ++f) {
    const Eigen::Vector3d c = m.centroid(f);
    const int r = c.x() > 10 && c.y() > 10 ? 1 : 0;
    seg.face_region[f] = r;
    seg.regions[r].faces.push_back(f);
    seg.regions[r].area += m.farea[f];
  }
  seg.regions[0].fit.shape.type = seg.regions[1].fit.shape.type = ShapeType::plane;
  seg.regions[0].fit.shape.dir = Eigen::Vector3d::UnitZ();
  seg.regions[1].fit.shape.point = Eigen::Vector3d(10, 0, 0);
  seg.regions[1].fit.shape.dir = Eigen::Vector3d::UnitX();
  auto between = [](const std::vector<TracedLine>& lines) {
    std::vector<TracedLine> out;
    for (const auto& l : lines)
      if (l.region_a == 0 && l.region_b == 1) out.push_back(l);
    return out;
  };
  const std::vector<TracedLine> clean = between(trace_lines(m, m.fnormal, seg, 25.0, 0.05, false));
  ASSERT_EQ(clean.size(), 1u);
  EXPECT_EQ(clean[0].fit.shape.type, ShapeType::freeform);
  const std::vector<TracedLine> noisy = between(trace_lines(m, m.fnormal, seg, 25.0, 0.05, true));
  ASSERT_EQ(noisy.size(), 2u);
  for (const auto& l : noisy) {
    ASSERT_EQ(l.fit.shape.type, ShapeType::line);
    EXPECT_NEAR(l.fit.shape.length, 10.0, 1e-9);
    EXPECT_LT(l.fit.rms, 1e-9);
  }
  const bool first_up = std::abs(noisy[0].fit.shape.dir.y()) > 0.5;
  const TracedLine& up = noisy[first_up ? 0 : 1];
  EXPECT_EQ(up.edge_a, 0) << "x = 10 is the two planes' intersection";
  EXPECT_EQ(up.edge_b, 1);
  EXPECT_EQ(noisy[first_up ? 1 : 0].edge_a, -1) << "y = 10 is not";
}

}  // namespace
}  // namespace s2c::features
