// Tests for core/predicates.h: exactness of orient2d/orient3d, triangle–triangle cases that
// defeat floating point, the shared-vertex rules of faces_self_intersect, and agreement with
// CGAL on pairs recorded by tools/cgal_check (tests/data/*_cgal.txt). Regenerate those with
//   cgal_check --random-tri-tri 20000 1 > tests/data/tri_tri_cgal.txt
//   cgal_check --random-face-pairs 5000 2 > tests/data/face_pairs_cgal.txt
// (the generator is platform-independent, so the files come out byte-identical).
#include "s2c/core/predicates.h"

#include <cmath>
#include <cstdlib>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include <gtest/gtest.h>

namespace {

using s2c::faces_self_intersect;
using s2c::orient2d;
using s2c::orient3d;
using s2c::triangles_intersect;
using V3 = Eigen::Vector3d;
using V2 = Eigen::Vector2d;
using Tri = std::array<V3, 3>;
using Ids = std::array<int, 3>;

std::string data_dir() {
#ifdef S2C_TEST_DATA_DIR
  return S2C_TEST_DATA_DIR;
#else
  // tests/unit/core/predicates_test.cpp -> tests/data
  std::string f = __FILE__;
  return f.substr(0, f.rfind("/unit/")) + "/data";
#endif
}

Tri scaled(const Tri& t, double s) { return {t[0] * s, t[1] * s, t[2] * s}; }
Tri shifted(const Tri& t, const V3& d) { return {t[0] + d, t[1] + d, t[2] + d}; }

// Both argument orders and all vertex rotations/reflections must agree.
bool intersect_sym(const Tri& t, const Tri& u) {
  const bool r = triangles_intersect(t, u);
  EXPECT_EQ(r, triangles_intersect(u, t));
  EXPECT_EQ(r, triangles_intersect(Tri{t[1], t[2], t[0]}, Tri{u[0], u[2], u[1]}));
  EXPECT_EQ(r, triangles_intersect(Tri{u[2], u[1], u[0]}, Tri{t[2], t[0], t[1]}));
  return r;
}

bool faces_sym(const Tri& p, const Ids& pi, const Tri& q, const Ids& qi) {
  const bool r = faces_self_intersect(p, pi, q, qi);
  EXPECT_EQ(r, faces_self_intersect(q, qi, p, pi));
  EXPECT_EQ(r, faces_self_intersect(Tri{p[1], p[2], p[0]}, Ids{pi[1], pi[2], pi[0]}, Tri{q[0], q[2], q[1]},
                                    Ids{qi[0], qi[2], qi[1]}));
  return r;
}

// ---- orient2d / orient3d ---------------------------------------------------------------

TEST(Predicates, OrientBasicSignsAndPermutations) {
  const V3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), d(0, 0, 1);
  EXPECT_EQ(orient3d(a, b, c, d), 1);
  EXPECT_EQ(orient3d(a, c, b, d), -1);
  EXPECT_EQ(orient3d(b, c, d, a), -1);  // odd permutation of (a, b, c, d)
  EXPECT_EQ(orient3d(a, b, c, V3(3, -7, 0)), 0);
  EXPECT_EQ(orient3d(a, a, c, d), 0);
  EXPECT_EQ(orient2d(V2(0, 0), V2(1, 0), V2(0, 1)), 1);
  EXPECT_EQ(orient2d(V2(0, 0), V2(0, 1), V2(1, 0)), -1);
  EXPECT_EQ(orient2d(V2(0, 0), V2(1, 1), V2(3, 3)), 0);
}

// The classic example (Kettner et al., "Classroom examples of robustness problems"): p just
// off the line y = x, q = (12, 12), r = (24, 24). Exactly, orient2d(p, q, r) = sign(py - px).
TEST(Predicates, OrientExactWhereFloatFails) {
  const double u = std::ldexp(1.0, -53);  // ulp of values in [0.5, 1)
  int naive_wrong = 0;
  for (int i = 0; i < 64; ++i)
    for (int j = 0; j < 64; ++j) {
      const V2 p(0.5 + i * u, 0.5 + j * u), q(12, 12), r(24, 24);
      const int expected = (j > i) - (j < i);
      ASSERT_EQ(orient2d(p, q, r), expected) << i << " " << j;
      ASSERT_EQ(orient3d(V3(p.x(), p.y(), 0), V3(12, 12, 0), V3(24, 24, 0), V3(0, 0, 1)), expected) << i << " " << j;
      const double naive = (q.x() - p.x()) * (r.y() - p.y()) - (q.y() - p.y()) * (r.x() - p.x());
      naive_wrong += ((naive > 0) - (naive < 0)) != expected;
    }
  EXPECT_GT(naive_wrong, 0) << "the grid no longer defeats naive floating point; the test lost its power";
}

