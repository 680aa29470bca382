// find_holes: single holes, continuous nested holes (the configuration of Fig. 1(b) of
// ../shared/papers/nested-hole-splitting.txt), orientation, termination on adversarial input.
#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <set>

#include "../test_util.h"
#include "s2c/core/check.h"
#include "s2c/repair/holes.h"

using namespace s2c;
using repair::find_holes;
using repair::Hole;
using repair::HoleStats;
using test::grid;

namespace {

bool in_block(int i, int j, int i0, int i1, int j0, int j1) { return i >= i0 && i < i1 && j >= j0 && j < j1; }

/// The orientation contract, checked edge by edge: every free edge a->b of a face (exactly one
/// face on the unordered edge) is traversed b->a by exactly one hole, and every hole edge is
/// such a free edge. Then the fan triangles (loop[0], loop[i], loop[i+1]) agree with the faces.
void expect_holes_cover_free_edges(const TriangleSoup& s, const std::vector<Hole>& holes) {
  std::map<std::pair<int, int>, int> count;  // unordered edge -> faces
  std::set<std::pair<int, int>> directed;
  for (const auto& f : s.faces)
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      ++count[std::minmax(a, b)];
      directed.insert({a, b});
    }
  std::map<std::pair<int, int>, int> used;  // hole half-edge -> times used
  for (const auto& h : holes) {
    ASSERT_GE(h.loop.size(), 3u);
    for (std::size_t i = 0; i < h.loop.size(); ++i) {
      const int a = h.loop[i], b = h.loop[(i + 1) % h.loop.size()];
      EXPECT_EQ(count[std::minmax(a, b)], 1) << "hole edge " << a << "-" << b << " is not a free edge";
      EXPECT_TRUE(directed.count({b, a})) << "hole edge " << a << "->" << b << " runs along its face, not against it";
      ++used[{a, b}];
    }
  }
  std::size_t free_edges = 0;
  for (const auto& [e, c] : count) free_edges += c == 1;
  std::size_t hole_edges = 0;
  for (const auto& [e, c] : used) {
    EXPECT_EQ(c, 1) << "free edge " << e.first << "->" << e.second << " in more than one hole";
    hole_edges += c;
  }
  EXPECT_EQ(hole_edges, free_edges);
}

/// Closes every hole with a star around its centroid: triangles (centre, loop[i], loop[i+1])
/// turn like the contract's fan (loop[0], loop[i], loop[i+1]) but never reuse an existing edge
/// as a chord, so for simple loops the closed, oriented surface must result.
void star_fill(TriangleSoup& s, const std::vector<Hole>& holes) {
  for (const auto& h : holes) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int v : h.loop) c += s.vertices[v];
    s.vertices.push_back(c / static_cast<double>(h.loop.size()));
    const int m = static_cast<int>(s.vertices.size()) - 1;
    for (std::size_t i = 0; i < h.loop.size(); ++i) s.faces.push_back({m, h.loop[i], h.loop[(i + 1) % h.loop.size()]});
  }
}

// Fig. 1(b) on a 14x14 grid: an outer hole R (the 6x6 block [3,9]² without its corner square
// [3,4]², which stays, and without the square [4,5]², an island that touches the rim only at
// C = (4,4)), and three 2x2 holes touching R from outside at its corners A = (9,9), B = (9,3),
// D = (3,9). The paper's answer: the three corner holes, and R with the island's rim inserted
// at C (A-B-C-P6-P4-C-P3-D-A).
bool fig1b_keep(int i, int j) {
  const bool outer = in_block(i, j, 3, 9, 3, 9) && !in_block(i, j, 3, 4, 3, 4) && !in_block(i, j, 4, 5, 4, 5);
  const bool a = in_block(i, j, 9, 11, 9, 11), b = in_block(i, j, 9, 11, 1, 3), d = in_block(i, j, 1, 3, 9, 11);
  return !(outer || a || b || d);
}

