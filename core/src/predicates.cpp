// Exact predicates in three stages:
//  1. a semi-static floating-point filter decides almost every call with a nonzero result;
//  2. when it cannot (zero or nearly zero determinants: coplanar neighbours, shared points),
//     the determinant is evaluated exactly with floating-point expansions (Shewchuk 1997) on
//     the stack. Mesh checks hit this stage often (every pair of coplanar neighbouring faces
//     has an exactly zero determinant, which no filter can certify), so it must not allocate;
//  3. inputs whose magnitudes would make expansion products underflow or overflow go to GMP
//     rationals, which are exact for any double.
// Triangle–triangle tests are built only from orient3d/orient2d and exact coordinate
// comparisons, never from constructed points, so their answers are exact as well.
#include "s2c/core/predicates.h"

#include <algorithm>
#include <cmath>

#include <gmpxx.h>

// The error bounds and two_sum/two_product rely on IEEE round-to-nearest arithmetic evaluated
// exactly as written; value-changing optimisations would silently break exactness.
#if defined(__FAST_MATH__)
#error "predicates.cpp must not be compiled with -ffast-math"
#endif

namespace s2c {
namespace {

using V3 = Eigen::Vector3d;
using V2 = Eigen::Vector2d;
using Tri = std::array<V3, 3>;

// Unit roundoff of IEEE double (round to nearest).
constexpr double kU = 0x1p-53;

// Error bound for orient3d's filter, derived for the evaluation order used below
// (det = x*(y*z - z*y) + y*(z*x - x*z) + z*(x*y - y*x) on the rounded differences):
//  * rounding the 9 differences perturbs each of the 6 monomials by at most 3u relative:
//    18u * X*Y*Z, where X, Y, Z bound the |differences| per axis;
//  * each term x*(p1 - p2) carries 6u*XYZ (two products, one subtraction, one product),
//    the two additions 4u*XYZ and 6u*XYZ: 28u*XYZ;
// total 46u*XYZ to first order. 47u leaves one u*XYZ for the second-order terms and for the
// absolute error of products that underflow, which the range check keeps far smaller
// (each such error is below 2^-1075 * max(X,Y,Z), and X*Y*Z*u >= 1e-210 * max(X,Y,Z)).
constexpr double kOrient3dBound = 47.0 * kU;
// Same derivation for orient2d (x*y - y*x): 4u from the differences, 4u from the evaluation.
constexpr double kOrient2dBound = 9.0 * kU;
// Per-axis magnitude range in which the bounds above hold: products neither overflow nor
// lose more than a negligible absolute amount to underflow.
constexpr double kOrient3dMin = 1e-97, kOrient3dMax = 1e102;
constexpr double kOrient2dMin = 1e-146, kOrient2dMax = 1e153;

int orient3d_gmp(const V3& a, const V3& b, const V3& c, const V3& d) {
  // mpq_class(double) is exact, and so is every operation below.
  const mpq_class ax(a.x()), ay(a.y()), az(a.z());
  const mpq_class bx = mpq_class(b.x()) - ax, by = mpq_class(b.y()) - ay, bz = mpq_class(b.z()) - az;
  const mpq_class cx = mpq_class(c.x()) - ax, cy = mpq_class(c.y()) - ay, cz = mpq_class(c.z()) - az;
  const mpq_class dx = mpq_class(d.x()) - ax, dy = mpq_class(d.y()) - ay, dz = mpq_class(d.z()) - az;
  const mpq_class det = bx * (cy * dz - cz * dy) + by * (cz * dx - cx * dz) + bz * (cx * dy - cy * dx);
  return sgn(det);
}

int orient2d_gmp(const V2& a, const V2& b, const V2& c) {
  const mpq_class ax(a.x()), ay(a.y());
  const mpq_class bx = mpq_class(b.x()) - ax, by = mpq_class(b.y()) - ay;
  const mpq_class cx = mpq_class(c.x()) - ax, cy = mpq_class(c.y()) - ay;
  const mpq_class det = bx * cy - by * cx;
  return sgn(det);
}

// ---- stage 2: floating-point expansions -------------------------------------------------
// An expansion is a sum of doubles with nonoverlapping bits, stored by increasing magnitude
// without zeros; its sign is the sign of its last (largest) component. two_sum and
// two_product (with a fused multiply-add) return the exact result as value + error, so every
// operation below is exact as long as no product underflows or overflows. The callers
// guarantee that with a range check: all coordinates are 0 or have |x| in [2^-306, 2^300]
// for orient3d, so every coordinate is a multiple of 2^-358 and a product of three
// differences is a multiple of 2^-1074 (the smallest subnormal) and below 2^906;
// for orient2d [2^-484, 2^500] gives multiples of 2^-536 and products of two below 2^1004.

constexpr int kExpansionCapacity = 192;  // det of orient3d: 3 * (2 * 2 * (2*2 + 2*2)) * 2 comps
struct Expansion {
  int n = 0;
  double c[kExpansionCapacity];
  void push(double x) {
    if (x != 0) c[n++] = x;
  }
  int sign() const { return n == 0 ? 0 : (c[n - 1] > 0 ? 1 : -1); }
};

inline void two_sum(double a, double b, double& x, double& y) {
  x = a + b;
  const double bv = x - a, av = x - bv;
  y = (a - av) + (b - bv);
}

inline void two_product(double a, double b, double& x, double& y) {
  x = a * b;
  y = std::fma(a, b, -x);
}

// Exact a - b as an expansion of at most two components.
Expansion difference(double a, double b) {
  double x, y;
  two_sum(a, -b, x, y);
  Expansion e;
  e.push(y);
  e.push(x);
  return e;
}

// e += b (Shewchuk's Grow-Expansion with zero elimination).
void grow(Expansion& e, double b) {
  double q = b;
  int k = 0;
  for (int i = 0; i < e.n; ++i) {
    double s, h;
    two_sum(q, e.c[i], s, h);
    q = s;
    if (h != 0) e.c[k++] = h;
  }
  if (q != 0) e.c[k++] = q;
  e.n = k;
}

// e += sign * f.
void add(Expansion& e, const Expansion& f, double sign = 1.0) {
  for (int i = 0; i < f.n; ++i) grow(e, sign * f.c[i]);
}

// e * b (Shewchuk's Scale-Expansion with zero elimination).
Expansion scale(const Expansion& e, double b) {
  Expansion h;
  if (e.n == 0 || b == 0) return h;
  double q, hh;
  two_product(e.c[0], b, q, hh);
  h.push(hh);
  for (int i = 1; i < e.n; ++i) {
    double p1, p0, s;
    two_product(e.c[i], b, p1, p0);
    two_sum(q, p0, s, hh);
    h.push(hh);
    two_sum(p1, s, q, hh);
    h.push(hh);
  }
  h.push(q);
  return h;
}

// e * f, f short (the components of f scale e one at a time).
Expansion multiply(const Expansion& e, const Expansion& f) {
  Expansion r;
  for (int j = 0; j < f.n; ++j) add(r, scale(e, f.c[j]));
  return r;
}

bool expansion_range(double x, double lo, double hi) {
  const double m = std::abs(x);
  return m == 0 || (m >= lo && m <= hi);
}

bool orient3d_expansion_ok(const V3& a, const V3& b, const V3& c, const V3& d) {
  for (const V3* p : {&a, &b, &c, &d})
    for (int k = 0; k < 3; ++k)
      if (!expansion_range((*p)[k], 0x1p-306, 0x1p300)) return false;
  return true;
}

int orient3d_expansion(const V3& a, const V3& b, const V3& c, const V3& d) {
  const Expansion bx = difference(b.x(), a.x()), by = difference(b.y(), a.y()), bz = difference(b.z(), a.z());
  const Expansion cx = difference(c.x(), a.x()), cy = difference(c.y(), a.y()), cz = difference(c.z(), a.z());
  const Expansion dx = difference(d.x(), a.x()), dy = difference(d.y(), a.y()), dz = difference(d.z(), a.z());
  auto minor = [](const Expansion& p, const Expansion& q, const Expansion& r, const Expansion& s) {
    Expansion m = multiply(p, q);  // p*q - r*s
    add(m, multiply(r, s), -1.0);
    return m;
  };
  Expansion det = multiply(minor(cy, dz, cz, dy), bx);
  add(det, multiply(minor(cz, dx, cx, dz), by));
  add(det, multiply(minor(cx, dy, cy, dx), bz));
  return det.sign();
}

bool orient2d_expansion_ok(const V2& a, const V2& b, const V2& c) {
  for (const V2* p : {&a, &b, &c})
    for (int k = 0; k < 2; ++k)
      if (!expansion_range((*p)[k], 0x1p-484, 0x1p500)) return false;
  return true;
}

int orient2d_expansion(const V2& a, const V2& b, const V2& c) {
  const Expansion bx = difference(b.x(), a.x()), by = difference(b.y(), a.y());
  const Expansion cx = difference(c.x(), a.x()), cy = difference(c.y(), a.y());
  Expansion det = multiply(bx, cy);
  add(det, multiply(by, cx), -1.0);
  return det.sign();
}

// ---- small exact helpers ---------------------------------------------------------------

// orient3d's sign when its floating-point filter settles it (with the exact zero of four points
// sharing a coordinate), else kUnsettled: lets a caller try cheaper exact tests before the
// expansion arithmetic.
constexpr int kUnsettled = 2;
int orient3d_filtered(const V3& a, const V3& b, const V3& c, const V3& d) {
  const double bx = b.x() - a.x(), by = b.y() - a.y(), bz = b.z() - a.z();
  const double cx = c.x() - a.x(), cy = c.y() - a.y(), cz = c.z() - a.z();
  const double dx = d.x() - a.x(), dy = d.y() - a.y(), dz = d.z() - a.z();
  const double det = bx * (cy * dz - cz * dy) + by * (cz * dx - cx * dz) + bz * (cx * dy - cy * dx);
  const double mx = std::max({std::abs(bx), std::abs(cx), std::abs(dx)});
  const double my = std::max({std::abs(by), std::abs(cy), std::abs(dy)});
  const double mz = std::max({std::abs(bz), std::abs(cz), std::abs(dz)});
  const double lo = std::min({mx, my, mz}), hi = std::max({mx, my, mz});
  // A difference of doubles is zero only if the operands are equal (subtraction is exact
  // near zero), so all four points then share one coordinate and are coplanar.
  if (lo == 0) return 0;
  if (lo >= kOrient3dMin && hi <= kOrient3dMax) {
    const double eps = kOrient3dBound * mx * my * mz;
    if (det > eps) return 1;
    if (det < -eps) return -1;
  }
  return kUnsettled;
}

// Lexicographic order on (x, y, z). On any line it is monotone along the line, so it orders
// collinear points exactly without constructing anything.
bool lex_less(const V3& a, const V3& b) {
  if (a.x() != b.x()) return a.x() < b.x();
  if (a.y() != b.y()) return a.y() < b.y();
  return a.z() < b.z();
}
bool lex_less(const V2& a, const V2& b) {
  if (a.x() != b.x()) return a.x() < b.x();
  return a.y() < b.y();
}

// Projection dropping axis k; orient2d of projected points is the sign of component k of
// (b-a)×(c-a), so the projection is orientation-faithful on a plane whose normal has n_k != 0.
V2 drop(const V3& p, int k) { return V2(p[(k + 1) % 3], p[(k + 2) % 3]); }

int orient2d_axis(const V3& a, const V3& b, const V3& c, int k) {
  return orient2d(drop(a, k), drop(b, k), drop(c, k));
}

// Returns an axis k with component k of (b-a)×(c-a) nonzero, preferring the largest one
// (best conditioned projection); -1 when a, b, c are collinear (or coincident).
int projection_axis(const V3& a, const V3& b, const V3& c) {
  // Approximate normal only to rank the axes; NaN (from overflow) ranks last.
  const V3 u = b - a, w = c - a;
  double n[3] = {u.y() * w.z() - u.z() * w.y(), u.z() * w.x() - u.x() * w.z(), u.x() * w.y() - u.y() * w.x()};
  for (double& x : n) x = std::isnan(x) ? 0.0 : std::abs(x);
  int order[3] = {0, 1, 2};
  std::sort(order, order + 3, [&](int i, int j) { return n[i] > n[j]; });
  for (int k : order)
    if (orient2d_axis(a, b, c, k) != 0) return k;
  return -1;
}

bool collinear(const V3& a, const V3& b, const V3& c) { return projection_axis(a, b, c) < 0; }

// What a possibly degenerate triangle is as a point set.
struct Shape {
  enum Kind { kPoint = 0, kSegment = 1, kTriangle = 2 } kind;
  V3 v[3];  // kPoint: v[0]; kSegment: v[0] != v[1] (endpoints); kTriangle: v[0..2]
};

Shape classify(const Tri& t) {
  Shape s;
  if (!collinear(t[0], t[1], t[2])) {
    s.kind = Shape::kTriangle;
    s.v[0] = t[0], s.v[1] = t[1], s.v[2] = t[2];
    return s;
  }
  const V3* lo = &t[0];
  const V3* hi = &t[0];
  for (int i = 1; i < 3; ++i) {
    if (lex_less(t[i], *lo)) lo = &t[i];
    if (lex_less(*hi, t[i])) hi = &t[i];
  }
  s.v[0] = *lo;
  s.v[1] = *hi;
  s.kind = (*lo == *hi) ? Shape::kPoint : Shape::kSegment;
  return s;
}

// ---- 2D tests (closed sets) ------------------------------------------------------------

}  // namespace

bool segments_intersect_2d(const V2& a, const V2& b, const V2& c, const V2& d) {
  const int o1 = orient2d(a, b, c), o2 = orient2d(a, b, d);
  if (o1 != 0 && o1 == o2) return false;
  const int o3 = orient2d(c, d, a), o4 = orient2d(c, d, b);
  if (o3 != 0 && o3 == o4) return false;
  if (o1 == 0 && o2 == 0 && o3 == 0 && o4 == 0) {
    // All four collinear: overlap of intervals in lexicographic order.
    const V2& ab_lo = lex_less(a, b) ? a : b;
    const V2& ab_hi = lex_less(a, b) ? b : a;
    const V2& cd_lo = lex_less(c, d) ? c : d;
    const V2& cd_hi = lex_less(c, d) ? d : c;
    return !lex_less(ab_hi, cd_lo) && !lex_less(cd_hi, ab_lo);
  }
  return true;
}

namespace {

// t must be non-degenerate (either orientation).
bool point_in_triangle_2d(const V2& p, const V2& t0, const V2& t1, const V2& t2) {
  const int o0 = orient2d(t0, t1, p), o1 = orient2d(t1, t2, p), o2 = orient2d(t2, t0, p);
  return (o0 >= 0 && o1 >= 0 && o2 >= 0) || (o0 <= 0 && o1 <= 0 && o2 <= 0);
}

// ---- 3D tests on classified shapes -------------------------------------------------------

bool point_on_segment(const V3& p, const V3& s0, const V3& s1) {
  if (!collinear(p, s0, s1)) return false;
  const V3& lo = lex_less(s0, s1) ? s0 : s1;
  const V3& hi = lex_less(s0, s1) ? s1 : s0;
  return !lex_less(p, lo) && !lex_less(hi, p);
}

// t non-degenerate.
bool point_in_triangle(const V3& p, const V3* t) {
  if (orient3d(t[0], t[1], t[2], p) != 0) return false;
  const int k = projection_axis(t[0], t[1], t[2]);
  return point_in_triangle_2d(drop(p, k), drop(t[0], k), drop(t[1], k), drop(t[2], k));
}

bool segments_intersect(const V3& a, const V3& b, const V3& c, const V3& d) {
  if (orient3d(a, b, c, d) != 0) return false;
  // Coplanar: any non-collinear triple gives a projection that is injective on the plane.
  for (int k = 0; k < 3; ++k) {
    if (orient2d_axis(a, b, c, k) != 0 || orient2d_axis(a, b, d, k) != 0 || orient2d_axis(c, d, a, k) != 0 ||
        orient2d_axis(c, d, b, k) != 0)
      return segments_intersect_2d(drop(a, k), drop(b, k), drop(c, k), drop(d, k));
  }
  // All on one line.
  const V3& ab_lo = lex_less(a, b) ? a : b;
  const V3& ab_hi = lex_less(a, b) ? b : a;
  const V3& cd_lo = lex_less(c, d) ? c : d;
  const V3& cd_hi = lex_less(c, d) ? d : c;
  return !lex_less(ab_hi, cd_lo) && !lex_less(cd_hi, ab_lo);
}

// Closed segment [s0, s1] (s0 != s1) against non-degenerate closed triangle t.
bool segment_triangle_intersect(const V3& s0, const V3& s1, const V3* t) {
  const int o0 = orient3d(t[0], t[1], t[2], s0), o1 = orient3d(t[0], t[1], t[2], s1);
  if (o0 != 0 && o0 == o1) return false;
  if (o0 == 0 && o1 == 0) {
    const int k = projection_axis(t[0], t[1], t[2]);
    const V2 a = drop(s0, k), b = drop(s1, k), p = drop(t[0], k), q = drop(t[1], k), r = drop(t[2], k);
    return point_in_triangle_2d(a, p, q, r) || segments_intersect_2d(a, b, p, q) ||
           segments_intersect_2d(a, b, q, r) || segments_intersect_2d(a, b, r, p);
  }
  // The segment meets the plane in exactly one point, so it meets the triangle iff its
  // supporting line does: the line passes each edge on the same side (zero = through it).
  const int e0 = orient3d(s0, s1, t[0], t[1]), e1 = orient3d(s0, s1, t[1], t[2]), e2 = orient3d(s0, s1, t[2], t[0]);
  return (e0 >= 0 && e1 >= 0 && e2 >= 0) || (e0 <= 0 && e1 <= 0 && e2 <= 0);
}

// Both non-degenerate and coplanar.
bool coplanar_triangles_intersect(const V3* t, const V3* u) {
  const int k = projection_axis(t[0], t[1], t[2]);
  V2 a[3], b[3];
  for (int i = 0; i < 3; ++i) a[i] = drop(t[i], k), b[i] = drop(u[i], k);
  for (int i = 0; i < 3; ++i)
    for (int j = 0; j < 3; ++j)
      if (segments_intersect_2d(a[i], a[(i + 1) % 3], b[j], b[(j + 1) % 3])) return true;
  // No boundary crossing: either one contains the other or they are disjoint.
  return point_in_triangle_2d(a[0], b[0], b[1], b[2]) || point_in_triangle_2d(b[0], a[0], a[1], a[2]);
}

// Coplanar or degenerate pairs: dispatch on what each triangle is as a point set.
bool shapes_intersect(const Tri& t, const Tri& u) {
  Shape a = classify(t), b = classify(u);
  if (a.kind < b.kind) std::swap(a, b);
  switch (a.kind * 3 + b.kind) {
    case Shape::kTriangle * 3 + Shape::kTriangle: return coplanar_triangles_intersect(a.v, b.v);
    case Shape::kTriangle * 3 + Shape::kSegment: return segment_triangle_intersect(b.v[0], b.v[1], a.v);
    case Shape::kTriangle * 3 + Shape::kPoint: return point_in_triangle(b.v[0], a.v);
    case Shape::kSegment * 3 + Shape::kSegment: return segments_intersect(a.v[0], a.v[1], b.v[0], b.v[1]);
    case Shape::kSegment * 3 + Shape::kPoint: return point_on_segment(b.v[0], a.v[0], a.v[1]);
    default: return a.v[0] == b.v[0];
  }
}

// Guigue–Devillers normalisation: picks the vertex k of a triangle that is alone on its side
// of the other triangle's plane, and the sign sigma that side must get (-1: flip the other
// triangle) so that s[k]*sigma >= 0 and the other two are <= 0 after the flip. The signs are
// neither all zero nor all equal and nonzero (those cases are handled before).
void alone_vertex(const int s[3], int& k, int& sigma) {
  for (int i = 0; i < 3; ++i) {
    const int a = s[(i + 1) % 3], b = s[(i + 2) % 3];
    if (s[i] > 0 && a <= 0 && b <= 0) { k = i, sigma = 1; return; }
    if (s[i] < 0 && a >= 0 && b >= 0) { k = i, sigma = -1; return; }
  }
  for (int i = 0; i < 3; ++i) {
    const int a = s[(i + 1) % 3], b = s[(i + 2) % 3];
    if (s[i] == 0 && a >= 0 && b >= 0) { k = i, sigma = -1; return; }
    if (s[i] == 0 && a <= 0 && b <= 0) { k = i, sigma = 1; return; }
  }
  k = 0, sigma = 1;  // unreachable for valid input
}

// Non-degenerate, non-coplanar triangles that both straddle (or touch) the other's plane.
// st: sides of t's vertices w.r.t. plane(u); su: sides of u's vertices w.r.t. plane(t).
bool straddling_triangles_intersect(const Tri& t, const int st[3], const Tri& u, const int su[3]) {
  int k1, sigma1, k2, sigma2;
  alone_vertex(st, k1, sigma1);
  alone_vertex(su, k2, sigma2);
  // Rotations keep orientation; swapping the last two vertices flips it.
  const V3* p1 = &t[k1];
  const V3* q1 = &t[(k1 + 1) % 3];
  const V3* r1 = &t[(k1 + 2) % 3];
  const V3* p2 = &u[k2];
  const V3* q2 = &u[(k2 + 1) % 3];
  const V3* r2 = &u[(k2 + 2) % 3];
  if (sigma1 < 0) std::swap(q2, r2);  // p1 now on the non-negative side of plane(u)
  if (sigma2 < 0) std::swap(q1, r1);  // p2 now on the non-negative side of plane(t)
  // Both triangles cut the line plane(t) ∩ plane(u) in an interval; the intervals overlap
  // iff these two orientations say neither interval ends before the other starts.
  return orient3d(*p1, *q1, *p2, *q2) <= 0 && orient3d(*p1, *r1, *r2, *p2) <= 0;
}

// ---- shared-vertex rules ---------------------------------------------------------------

Tri segment_tri(const V3& a, const V3& b) { return {a, b, b}; }

// Whether the faces (v, a, b) and (v, c, d), projected along an axis where both are non-flat,
// meet only at v: their angular sectors at v are then disjoint. If so the faces themselves meet
// only at v (a second common point w would project into both sectors, onto v only if vw ran
// along the axis, which a face not flat in that projection cannot contain). A filter in front of
// the exact 3D tests: in a mesh's flat regions neighbouring faces are nearly coplanar, where
// orient3d needs its exact expansion, while these 2D signs are clear.
bool sectors_apart(const V3& v, const V3& a, const V3& b, const V3& c, const V3& d) {
  const int k = projection_axis(v, a, b);
  if (k < 0) return false;
  const V2 pv = drop(v, k), pa = drop(a, k), pb = drop(b, k), pc = drop(c, k), pd = drop(d, k);
  const int o1 = orient2d(pv, pa, pb), o2 = orient2d(pv, pc, pd);
  if (o1 == 0 || o2 == 0) return false;
  // Each sector counter-clockwise from `lo` to `hi` (less than 180°): x is in the closed sector
  // when it is left of or on v→lo and right of or on v→hi.
  const V2& lo1 = o1 > 0 ? pa : pb;
  const V2& hi1 = o1 > 0 ? pb : pa;
  const V2& lo2 = o2 > 0 ? pc : pd;
  const V2& hi2 = o2 > 0 ? pd : pc;
  auto in_sector = [&](const V2& lo, const V2& hi, const V2& x) { return orient2d(pv, lo, x) >= 0 && orient2d(pv, hi, x) <= 0; };
  // Two such sectors overlap iff one holds a boundary ray of the other.
  return !in_sector(lo1, hi1, lo2) && !in_sector(lo1, hi1, hi2) && !in_sector(lo2, hi2, lo1);
}

// Whether the projections of two faces along an axis are strictly separated by the line of one
// of their edges: the faces are then disjoint (a common point would project into both). The
// same filter as sectors_apart for faces with no common corner: nearby faces of a flat region
// are nearly coplanar, where the 3D tests need exact arithmetic.
bool projections_apart(const Tri& t, const Tri& u) {
  int k = projection_axis(t[0], t[1], t[2]);
  if (k < 0) k = projection_axis(u[0], u[1], u[2]);
  if (k < 0) return false;
  V2 a[3], b[3];
  for (int i = 0; i < 3; ++i) a[i] = drop(t[i], k), b[i] = drop(u[i], k);
  // An edge of one separates when the other's corners are all strictly on its outer side.
  auto separates = [](const V2* p, const V2* q) {
    const int o = orient2d(p[0], p[1], p[2]);
    if (o == 0) return false;
    for (int i = 0; i < 3; ++i) {
      const V2 &e0 = p[i], &e1 = p[(i + 1) % 3];
      if (orient2d(e0, e1, q[0]) * o < 0 && orient2d(e0, e1, q[1]) * o < 0 && orient2d(e0, e1, q[2]) * o < 0) return true;
    }
    return false;
  };
  return separates(a, b) || separates(b, a);
}

// Faces (v, a, b) and (v, c, d) sharing vertex v: do they share a point other than v?
bool share_beyond_vertex(const V3& v, const V3& a, const V3& b, const V3& c, const V3& d) {
  // One face strictly on one side of the other's plane (except v): it meets that plane only at
  // v. On a curved surface the floating-point filter settles these signs; on a flat region
  // (nearly) coplanar neighbours leave them to the exact expansion, so the 2D sector test comes
  // before that. Each test alone proves the faces apart: the order changes no answer.
  const auto same_side = [](int s, int t) { return s != kUnsettled && t != kUnsettled && s * t > 0; };
  if (same_side(orient3d_filtered(v, c, d, a), orient3d_filtered(v, c, d, b)) ||
      same_side(orient3d_filtered(v, a, b, c), orient3d_filtered(v, a, b, d)))
    return false;
  if (sectors_apart(v, a, b, c, d)) return false;
  if (orient3d(v, c, d, a) * orient3d(v, c, d, b) > 0 || orient3d(v, a, b, c) * orient3d(v, a, b, d) > 0) return false;
  const bool flat1 = collinear(v, a, b), flat2 = collinear(v, c, d);
  if (!flat1 && !flat2) {
    // As CGAL: some point other than v is shared iff an opposite edge touches the other face.
    const V3 t1[3] = {v, a, b}, t2[3] = {v, c, d};
    return segment_triangle_intersect(a, b, t2) || segment_triangle_intersect(c, d, t1);
  }
  // General form of the same argument. Write a face as the hull of v and its far part F
  // (the opposite edge) with v not in F; then the faces share a point other than v iff
  // F1 meets face 2 or F2 meets face 1 (follow the ray from v through a shared point w != v
  // to where it leaves the nearer face: that exit point lies in that face's F and in the
  // other face). A flat face whose opposite edge contains v is the union of the two
  // segments [v, a] and [v, b], each of that form with F a single point.
  struct Piece { Tri far_part, face; };
  auto pieces = [&](const V3& x, const V3& y, Piece* out) {
    if (!point_on_segment(v, x, y)) {
      out[0] = {segment_tri(x, y), Tri{v, x, y}};
      return 1;
    }
    int n = 0;
    if (x != v) out[n++] = {Tri{x, x, x}, segment_tri(v, x)};
    if (y != v) out[n++] = {Tri{y, y, y}, segment_tri(v, y)};
    return n;
  };
  Piece p1[2], p2[2];
  const int n1 = pieces(a, b, p1), n2 = pieces(c, d, p2);
  for (int i = 0; i < n1; ++i)
    for (int j = 0; j < n2; ++j)
      if (triangles_intersect(p1[i].far_part, p2[j].face) || triangles_intersect(p2[j].far_part, p1[i].face))
        return true;
  return false;
}

// c lies on line ab strictly beyond b (b strictly between a and c). Requires collinearity, a != b.
bool beyond(const V3& a, const V3& b, const V3& c) { return lex_less(a, b) ? lex_less(b, c) : lex_less(c, b); }

// Faces (a, b, c) and (a, b, d) sharing the edge ab: do they share a point outside [a, b]?
bool share_beyond_edge(const V3& a, const V3& b, const V3& c, const V3& d) {
  if (a == b) return share_beyond_vertex(a, b, c, b, d);
  const int k = projection_axis(a, b, c);
  // c and d on opposite sides of ab in a projection where (a, b, c) is not flat: the faces meet
  // only in [a, b], coplanar or not (the argument of sectors_apart); no exact orient3d needed.
  if (k >= 0 && orient2d_axis(a, b, c, k) * orient2d_axis(a, b, d, k) < 0) return false;
  const bool flat1 = k < 0, flat2 = collinear(a, b, d);
  if (!flat1 && !flat2) {
    // Non-coplanar faces meet only on their common line, i.e. in [a, b]; coplanar ones
    // overlap in 2D iff c and d are strictly on the same side of ab.
    if (orient3d(a, b, c, d) != 0) return false;
    return orient2d_axis(a, b, c, k) * orient2d_axis(a, b, d, k) > 0;
  }
  // A flat face lies on line ab; a non-flat face meets that line only in [a, b].
  if (flat1 != flat2) return false;
  return (beyond(a, b, c) && beyond(a, b, d)) || (beyond(b, a, c) && beyond(b, a, d));
}

}  // namespace

int orient3d(const V3& a, const V3& b, const V3& c, const V3& d) {
  const int sign = orient3d_filtered(a, b, c, d);
  if (sign != kUnsettled) return sign;
  if (orient3d_expansion_ok(a, b, c, d)) return orient3d_expansion(a, b, c, d);
  return orient3d_gmp(a, b, c, d);
}

int orient2d(const V2& a, const V2& b, const V2& c) {
  const double bx = b.x() - a.x(), by = b.y() - a.y();
  const double cx = c.x() - a.x(), cy = c.y() - a.y();
  const double det = bx * cy - by * cx;
  const double mx = std::max(std::abs(bx), std::abs(cx)), my = std::max(std::abs(by), std::abs(cy));
  const double lo = std::min(mx, my), hi = std::max(mx, my);
  if (lo == 0) return 0;
  if (lo >= kOrient2dMin && hi <= kOrient2dMax) {
    const double eps = kOrient2dBound * mx * my;
    if (det > eps) return 1;
    if (det < -eps) return -1;
  }
  if (orient2d_expansion_ok(a, b, c)) return orient2d_expansion(a, b, c);
  return orient2d_gmp(a, b, c);
}

bool triangles_intersect(const Tri& t, const Tri& u) {
  int su[3], st[3];
  for (int i = 0; i < 3; ++i) su[i] = orient3d(t[0], t[1], t[2], u[i]);
  if (su[0] != 0 && su[0] == su[1] && su[0] == su[2]) return false;
  for (int i = 0; i < 3; ++i) st[i] = orient3d(u[0], u[1], u[2], t[i]);
  if (st[0] != 0 && st[0] == st[1] && st[0] == st[2]) return false;
  // A degenerate triangle has orientation 0 with every point, so "not all zero" on both
  // sides means both are proper triangles in different planes: the common fast path.
  const bool flat_u = su[0] == 0 && su[1] == 0 && su[2] == 0;
  const bool flat_t = st[0] == 0 && st[1] == 0 && st[2] == 0;
  if (flat_u || flat_t) return shapes_intersect(t, u);
  return straddling_triangles_intersect(t, st, u, su);
}

bool faces_self_intersect(const Tri& p, const std::array<int, 3>& pi, const Tri& q, const std::array<int, 3>& qi) {
  // Distinct shared indices, with their first position in p and in q.
  int shared_p[3], shared_q[3], n = 0;
  for (int i = 0; i < 3; ++i) {
    bool seen = false;
    for (int s = 0; s < n; ++s) seen = seen || pi[shared_p[s]] == pi[i];
    if (seen) continue;
    for (int j = 0; j < 3; ++j)
      if (qi[j] == pi[i]) {
        shared_p[n] = i, shared_q[n] = j, ++n;
        break;
      }
  }
  if (n == 0) return !projections_apart(p, q) && triangles_intersect(p, q);
  if (n == 3) return true;
  if (n == 1) {
    const int i = shared_p[0], j = shared_q[0];
    return share_beyond_vertex(p[i], p[(i + 1) % 3], p[(i + 2) % 3], q[(j + 1) % 3], q[(j + 2) % 3]);
  }
  // n == 2: the third vertex is the remaining position (a repeated index makes it one of
  // the shared vertices again, i.e. a flat face).
  const int i0 = shared_p[0], i1 = shared_p[1], j0 = shared_q[0], j1 = shared_q[1];
  return share_beyond_edge(p[i0], p[i1], p[3 - i0 - i1], q[3 - j0 - j1]);
}

}  // namespace s2c