TEST(Predicates, OrientSurvivesUnderflowAndOverflow) {
  const V3 a(0, 0, 0), b(1, 0, 0), c(0, 1, 0), d(0.25, 0.5, 3);
  for (double s : {std::ldexp(1.0, -1060), 1e-300, std::ldexp(1.0, -1000), 1e300, std::ldexp(1.0, 1000)}) {
    EXPECT_EQ(orient3d(a * s, b * s, c * s, d * s), 1) << s;
    EXPECT_EQ(orient3d(a * s, c * s, b * s, d * s), -1) << s;
    EXPECT_EQ(orient2d(V2(0, 0) * s, V2(1, 0) * s, V2(0.25, 1e-3) * s), 1) << s;
  }
  // Huge coordinates whose differences overflow.
  const double big = 1.7e308;
  EXPECT_EQ(orient2d(V2(-big, -big), V2(big, -big), V2(0, big)), 1);
  EXPECT_EQ(orient3d(V3(-big, -big, -big), V3(big, -big, -big), V3(-big, big, -big), V3(-big, -big, big)), 1);
  // Smallest subnormal offsets off a plane are still seen.
  const double tiny = std::nextafter(0.0, 1.0);
  EXPECT_EQ(orient3d(V3(0, 0, 0), V3(1, 0, 0), V3(0, 1, 0), V3(0.3, 0.3, tiny)), 1);
  EXPECT_EQ(orient3d(V3(0, 0, 0), V3(1, 0, 0), V3(0, 1, 0), V3(0.3, 0.3, -tiny)), -1);
}

// Scaling each axis by its own power of two multiplies the determinants by a positive power
// of two, so the signs must not change: near-degenerate configurations (integer grid plus
// one-ulp nudges) at per-axis scales from 2^-1000 to 2^1000, where products underflow or
// overflow and a filter without a valid error bound returns wrong signs.
TEST(Predicates, OrientInvariantUnderPerAxisPowerOfTwoScaling) {
  std::mt19937_64 gen(12345);
  auto grid = [&] { return static_cast<double>(static_cast<int>(gen() % 7) - 3); };
  auto nudge = [&](double x) {  // never from 0: a subnormal would not scale exactly
    const int steps = x == 0 ? 0 : static_cast<int>(gen() % 3);
    for (int i = 0; i < steps; ++i) x = std::nextafter(x, (gen() & 1) ? 8.0 : -8.0);
    return x;
  };
  int nonzero = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    V3 p[4];
    for (auto& v : p) v = V3(nudge(grid()), nudge(grid()), nudge(grid()));
    const int reference3 = orient3d(p[0], p[1], p[2], p[3]);
    const int reference2 = orient2d(p[0].head<2>(), p[1].head<2>(), p[2].head<2>());
    nonzero += reference3 != 0;
    for (int k = 0; k < 8; ++k) {
      const int ex = static_cast<int>(gen() % 2001) - 1000, ey = static_cast<int>(gen() % 2001) - 1000,
                ez = static_cast<int>(gen() % 2001) - 1000;
      V3 s[4];
      for (int i = 0; i < 4; ++i) s[i] = V3(std::ldexp(p[i].x(), ex), std::ldexp(p[i].y(), ey), std::ldexp(p[i].z(), ez));
      ASSERT_EQ(orient3d(s[0], s[1], s[2], s[3]), reference3) << trial << " " << ex << " " << ey << " " << ez;
      ASSERT_EQ(orient2d(s[0].head<2>(), s[1].head<2>(), s[2].head<2>()), reference2)
          << trial << " " << ex << " " << ey;
    }
  }
  EXPECT_GT(nonzero, 1000);
}