void expect_fig1b(const TriangleSoup& s, const std::vector<Hole>& holes, const HoleStats& st) {
  constexpr int n = 14;
  auto v = [](int i, int j) { return i * (n + 1) + j; };
  EXPECT_EQ(st.nested_holes, 1u);   // the one continuous nested hole ...
  EXPECT_EQ(st.single_holes, 1u);   // ... and the grid's own outer rim
  EXPECT_EQ(st.common_points, 4u);  // A, B, C, D
  // Four holes from the nested one, plus the grid rim.
  ASSERT_EQ(holes.size(), 5u);
  EXPECT_EQ(st.holes_out, 5u);
  std::vector<const Hole*> nested;
  for (const auto& h : holes)
    if (h.origin == Hole::Origin::nested) nested.push_back(&h);
  ASSERT_EQ(nested.size(), 4u);
  std::sort(nested.begin(), nested.end(), [](const Hole* a, const Hole* b) { return a->loop.size() < b->loop.size(); });
  // A-P1-A, B-P5-B, D-P2-D: simple loops of 8 around 2x2 squares, each through its corner point.
  const std::set<int> corners = {v(9, 9), v(9, 3), v(3, 9)};
  std::set<int> seen;
  for (int k = 0; k < 3; ++k) {
    EXPECT_EQ(nested[k]->loop.size(), 8u);
    EXPECT_EQ(std::set<int>(nested[k]->loop.begin(), nested[k]->loop.end()).size(), 8u);
    EXPECT_NEAR(nested[k]->perimeter, 8.0, 1e-9);
    EXPECT_NEAR(nested[k]->diameter, std::sqrt(8.0), 1e-9);
    for (int c : corners)
      if (std::count(nested[k]->loop.begin(), nested[k]->loop.end(), c)) seen.insert(c);
  }
  EXPECT_EQ(seen, corners);
  // A-B-C-P6-P4-C-P3-D-A: the 24-vertex rim of R with the island's 4 rim vertices inserted at C,
  // C twice, in this order (counter-clockwise around R, clockwise around the island).
  const auto& big = nested[3]->loop;
  ASSERT_EQ(big.size(), 28u);
  EXPECT_EQ(std::count(big.begin(), big.end(), v(4, 4)), 2);
  EXPECT_EQ(std::set<int>(big.begin(), big.end()).size(), 27u);
  const std::vector<int> expected_piece = {v(3, 4), v(4, 4), v(4, 5), v(5, 5), v(5, 4), v(4, 4), v(4, 3), v(5, 3)};
  bool found = false;
  for (std::size_t t = 0; t < big.size() && !found; ++t) {
    bool match = true;
    for (std::size_t k = 0; k < expected_piece.size() && match; ++k) match = big[(t + k) % big.size()] == expected_piece[k];
    found = match;
  }
  EXPECT_TRUE(found) << "the island is not inserted at C in the expected order: " << ::testing::PrintToString(big);
  EXPECT_NEAR(nested[3]->perimeter, 24.0 + 4.0, 1e-9);
  expect_holes_cover_free_edges(s, holes);
}

}  // namespace

TEST(Holes, ClosedMeshHasNone) {
  HoleStats st;
  EXPECT_TRUE(find_holes(test::cube(), &st).empty());
  EXPECT_EQ(st.boundary_edges, 0u);
  EXPECT_EQ(st.holes_out, 0u);
}

TEST(Holes, SingleHole) {
  auto s = test::cube(10);
  s.faces.erase(s.faces.begin(), s.faces.begin() + 2);  // the bottom square
  HoleStats st;
  const auto holes = find_holes(s, &st);
  ASSERT_EQ(holes.size(), 1u);
  EXPECT_EQ(holes[0].origin, Hole::Origin::single);
  EXPECT_EQ(holes[0].loop.size(), 4u);
  EXPECT_NEAR(holes[0].perimeter, 40.0, 1e-12);
  EXPECT_NEAR(holes[0].diameter, std::sqrt(200.0), 1e-12);
  EXPECT_EQ(st.boundary_edges, 4u);
  EXPECT_EQ(st.single_holes, 1u);
  EXPECT_EQ(st.nested_holes, 0u);
  EXPECT_EQ(st.common_points, 0u);
  expect_holes_cover_free_edges(s, holes);
  star_fill(s, holes);
  const auto r = check_mesh(s);
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.oriented);  // the star closes the cube outward
  EXPECT_NEAR(r.volume, 1000.0, 1e-9);
}

TEST(Holes, SingleHoleInAGrid) {
  const auto s = grid(10, [](int i, int j) { return !in_block(i, j, 3, 6, 3, 6); });
  HoleStats st;
  const auto holes = find_holes(s, &st);
  ASSERT_EQ(holes.size(), 2u);  // the 3x3 hole and the grid's rim
  EXPECT_EQ(st.single_holes, 2u);
  const auto& h = holes[0].loop.size() == 12 ? holes[0] : holes[1];
  EXPECT_EQ(h.loop.size(), 12u);
  EXPECT_NEAR(h.perimeter, 12.0, 1e-12);
  EXPECT_NEAR(h.diameter, std::sqrt(18.0), 1e-12);
  expect_holes_cover_free_edges(s, holes);
}

