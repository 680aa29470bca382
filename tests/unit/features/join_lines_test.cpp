// One CAD edge as one feature line on a noisy mesh (join_lines.h): a scan rounds the edge between
// two faces into a band, the band pinches or breaks into other patches, and the chain along the
// edge changes its pair of patches there. The pieces are the same two planes' intersection: one
// line, ends at its corners. A cut across the edge keeps the pieces apart.
#include <cmath>
#include <vector>

#include <gtest/gtest.h>

#include "join_lines.h"
#include "lines.h"
#include "mesh_arrays.h"
#include "segment.h"

namespace s2c::features {
namespace {

using Eigen::Vector3d;

constexpr double kLength = 20.0, kStep = 0.5;         // along the edge (x)
constexpr double kWidth = 6.0, kRound = 0.3, kHeight = 6.0;
constexpr int kTop = 0, kBand = 1, kSide = 2, kCap = 3;

/// The edge y = z = 0 of a top face (z = 0, y < 0) and a side face (y = 0, z < 0), rounded by a
/// 45° band of width kRound√2, from x = 0 to kLength, with a cap face x = kLength. The profile
/// (y, z) runs (−kWidth, 0) → (−kWidth/2, 0) → (−kRound, 0) → (0, −kRound) → (0, −kHeight):
/// strips 0–1 are the top, 2 the band, 3 the side, two faces per step each, then the cap's fan.
struct Strip {
  TriangleSoup soup;
  int steps = static_cast<int>(kLength / kStep);
  int strip_faces = 2 * static_cast<int>(kLength / kStep);
};

Strip strip() {
  Strip s;
  const double profile[5][2] = {{-kWidth, 0}, {-kWidth / 2, 0}, {-kRound, 0}, {0, -kRound}, {0, -kHeight}};
  for (const auto& p : profile)
    for (int i = 0; i <= s.steps; ++i) s.soup.vertices.emplace_back(i * kStep, p[0], p[1]);
  const int row = s.steps + 1;
  for (int k = 0; k < 4; ++k)
    for (int i = 0; i < s.steps; ++i) {
      const int a = k * row + i, b = a + 1, c = b + row, d = a + row;
      s.soup.faces.push_back({a, b, c});
      s.soup.faces.push_back({a, c, d});
    }
  // The cap: a fan about its middle over the profile closed by (−kWidth, −kHeight), facing +x.
  const int corner = static_cast<int>(s.soup.vertices.size());
  s.soup.vertices.emplace_back(kLength, -kWidth, -kHeight);
  const int middle = corner + 1;
  s.soup.vertices.emplace_back(kLength, -kWidth / 2, -kHeight / 2);
  const int ring[6] = {s.steps, row + s.steps, 2 * row + s.steps, 3 * row + s.steps, 4 * row + s.steps, corner};
  for (int k = 0; k < 6; ++k) s.soup.faces.push_back({middle, ring[(k + 1) % 6], ring[k]});
  return s;
}

Shape plane(const Vector3d& point, const Vector3d& normal) {
  Shape p;
  p.type = ShapeType::plane;
  p.point = point;
  p.dir = normal;
  return p;
}

/// Top, band (freeform), side and cap; `region_of` may move faces to other regions.
Segmentation segmentation(const MeshArrays& m, const Strip& s, int regions,
                          int (*region_of)(int face, int strip, double x)) {
  Segmentation seg;
  seg.regions.resize(regions);
  seg.face_region.resize(m.faces());
  for (int f = 0; f < m.faces(); ++f) {
    const int strip_index = f < 4 * s.strip_faces ? f / s.strip_faces : 4;
    const int natural = strip_index <= 1 ? kTop : strip_index == 2 ? kBand : strip_index == 3 ? kSide : kCap;
    const int r = region_of ? region_of(f, natural, m.centroid(f).x()) : natural;
    seg.face_region[f] = r;
    seg.regions[r].faces.push_back(f);
    seg.regions[r].area += m.farea[f];
  }
  seg.regions[kTop].fit.shape = plane(Vector3d::Zero(), Vector3d::UnitZ());
  seg.regions[kSide].fit.shape = plane(Vector3d::Zero(), Vector3d::UnitY());
  seg.regions[kCap].fit.shape = plane(Vector3d(kLength, 0, 0), Vector3d::UnitX());
  for (auto& r : seg.regions) r.fit.ok = r.fit.shape.type != ShapeType::freeform;
  return seg;
}

/// The lines fitted as the edge of the top and the side.
std::vector<TracedLine> edges(const std::vector<TracedLine>& lines) {
  std::vector<TracedLine> out;
  for (const auto& l : lines)
    if (l.edge_a == kTop && l.edge_b == kSide && l.fit.shape.type == ShapeType::line) out.push_back(l);
  return out;
}

constexpr double kTolerance = 0.05, kMinCrease = 25.0;

TEST(JoinLines, AnEdgeTracedInPiecesAlongAPinchedBandIsOneLineToItsCorner) {
  // The band pinches out for x in [4, 5) and [11, 12.5): the top meets the side directly there,
  // so the chain along the edge changes its pair of patches four times.
  const Strip s = strip();
  const MeshArrays m = build_arrays(TriangleSoup(s.soup));
  const Segmentation seg = segmentation(m, s, 4, [](int, int natural, double x) {
    const bool pinched = (x > 4 && x < 5) || (x > 11 && x < 12.5);
    return natural == kBand && pinched ? kTop : natural;
  });
  // A clean mesh has no bands: its chains are fitted as they lie, pieces along the edge.
  int along = 0;
  for (const auto& l : trace_lines(m, m.fnormal, seg, kMinCrease, kTolerance, false))
    along += l.fit.shape.type == ShapeType::line && std::abs(l.fit.shape.dir.x()) > 0.99 &&
             std::hypot(l.fit.shape.point.y(), l.fit.shape.point.z()) < 0.5;
  EXPECT_GE(along, 3);

  const std::vector<TracedLine> noisy = edges(trace_lines(m, m.fnormal, seg, kMinCrease, kTolerance, true));
  ASSERT_EQ(noisy.size(), 1u);
  const Shape& line = noisy.front().fit.shape;
  EXPECT_NEAR(std::abs(line.dir.x()), 1.0, 1e-9);
  EXPECT_NEAR(std::hypot(line.point.y(), line.point.z()), 0.0, 1e-9);
  // From the mesh's open end at x = 0 to the cap's plane at x = kLength.
  const double lo = std::min(line.point.x(), line.point.x() + line.length * line.dir.x());
  EXPECT_NEAR(lo, 0.0, 1e-9);
  EXPECT_NEAR(line.length, kLength, 1e-9);
  EXPECT_LE(noisy.front().fit.rms, 2 * std::hypot(kTolerance, 0.5 * m.median_edge));
  // Its vertices are the pieces' own, in order along the edge.
  double last = -1;
  for (int v : noisy.front().vertices) {
    EXPECT_GE(m.pos[v].x(), last - 1e-9);
    last = m.pos[v].x();
  }
  EXPECT_GT(noisy.front().vertices.size(), static_cast<std::size_t>(s.steps));
}

TEST(JoinLines, ACutAcrossTheEdgeKeepsItsPiecesApart) {
  // A large patch (a slot's wall, here a plane across the edge) for x in [9, 10.5): the pieces on
  // either side are the same two planes' intersection, 1.5 mm apart, but the mesh between them is
  // the cut's: two lines, each ending where the cut's plane crosses the edge.
  const Strip s = strip();
  const MeshArrays m = build_arrays(TriangleSoup(s.soup));
  Segmentation seg = segmentation(m, s, 5, [](int, int natural, double x) {
    return natural != kCap && x > 9 && x < 10.5 ? 4 : natural;
  });
  seg.regions[4].fit.shape = plane(Vector3d(9.75, 0, 0), Vector3d::UnitX());
  seg.regions[4].fit.ok = true;
  const std::vector<TracedLine> pieces = edges(trace_lines(m, m.fnormal, seg, kMinCrease, kTolerance, true));
  ASSERT_EQ(pieces.size(), 2u);
  for (const auto& l : pieces) {
    const Shape& line = l.fit.shape;
    const double a = line.point.x(), b = a + line.length * line.dir.x();
    EXPECT_TRUE(std::abs(std::max(a, b) - 9.75) < 1e-9 || std::abs(std::min(a, b) - 9.75) < 1e-9)
        << "a piece from " << a << " to " << b;
  }
}

TEST(JoinLines, AnEndMovesOnlyToAPlaneWhosePatchIsThere) {
  // A line along the edge that stops short of the cap (x from 1 to kLength − 1.5), and a plane
  // x = kLength − 1 nearer to its end but whose patch (the top's outer half, y ≤ −kWidth/2) lies far
  // from the edge: the end moves to the cap.
  const Strip s = strip();
  const MeshArrays m = build_arrays(TriangleSoup(s.soup));
  Segmentation seg = segmentation(m, s, 5, [](int f, int natural, double) {
    return natural == kTop && f < Strip{}.strip_faces ? 4 : natural;  // the outer strip of the top
  });
  seg.regions[4].fit.shape = plane(Vector3d(kLength - 1, 0, 0), Vector3d::UnitX());
  seg.regions[4].fit.ok = true;
  std::vector<TracedLine> lines(4);
  lines[0].region_a = lines[0].edge_a = kTop;
  lines[0].region_b = lines[0].edge_b = kSide;
  lines[0].fit.shape.type = ShapeType::line;
  lines[0].fit.shape.point = Vector3d(1, 0, 0);
  lines[0].fit.shape.dir = Vector3d::UnitX();
  lines[0].fit.shape.length = kLength - 2.5;
  // The patch pairs that meet: the cap and the far plane are both next to the top and the side.
  const int pairs[3][2] = {{kTop, kCap}, {kSide, kCap}, {4, kBand}};
  for (int k = 0; k < 3; ++k) lines[k + 1].region_a = pairs[k][0], lines[k + 1].region_b = pairs[k][1];
  lines.emplace_back();
  lines.back().region_a = kTop, lines.back().region_b = kBand;
  lines.emplace_back();
  lines.back().region_a = kSide, lines.back().region_b = kBand;
  const RegionNeighbours neighbours(seg, lines);
  ASSERT_TRUE(neighbours.adjacent(4, kSide)) << "through the band";
  end_at_corners(m, seg, neighbours, 0.0, 2.0, lines);
  const Shape& line = lines[0].fit.shape;
  EXPECT_NEAR(line.point.x(), 1.0, 1e-12) << "no plane cuts the edge near its start";
  EXPECT_NEAR(line.point.x() + line.length, kLength, 1e-9);
  // Out of reach, the end stays.
  lines[0].fit.shape.length = kLength - 4.5;
  end_at_corners(m, seg, neighbours, 0.0, 2.0, lines);
  EXPECT_NEAR(lines[0].fit.shape.length, kLength - 4.5, 1e-12);
}

}  // namespace
}  // namespace s2c::features