TEST(Predicates, OrientPointOneTwoThree) {
  // 0.1 + 0.2 != 0.3 in doubles: (0.1+0.2, 0, 0) lies off the line/plane through (0.3, 0, 0).
  const double s = 0.1 + 0.2;
  EXPECT_EQ(orient2d(V2(0.3, -1), V2(0.3, 1), V2(s, 0)), -1);
  EXPECT_EQ(orient2d(V2(0.3, -1), V2(0.3, 1), V2(0.3, 0)), 0);
  EXPECT_EQ(orient3d(V3(0.3, 0, 0), V3(0.3, 1, 0), V3(0.3, 0, 1), V3(s, 0.5, 0.5)), 1);
  // Points on the line x = y = z through decimal values are exactly collinear.
  EXPECT_EQ(orient2d(V2(0.1, 0.1), V2(0.7, 0.7), V2(s, s)), 0);
}

// ---- triangles_intersect ---------------------------------------------------------------

const Tri kUnit{V3(0, 0, 0), V3(1, 0, 0), V3(0, 1, 0)};

TEST(Predicates, TrianglesSeparatedAndCrossing) {
  EXPECT_FALSE(intersect_sym(kUnit, shifted(kUnit, V3(0, 0, 1))));
  EXPECT_FALSE(intersect_sym(kUnit, Tri{V3(2, 2, -1), V3(2, 3, 1), V3(3, 2, 1)}));
  // Straddles the plane of kUnit but misses the triangle.
  EXPECT_FALSE(intersect_sym(kUnit, Tri{V3(0.6, 0.6, -1), V3(0.6, 0.6, 1), V3(2, 2, 0)}));
  EXPECT_TRUE(intersect_sym(kUnit, Tri{V3(0.2, 0.2, -1), V3(0.2, 0.2, 1), V3(2, 2, 0)}));
  EXPECT_TRUE(intersect_sym(kUnit, Tri{V3(0.25, -1, -1), V3(0.25, 3, -1), V3(0.25, 0.5, 1)}));
}

TEST(Predicates, TrianglesTouching) {
  // At a vertex of both.
  EXPECT_TRUE(intersect_sym(kUnit, Tri{V3(1, 0, 0), V3(2, 0, 1), V3(2, 1, 1)}));
  // A vertex of one on the interior of the other.
  EXPECT_TRUE(intersect_sym(kUnit, Tri{V3(0.25, 0.25, 0), V3(1, 1, 1), V3(-1, 1, 1)}));
  // Edge crossing edge at one point (0.5, 0, 0), not coplanar; the rest of q is apart.
  const Tri q{V3(0.5, -1, 1), V3(0.5, 1, -1), V3(0.5, -2, -2)};
  EXPECT_TRUE(intersect_sym(kUnit, q));
  // The same, moved by 2^-50 in y: separated one way, overlapping the other way.
  const double e = std::ldexp(1.0, -50);
  EXPECT_FALSE(intersect_sym(kUnit, shifted(q, V3(0, -e, 0))));
  EXPECT_TRUE(intersect_sym(kUnit, shifted(q, V3(0, e, 0))));
  // An edge of q lying in the plane of kUnit, crossing its edge.
  EXPECT_TRUE(intersect_sym(kUnit, Tri{V3(0.5, -0.5, 0), V3(0.5, 0.5, 0), V3(0.5, 0, 1)}));
  EXPECT_FALSE(intersect_sym(kUnit, Tri{V3(0.5, -0.5, std::nextafter(0.0, 1.0)), V3(0.5, 0.5, std::nextafter(0.0, 1.0)),
                                        V3(0.5, 0, 1)}));
  // Edge lying along an edge (collinear overlap), different planes.
  EXPECT_TRUE(intersect_sym(kUnit, Tri{V3(0.5, 0, 0), V3(2, 0, 0), V3(1, 0, 1)}));
}

TEST(Predicates, TrianglesCoplanar) {
  EXPECT_TRUE(intersect_sym(kUnit, shifted(kUnit, V3(0.25, 0.25, 0))));
  EXPECT_TRUE(intersect_sym(kUnit, Tri{V3(0.1, 0.1, 0), V3(0.2, 0.1, 0), V3(0.1, 0.2, 0)}));  // nested
  EXPECT_FALSE(intersect_sym(kUnit, shifted(kUnit, V3(0.6, 0.6, 0))));
  EXPECT_TRUE(intersect_sym(kUnit, shifted(kUnit, V3(0.5, 0.5, 0))));  // touch at (0.5, 0.5)
  EXPECT_TRUE(intersect_sym(kUnit, Tri{V3(1, 0, 0), V3(0, 1, 0), V3(1, 1, 0)}));  // shared edge
  EXPECT_FALSE(intersect_sym(kUnit, shifted(kUnit, V3(std::nextafter(1.0, 2.0), 0, 0))));  // 1 ulp gap
  EXPECT_TRUE(intersect_sym(kUnit, shifted(kUnit, V3(1, 0, 0))));                     // vertex touch
  // A tilted plane, projected by the exact predicates.
  const Tri t{V3(0, 0, 0), V3(3, 1, 2), V3(1, 3, 2)};
  EXPECT_TRUE(intersect_sym(t, Tri{V3(2, 2, 2), V3(4, 0, 2), V3(4, 4, 4)}));     // coplanar, overlapping
  EXPECT_FALSE(intersect_sym(t, Tri{V3(3, 3, 3), V3(5, 1, 3), V3(5, 5, 5)}));    // coplanar, disjoint
}