TEST(Holes, TwoHolesTouchingAtOneVertex) {
  // Squares [2,4]² and [4,6]² removed: two holes with the common point (4,4).
  const auto s = grid(8, [](int i, int j) { return !in_block(i, j, 2, 4, 2, 4) && !in_block(i, j, 4, 6, 4, 6); });
  HoleStats st;
  auto holes = find_holes(s, &st);
  EXPECT_EQ(st.nested_holes, 1u);
  EXPECT_EQ(st.common_points, 1u);
  holes.erase(std::remove_if(holes.begin(), holes.end(), [](const Hole& h) { return h.origin == Hole::Origin::single; }),
              holes.end());
  ASSERT_EQ(holes.size(), 2u);  // not one figure-eight: they touch from outside, nothing to merge
  for (const auto& h : holes) {
    EXPECT_EQ(h.loop.size(), 8u);
    EXPECT_EQ(std::set<int>(h.loop.begin(), h.loop.end()).size(), 8u);
    EXPECT_EQ(std::count(h.loop.begin(), h.loop.end(), 4 * 9 + 4), 1);
  }
  expect_holes_cover_free_edges(s, find_holes(s));
}

TEST(Holes, PaperFigure1b) {
  const auto s = grid(14, fig1b_keep);
  HoleStats st;
  const auto holes = find_holes(s, &st);
  expect_fig1b(s, holes, st);
  EXPECT_EQ(st.boundary_edges, 56u + 24u + 4u + 3u * 8u);
}

TEST(Holes, PaperFigure1bTiltedPlane) {
  // The same, rotated out of the xy plane and shifted: nothing may depend on the axes.
  const Eigen::Matrix3d rot = (Eigen::AngleAxisd(0.7, Eigen::Vector3d(1, 2, 3).normalized())).toRotationMatrix();
  const auto s = grid(14, fig1b_keep, [&](double i, double j) {
    return Eigen::Vector3d(rot * Eigen::Vector3d(i, j, 0) + Eigen::Vector3d(100, -50, 7));
  });
  HoleStats st;
  expect_fig1b(s, find_holes(s, &st), st);
}

TEST(Holes, PaperFigure1bWoundIntoAHelix) {
  // The grid wound as a helical band, 50° per column (the outer hole alone turns 300°, the
  // whole band almost two turns): the best-fit-plane projection folds over itself, so
  // point-in-polygon is meaningless; the local smallest-angle rule must give the same answer.
  const auto s = grid(14, fig1b_keep, [](double i, double j) {
    const double a = i * 50.0 / 180.0 * 3.14159265358979;
    return Eigen::Vector3d(6 * std::cos(a), 6 * std::sin(a), j + 16.0 * a / (2 * 3.14159265358979));
  });
  ASSERT_EQ(check_mesh(s).self_intersections, 0u);
  HoleStats st;
  const auto holes = find_holes(s, &st);
  EXPECT_EQ(st.nested_holes, 1u);
  std::size_t nested = 0, merged = 0;
  for (const auto& h : holes) {
    if (h.origin != Hole::Origin::nested) continue;
    ++nested;
    if (h.loop.size() == 28u) ++merged;
  }
  EXPECT_EQ(nested, 4u);
  EXPECT_EQ(merged, 1u);
  expect_holes_cover_free_edges(s, holes);
}