TEST(Predicates, TrianglesNearlyCoplanarTinyScales) {
  const Tri q = shifted(kUnit, V3(0.25, 0.25, 0));
  for (double s : {1.0, 1e-300, std::ldexp(1.0, -1000), 1e300}) {
    SCOPED_TRACE(s);
    const Tri p = scaled(kUnit, s);
    EXPECT_TRUE(intersect_sym(p, scaled(q, s)));
    // Lifted by the smallest subnormal double: parallel and apart.
    const double lift = std::nextafter(0.0, 1.0);
    EXPECT_FALSE(intersect_sym(p, shifted(scaled(q, s), V3(0, 0, lift))));
    // One vertex below, two above the plane: crosses it inside p.
    Tri r = scaled(q, s);
    r[0].z() = -lift;
    r[1].z() = 2 * lift;
    r[2].z() = 2 * lift;
    EXPECT_TRUE(intersect_sym(p, r));
  }
  // 1e-300-sized triangles separated by 1e-316 (below the smallest normal double).
  const Tri tiny = scaled(kUnit, 1e-300);
  EXPECT_FALSE(intersect_sym(tiny, shifted(tiny, V3(0, 0, 1e-316))));
  EXPECT_TRUE(intersect_sym(tiny, Tri{V3(2e-301, 2e-301, -1e-316), V3(2e-301, 2e-301, 1e-316), V3(1e-299, 1e-299, 0)}));
}

TEST(Predicates, TrianglesPointOneTwoThree) {
  // A vertical triangle in the plane x = c against kUnit' whose vertex is at x = 0.3.
  const Tri p{V3(0, 0, 0), V3(0.3, 0, 0), V3(0, 1, 0)};
  const double s = 0.1 + 0.2;  // 0.30000000000000004
  const Tri wall_s{V3(s, -1, -1), V3(s, 1, -1), V3(s, 0, 1)};
  const Tri wall_3{V3(0.3, -1, -1), V3(0.3, 1, -1), V3(0.3, 0, 1)};
  EXPECT_FALSE(intersect_sym(p, wall_s));
  EXPECT_TRUE(intersect_sym(p, wall_3));
  // Coplanar version: a triangle in z = 0 starting at x = 0.1 + 0.2 misses p by 4e-17.
  EXPECT_FALSE(intersect_sym(p, Tri{V3(s, 0, 0), V3(1, 0, 0), V3(1, 1, 0)}));
  EXPECT_TRUE(intersect_sym(p, Tri{V3(0.3, 0, 0), V3(1, 0, 0), V3(1, 1, 0)}));
}

TEST(Predicates, TrianglesDegenerate) {
  const V3 inside(0.25, 0.25, 0);
  // Point triangles.
  EXPECT_TRUE(intersect_sym(kUnit, Tri{inside, inside, inside}));
  EXPECT_TRUE(intersect_sym(kUnit, Tri{V3(0.5, 0.5, 0), V3(0.5, 0.5, 0), V3(0.5, 0.5, 0)}));  // on the hypotenuse
  EXPECT_FALSE(intersect_sym(kUnit, Tri{V3(0.5, 0.5, 1e-300), V3(0.5, 0.5, 1e-300), V3(0.5, 0.5, 1e-300)}));
  // Segment triangles (collinear, the middle point listed last or first).
  EXPECT_TRUE(intersect_sym(kUnit, Tri{V3(0.2, 0.2, -1), V3(0.2, 0.2, 1), V3(0.2, 0.2, 0.5)}));
  EXPECT_FALSE(intersect_sym(kUnit, Tri{V3(0.2, 0.2, 0.5), V3(0.2, 0.2, 2), V3(0.2, 0.2, 1)}));
  EXPECT_TRUE(intersect_sym(kUnit, Tri{V3(-1, 0.5, 0), V3(0, 0.5, 0), V3(2, 0.5, 0)}));   // in-plane crossing
  EXPECT_FALSE(intersect_sym(kUnit, Tri{V3(1, 1, 0), V3(2, 2, 0), V3(3, 3, 0)}));        // in-plane outside
  // Segment against segment, and against a point.
  const Tri seg{V3(0, 0, 0), V3(2, 2, 2), V3(1, 1, 1)};
  EXPECT_TRUE(intersect_sym(seg, Tri{V3(1, 1, 1), V3(3, 3, 3), V3(3, 3, 3)}));            // collinear overlap
  EXPECT_FALSE(intersect_sym(seg, Tri{V3(2.5, 2.5, 2.5), V3(3, 3, 3), V3(3, 3, 3)}));     // collinear apart
  EXPECT_TRUE(intersect_sym(seg, Tri{V3(0, 2, 0), V3(2, 0, 2), V3(0, 2, 0)}));            // crossing at (1,1,1)
  EXPECT_FALSE(intersect_sym(seg, Tri{V3(0, 2, 0), V3(2, 0, 2.5), V3(0, 2, 0)}));         // skew
  EXPECT_TRUE(intersect_sym(seg, Tri{V3(0.5, 0.5, 0.5), V3(0.5, 0.5, 0.5), V3(0.5, 0.5, 0.5)}));
  EXPECT_FALSE(intersect_sym(seg, Tri{V3(0.5, 0.5, 0.6), V3(0.5, 0.5, 0.6), V3(0.5, 0.5, 0.6)}));
}

// ---- faces_self_intersect --------------------------------------------------------------

TEST(Predicates, FacesFanNeighboursDoNotIntersect) {
  // A flat fan around v = 0 and a bent one.
  const V3 v(0, 0, 0), a(1, 0, 0), b(0, 1, 0), c(-1, 0, 0), d(0, -1, 0);
  EXPECT_FALSE(faces_sym(Tri{v, a, b}, Ids{0, 1, 2}, Tri{v, b, c}, Ids{0, 2, 3}));  // shared edge, flat
  EXPECT_FALSE(faces_sym(Tri{v, a, b}, Ids{0, 1, 2}, Tri{v, c, d}, Ids{0, 3, 4}));  // shared vertex only
  EXPECT_FALSE(faces_sym(Tri{v, a, b}, Ids{0, 1, 2}, Tri{v, c, V3(0, -1, 1)}, Ids{0, 3, 4}));
  // The same geometry without shared indices (an unwelded soup) touches at v.
  EXPECT_TRUE(faces_sym(Tri{v, a, b}, Ids{0, 1, 2}, Tri{v, c, d}, Ids{5, 3, 4}));
}

TEST(Predicates, FacesSharedVertexFoldOver) {
  const V3 v(0, 0, 0), a(1, 0, 0), b(0, 1, 0);
  // Coplanar: the second face overlaps the first beyond v.
  EXPECT_TRUE(faces_sym(Tri{v, a, b}, Ids{0, 1, 2}, Tri{v, V3(1, 1, 0), V3(2, 0.5, 0)}, Ids{0, 3, 4}));
  // Coplanar, touching only along a ray from v (shares a segment on the edge v-a).
  EXPECT_TRUE(faces_sym(Tri{v, a, b}, Ids{0, 1, 2}, Tri{v, V3(2, 0, 0), V3(1, -1, 0)}, Ids{0, 3, 4}));
  // Not coplanar: the opposite edge of the second face pierces the first.
  EXPECT_TRUE(faces_sym(Tri{v, a, b}, Ids{0, 1, 2}, Tri{v, V3(0.3, 0.3, -1), V3(0.3, 0.3, 1)}, Ids{0, 3, 4}));
  // Not coplanar, the cut passes only through v: no intersection.
  EXPECT_FALSE(faces_sym(Tri{v, a, b}, Ids{0, 1, 2}, Tri{v, V3(-0.3, -0.3, -1), V3(-0.3, -0.3, 1)}, Ids{0, 3, 4}));
}