TEST(Holes, IslandWithANestedHoleOfItsOwn) {
  // A nested hole (rim + island touching at (3,3)) whose island carries a nested hole of its own
  // (rim + island touching at (5,5)). Each rim gets its own island; the hole in the island is
  // not merged into anything outside it.
  // Outer hole [2,12]² minus kept [2,3]² corner and the island [3,11]² (touching at (3,3));
  // in the island, the hole [4,10]² minus kept [4,5]² corner and the island [5,9]² (at (5,5)).
  const auto s = grid(14, [](int i, int j) {
    const bool hole1 = in_block(i, j, 2, 12, 2, 12) && !in_block(i, j, 2, 3, 2, 3) && !in_block(i, j, 3, 11, 3, 11);
    const bool hole2 = in_block(i, j, 4, 10, 4, 10) && !in_block(i, j, 4, 5, 4, 5) && !in_block(i, j, 5, 9, 5, 9);
    return !(hole1 || hole2);
  });
  HoleStats st;
  const auto holes = find_holes(s, &st);
  EXPECT_EQ(st.nested_holes, 2u);
  std::vector<std::size_t> sizes;
  for (const auto& h : holes)
    if (h.origin == Hole::Origin::nested) sizes.push_back(h.loop.size());
  std::sort(sizes.begin(), sizes.end());
  // Hole 1: the rim of [2,12]² without the corner square has 40 vertices, the island [3,11]²
  // rim 32: merged 72 entries.
  // Hole 2: rim of [4,10]² without the corner: 24; island [5,9]² rim: 16; merged 40.
  EXPECT_EQ(sizes, (std::vector<std::size_t>{40u, 72u}));
  expect_holes_cover_free_edges(s, holes);
}

TEST(Holes, CheckerboardOfTouchingHoles) {
  // Every interior vertex of the checkerboard is a common point of two holes.
  const auto s = grid(12, [](int i, int j) { return !(in_block(i, j, 2, 10, 2, 10) && (i + j) % 2 == 0); });
  HoleStats st;
  const auto holes = find_holes(s, &st);
  std::size_t squares = 0;
  for (const auto& h : holes)
    if (h.origin == Hole::Origin::nested) {
      EXPECT_EQ(h.loop.size(), 4u);
      ++squares;
    }
  EXPECT_EQ(squares, 32u);
  EXPECT_EQ(st.nested_holes, 1u);
  expect_holes_cover_free_edges(s, holes);
}

TEST(Holes, LoopsAreConsistentlyOrientedOnASphere) {
  auto s = test::icosphere(Eigen::Vector3d::Zero(), 10, 3);
  // Remove three separate face discs (faces near three directions).
  const std::vector<Eigen::Vector3d> dirs = {{1, 0, 0}, {0, 1, 0}, {-1, -1, -1}};
  std::vector<std::array<int, 3>> kept;
  for (const auto& f : s.faces) {
    const Eigen::Vector3d c = (s.vertices[f[0]] + s.vertices[f[1]] + s.vertices[f[2]]) / 30.0;
    bool drop = false;
    for (const auto& d : dirs) drop = drop || c.dot(d.normalized()) > 0.9;
    if (!drop) kept.push_back(f);
  }
  s.faces = kept;
  HoleStats st;
  const auto holes = find_holes(s, &st);
  EXPECT_EQ(holes.size(), 3u);
  EXPECT_EQ(st.single_holes, 3u);
  expect_holes_cover_free_edges(s, holes);
  star_fill(s, holes);
  const auto r = check_mesh(s, {false});
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.oriented);
  EXPECT_EQ(r.orientation_conflicts, 0u);
}

TEST(Holes, TerminatesOnRandomFaceRemoval) {
  // Adversarial: random removal leaves many holes touching at many vertices, with folds.
  for (const double keep_fraction : {0.9, 0.7, 0.5, 0.3}) {
    for (unsigned seed = 1; seed <= 3; ++seed) {
      auto s = test::icosphere(Eigen::Vector3d::Zero(), 10, 3);
      std::mt19937 rng(seed);
      std::vector<std::array<int, 3>> kept;
      for (const auto& f : s.faces)
        if (std::generate_canonical<double, 32>(rng) < keep_fraction) kept.push_back(f);
      s.faces = kept;
      HoleStats st;
      const auto holes = find_holes(s, &st);
      SCOPED_TRACE(::testing::Message() << "keep " << keep_fraction << " seed " << seed);
      EXPECT_EQ(st.holes_out, holes.size());
      EXPECT_GT(holes.size(), 0u);
      expect_holes_cover_free_edges(s, holes);
      for (const auto& h : holes) {
        EXPECT_GT(h.perimeter, 0);
        EXPECT_GT(h.diameter, 0);
      }
    }
  }
}

TEST(Holes, IgnoresNonManifoldEdgesAndRejectsBadIndices) {
  auto s = test::cube(10);
  s.faces.push_back(s.faces[0]);  // the bottom edge triangle twice: its edges have 2-3 faces
  HoleStats st;
  find_holes(s, &st);  // must not throw or loop
  auto bad = test::cube(10);
  bad.faces[3][1] = 99;
  test::expect_invalid_input([&] { find_holes(bad); }, {"face 3", "99"});
}