TEST(Predicates, FacesNearlyCoplanarAroundAVertex) {
  // A mesh's flat region: neighbours off the plane by rounding only. Sectors apart in projection
  // decide without the exact 3D tests; overlapping sectors still go to them.
  const double up = std::nextafter(0.3, 1.0), down = std::nextafter(0.3, 0.0);  // one ulp off
  const V3 v(0.1, 0.2, 0.3), a(1.1, 0.2, up), b(0.1, 1.2, down);
  const V3 c(-0.9, 0.2, up), d(0.1, -0.8, 0.3);
  EXPECT_FALSE(faces_sym(Tri{v, a, b}, Ids{0, 1, 2}, Tri{v, c, d}, Ids{0, 3, 4}));
  EXPECT_FALSE(faces_sym(Tri{v, a, b}, Ids{0, 1, 2}, Tri{v, b, c}, Ids{0, 2, 3}));
  // Overlapping in projection but lifted off the first face everywhere except at v: apart in 3D.
  EXPECT_FALSE(faces_sym(Tri{v, a, b}, Ids{0, 1, 2}, Tri{v, V3(0.6, 0.7, 0.31), V3(1.1, 0.7, 0.31)}, Ids{0, 3, 4}));
  // Overlapping in projection, the first face's corners one ulp off the second's plane: the
  // second face's edge from (0.6, 0.7) to (1.1, 0.7) passes through the first face's interior
  // only if the first face is not exactly in z = 0.3; it is not (a above, b below): they cross.
  const Tri flat{v, V3(0.6, 0.7, 0.3), V3(1.1, 0.7, 0.3)};
  EXPECT_TRUE(faces_sym(Tri{v, a, b}, Ids{0, 1, 2}, flat, Ids{0, 3, 4}));
  // Sharing an edge, the third corners on opposite sides: apart whatever the rounding.
  EXPECT_FALSE(faces_sym(Tri{v, a, b}, Ids{0, 1, 2}, Tri{a, v, V3(0.6, -0.8, up)}, Ids{1, 0, 3}));
}

TEST(Predicates, FacesSharedEdge) {
  const V3 a(0, 0, 0), b(1, 0, 0), c(0.5, 1, 0);
  // Folded flat onto the first face: same side of ab, coplanar.
  EXPECT_TRUE(faces_sym(Tri{a, b, c}, Ids{0, 1, 2}, Tri{b, a, V3(0.7, 0.2, 0)}, Ids{1, 0, 3}));
  // Normal dihedral angle.
  EXPECT_FALSE(faces_sym(Tri{a, b, c}, Ids{0, 1, 2}, Tri{b, a, V3(0.5, -1, 0.3)}, Ids{1, 0, 3}));
  // Nearly folded (one ulp out of the plane): not coplanar, no intersection.
  EXPECT_FALSE(
      faces_sym(Tri{a, b, c}, Ids{0, 1, 2}, Tri{b, a, V3(0.7, 0.2, std::nextafter(0.0, 1.0))}, Ids{1, 0, 3}));
  // Coplanar on the other side: a flat neighbour.
  EXPECT_FALSE(faces_sym(Tri{a, b, c}, Ids{0, 1, 2}, Tri{b, a, V3(0.5, -1, 0)}, Ids{1, 0, 3}));
  // Tiny and decimal coordinates.
  const double s = 0.1 + 0.2;
  EXPECT_TRUE(faces_sym(scaled(Tri{a, b, c}, 1e-300), Ids{0, 1, 2}, Tri{b * 1e-300, a * 1e-300, V3(s, 0.1, 0) * 1e-300},
                        Ids{1, 0, 3}));
}

TEST(Predicates, FacesDuplicate) {
  const Tri t{V3(0, 0, 0), V3(1, 0, 0), V3(0, 1, 0)};
  EXPECT_TRUE(faces_sym(t, Ids{0, 1, 2}, t, Ids{0, 1, 2}));
  EXPECT_TRUE(faces_sym(t, Ids{0, 1, 2}, Tri{t[0], t[2], t[1]}, Ids{0, 2, 1}));  // opposite orientation
}

TEST(Predicates, FacesDegenerate) {
  const V3 a(0, 0, 0), b(1, 0, 0), c(0.5, 1, 0);
  // Flat faces on the shared edge's line: intersect only if both extend beyond the same end.
  EXPECT_TRUE(faces_sym(Tri{a, b, V3(2, 0, 0)}, Ids{0, 1, 2}, Tri{a, b, V3(3, 0, 0)}, Ids{0, 1, 3}));
  EXPECT_FALSE(faces_sym(Tri{a, b, V3(2, 0, 0)}, Ids{0, 1, 2}, Tri{a, b, V3(-1, 0, 0)}, Ids{0, 1, 3}));
  EXPECT_FALSE(faces_sym(Tri{a, b, V3(2, 0, 0)}, Ids{0, 1, 2}, Tri{a, b, c}, Ids{0, 1, 3}));
  // A flat face (v in the middle of its segment) against a proper face sharing v.
  const V3 v(0, 0, 0);
  EXPECT_TRUE(faces_sym(Tri{v, V3(-1, 0, 0), V3(1, 0, 0)}, Ids{0, 1, 2}, Tri{v, V3(1, 1, 0), V3(1, -1, 0)}, Ids{0, 3, 4}));
  EXPECT_FALSE(faces_sym(Tri{v, V3(-1, 0, 1), V3(1, 0, -1)}, Ids{0, 1, 2}, Tri{v, V3(1, 1, 0), V3(1, -1, 0)}, Ids{0, 3, 4}));
  // A repeated index makes a flat face that equals the shared edge: nothing beyond it.
  EXPECT_FALSE(faces_sym(Tri{a, b, a}, Ids{0, 1, 0}, Tri{a, b, c}, Ids{0, 1, 3}));
}

// ---- agreement with CGAL on recorded pairs (tools/cgal_check) --------------------------

std::vector<double> parse_line(const std::string& line) {
  // strtod, not operator>>: libstdc++ flags subnormal results as failures.
  std::vector<double> v;
  const char* s = line.c_str();
  char* end = nullptr;
  for (double x = std::strtod(s, &end); end != s; x = std::strtod(s, &end)) {
    v.push_back(x);
    s = end;
  }
  return v;
}

TEST(Predicates, AgreesWithCgalOnRecordedPairs) {
  const std::string path = data_dir() + "/tri_tri_cgal.txt";
  std::ifstream in(path);
  ASSERT_TRUE(in) << "missing " << path;
  std::string line;
  int lines = 0, disagreements = 0, hits = 0;
  while (std::getline(in, line)) {
    const std::vector<double> v = parse_line(line);
    ASSERT_EQ(v.size(), 19u) << path << ":" << lines + 1;
    Tri p, q;
    for (int i = 0; i < 3; ++i) {
      p[i] = V3(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
      q[i] = V3(v[9 + 3 * i], v[9 + 3 * i + 1], v[9 + 3 * i + 2]);
    }
    const bool expected = v[18] != 0;
    hits += expected;
    ++lines;
    if (triangles_intersect(p, q) != expected) {
      if (++disagreements <= 10) ADD_FAILURE() << path << ":" << lines << " CGAL says " << expected << ": " << line;
    }
  }
  EXPECT_EQ(lines, 20000);
  EXPECT_EQ(disagreements, 0);
  // The file must exercise both answers substantially.
  EXPECT_GT(hits, lines / 5);
  EXPECT_LT(hits, lines - lines / 5);
}

TEST(Predicates, FacesAgreeWithCgalOnRecordedPairs) {
  const std::string path = data_dir() + "/face_pairs_cgal.txt";
  std::ifstream in(path);
  ASSERT_TRUE(in) << "missing " << path;
  std::string line;
  int lines = 0, disagreements = 0, hits = 0;
  while (std::getline(in, line)) {
    const std::vector<double> v = parse_line(line);
    ASSERT_EQ(v.size(), 25u) << path << ":" << lines + 1;
    Tri p, q;
    Ids pi, qi;
    for (int i = 0; i < 3; ++i) {
      p[i] = V3(v[3 * i], v[3 * i + 1], v[3 * i + 2]);
      q[i] = V3(v[9 + 3 * i], v[9 + 3 * i + 1], v[9 + 3 * i + 2]);
      pi[i] = static_cast<int>(v[18 + i]);
      qi[i] = static_cast<int>(v[21 + i]);
    }
    const bool expected = v[24] != 0;
    hits += expected;
    ++lines;
    if (faces_self_intersect(p, pi, q, qi) != expected) {
      if (++disagreements <= 10) ADD_FAILURE() << path << ":" << lines << " CGAL says " << expected << ": " << line;
    }
  }
  EXPECT_EQ(lines, 5000);
  EXPECT_EQ(disagreements, 0);
  EXPECT_GT(hits, lines / 5);
  EXPECT_LT(hits, lines - lines / 5);
}

}  // namespace
