#include "fit_passes.h"

#include <immintrin.h>

// Compiled for AVX (without FMA) function by function; called only when have_avx_passes().
#define S2C_AVX __attribute__((target("avx")))

namespace s2c::features::fit {

bool have_avx_passes() {
  static const bool avx = __builtin_cpu_supports("avx");
  return avx;
}

namespace {

/// Lanes [0, n) of a 4-sample group, for the masked loads and stores of the last group.
S2C_AVX inline __m256i lanes(int n) {
  return _mm256_set_epi64x(n > 3 ? -1 : 0, n > 2 ? -1 : 0, n > 1 ? -1 : 0, n > 0 ? -1 : 0);
}

S2C_AVX inline __m256d load(const double* a, int n, __m256i mask) {
  return n == 4 ? _mm256_loadu_pd(a) : _mm256_maskload_pd(a, mask);
}

S2C_AVX inline void store(double* a, __m256d v, int n, __m256i mask) {
  if (n == 4)
    _mm256_storeu_pd(a, v);
  else
    _mm256_maskstore_pd(a, mask, v);
}

S2C_AVX inline __m256d negated(__m256d v) { return _mm256_xor_pd(v, _mm256_set1_pd(-0.0)); }

/// (x·e0 + y·e1) + z·e2, the order of Eigen's 3-vector dot product.
S2C_AVX inline __m256d dot(__m256d x, __m256d y, __m256d z, const double e[3]) {
  return _mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(x, _mm256_set1_pd(e[0])), _mm256_mul_pd(y, _mm256_set1_pd(e[1]))),
                       _mm256_mul_pd(z, _mm256_set1_pd(e[2])));
}

/// sample − q for the samples [i, i + n) of `c`, by coordinate.
struct Offset {
  __m256d x, y, z;
};
S2C_AVX inline Offset offset(const ColumnView& c, int i, int n, __m256i mask, const double q[3]) {
  return {_mm256_sub_pd(load(c.x + i, n, mask), _mm256_set1_pd(q[0])),
          _mm256_sub_pd(load(c.y + i, n, mask), _mm256_set1_pd(q[1])),
          _mm256_sub_pd(load(c.z + i, n, mask), _mm256_set1_pd(q[2]))};
}

/// sqrt((x² + y²) + z²), the order of Eigen's 3-vector norm.
S2C_AVX inline __m256d length(__m256d x, __m256d y, __m256d z) {
  return _mm256_sqrt_pd(_mm256_add_pd(_mm256_add_pd(_mm256_mul_pd(x, x), _mm256_mul_pd(y, y)), _mm256_mul_pd(z, z)));
}

/// Four columns of four samples' values as the samples' rows: row s gets (c0[s], c1[s], c2[s],
/// c3[s]) at rows + s·stride (32-byte aligned).
S2C_AVX inline void store_rows(__m256d c0, __m256d c1, __m256d c2, __m256d c3, double* rows, int stride) {
  const __m256d t0 = _mm256_unpacklo_pd(c0, c1), t1 = _mm256_unpackhi_pd(c0, c1);
  const __m256d t2 = _mm256_unpacklo_pd(c2, c3), t3 = _mm256_unpackhi_pd(c2, c3);
  _mm256_store_pd(rows, _mm256_permute2f128_pd(t0, t2, 0x20));
  _mm256_store_pd(rows + stride, _mm256_permute2f128_pd(t1, t3, 0x20));
  _mm256_store_pd(rows + 2 * stride, _mm256_permute2f128_pd(t0, t2, 0x31));
  _mm256_store_pd(rows + 3 * stride, _mm256_permute2f128_pd(t1, t3, 0x31));
}

}  // namespace

S2C_AVX void axis_residuals_avx(const ColumnView& c, const double q[3], const double b[3], double r, double cos_theta,
                                double sin_theta, const AxisGeometry& g, double* out) {
  const __m256d bx = _mm256_set1_pd(b[0]), by = _mm256_set1_pd(b[1]), bz = _mm256_set1_pd(b[2]);
  const __m256d rr = _mm256_set1_pd(r), ct = _mm256_set1_pd(cos_theta), st = _mm256_set1_pd(sin_theta);
  for (int i = 0; i < c.m; i += 4) {
    const int n = c.m - i < 4 ? c.m - i : 4;
    const __m256i mask = lanes(n);
    const Offset v = offset(c, i, n, mask, q);
    const __m256d h = dot(v.x, v.y, v.z, b);
    const __m256d wx = _mm256_sub_pd(v.x, _mm256_mul_pd(h, bx));
    const __m256d wy = _mm256_sub_pd(v.y, _mm256_mul_pd(h, by));
    const __m256d wz = _mm256_sub_pd(v.z, _mm256_mul_pd(h, bz));
    const __m256d rho = length(wx, wy, wz);
    const __m256d res = _mm256_mul_pd(load(c.sw + i, n, mask),
                                      _mm256_sub_pd(_mm256_mul_pd(_mm256_sub_pd(rho, rr), ct), _mm256_mul_pd(h, st)));
    store(g.h + i, h, n, mask);
    store(g.wx + i, wx, n, mask);
    store(g.wy + i, wy, n, mask);
    store(g.wz + i, wz, n, mask);
    store(g.rho + i, rho, n, mask);
    if (out) store(out + i, res, n, mask);
  }
}

namespace {

/// The Jacobian rows of samples [i, i + n), n ≤ 4, into rows[0..n) (eight doubles each, the last
/// two unused).
template <int K>
S2C_AVX void jacobian_rows(const ColumnView& c, const AxisGeometry& g, int i, int n, const double p[3],
                           const double u[3], const double t[3], double r, double cos_theta, double sin_theta,
                           double (*rows)[8]) {
  const __m256i mask = lanes(n);
  const __m256d ct = _mm256_set1_pd(cos_theta), st = _mm256_set1_pd(sin_theta), zero = _mm256_setzero_pd();
  const Offset v = offset(c, i, n, mask, p);
  const __m256d rho = load(g.rho + i, n, mask), h = load(g.h + i, n, mask), sw = load(c.sw + i, n, mask);
  const __m256d wx = load(g.wx + i, n, mask), wy = load(g.wy + i, n, mask), wz = load(g.wz + i, n, mask);
  // (w·u, w·t)/rho, zero where rho is not positive (on the axis; any direction is a subgradient).
  const __m256d off_axis = _mm256_cmp_pd(rho, zero, _CMP_GT_OQ);
  const __m256d wu = _mm256_and_pd(_mm256_div_pd(dot(wx, wy, wz, u), rho), off_axis);
  const __m256d wt = _mm256_and_pd(_mm256_div_pd(dot(wx, wy, wz, t), rho), off_axis);
  const __m256d du = dot(v.x, v.y, v.z, u), dt = dot(v.x, v.y, v.z, t);
  const __m256d ct_h = _mm256_mul_pd(_mm256_set1_pd(-cos_theta), h);  // (−cos θ) h
  const __m256d j0 = _mm256_mul_pd(sw, _mm256_sub_pd(_mm256_mul_pd(ct_h, wu), _mm256_mul_pd(st, du)));
  const __m256d j1 = _mm256_mul_pd(sw, _mm256_sub_pd(_mm256_mul_pd(ct_h, wt), _mm256_mul_pd(st, dt)));
  const __m256d sw_ct = _mm256_mul_pd(negated(sw), ct);  // (−sw) cos θ
  const __m256d j2 = _mm256_mul_pd(sw_ct, wu), j3 = _mm256_mul_pd(sw_ct, wt), j4 = sw_ct;
  const __m256d j5 = K > 5 ? _mm256_mul_pd(sw, _mm256_sub_pd(_mm256_mul_pd(negated(_mm256_sub_pd(rho, _mm256_set1_pd(r))), st),
                                                             _mm256_mul_pd(h, ct)))
                           : zero;
  // The rows: a 4 × 4 transpose of (J0..J3), and (J4, J5) by pairs.
  store_rows(j0, j1, j2, j3, rows[0], 8);
  const __m256d e0 = _mm256_unpacklo_pd(j4, j5), e1 = _mm256_unpackhi_pd(j4, j5);
  _mm_store_pd(rows[0] + 4, _mm256_castpd256_pd128(e0));
  _mm_store_pd(rows[1] + 4, _mm256_castpd256_pd128(e1));
  _mm_store_pd(rows[2] + 4, _mm256_extractf128_pd(e0, 1));
  _mm_store_pd(rows[3] + 4, _mm256_extractf128_pd(e1, 1));
}

template <int K>
S2C_AVX void normal_equations(const ColumnView& c, const AxisGeometry& g, const double p[3], const double u[3],
                              const double t[3], double r, double cos_theta, double sin_theta, const double* res,
                              double* A, double* jr) {
  static_assert(K == 5 || K == 6, "the cylinder and the cone");
  // Per sample, with its row (J0..J5): A's column b gets (J0..J3) J_b in rows 0-3 (b ≤ 3) and
  // (J4, J5) J_b in rows 4-5: every entry of the lower triangle, each a sum in sample order. Named
  // one by one: GCC kept arrays of them on the stack, a store per sum and sample.
  __m256d c0 = _mm256_setzero_pd(), c1 = c0, c2 = c0, c3 = c0, g_top = c0;  // A(0..3, b), Jᵀres(0..3)
  __m128d d0 = _mm_setzero_pd(), d1 = d0, d2 = d0, d3 = d0, d4 = d0, d5 = d0, g_bottom = d0;  // A(4..5, b)
  // The rows of a block of samples first, then their sums: the sums take most registers.
  constexpr int kBlock = 32;
  alignas(32) double rows[kBlock][8];  // (the last two of each unused)
  for (int begin = 0; begin < c.m; begin += kBlock) {
    const int end = c.m - begin < kBlock ? c.m : begin + kBlock;
    for (int i = begin; i < end; i += 4)
      jacobian_rows<K>(c, g, i, end - i < 4 ? end - i : 4, p, u, t, r, cos_theta, sin_theta, rows + (i - begin));
    for (int i = begin; i < end; ++i) {
      const double* row = rows[i - begin];
      const __m256d head = _mm256_load_pd(row);
      const __m128d tail = _mm_load_pd(row + 4);
      c0 = _mm256_add_pd(c0, _mm256_mul_pd(head, _mm256_broadcast_sd(row)));
      c1 = _mm256_add_pd(c1, _mm256_mul_pd(head, _mm256_broadcast_sd(row + 1)));
      c2 = _mm256_add_pd(c2, _mm256_mul_pd(head, _mm256_broadcast_sd(row + 2)));
      c3 = _mm256_add_pd(c3, _mm256_mul_pd(head, _mm256_broadcast_sd(row + 3)));
      d0 = _mm_add_pd(d0, _mm_mul_pd(tail, _mm_loaddup_pd(row)));
      d1 = _mm_add_pd(d1, _mm_mul_pd(tail, _mm_loaddup_pd(row + 1)));
      d2 = _mm_add_pd(d2, _mm_mul_pd(tail, _mm_loaddup_pd(row + 2)));
      d3 = _mm_add_pd(d3, _mm_mul_pd(tail, _mm_loaddup_pd(row + 3)));
      d4 = _mm_add_pd(d4, _mm_mul_pd(tail, _mm_loaddup_pd(row + 4)));
      if (K > 5) d5 = _mm_add_pd(d5, _mm_mul_pd(tail, _mm_loaddup_pd(row + 5)));
      g_top = _mm256_add_pd(g_top, _mm256_mul_pd(head, _mm256_broadcast_sd(res + i)));
      g_bottom = _mm_add_pd(g_bottom, _mm_mul_pd(tail, _mm_loaddup_pd(res + i)));
    }
  }
  const __m256d top[4] = {c0, c1, c2, c3};
  const __m128d bottom[6] = {d0, d1, d2, d3, d4, d5};
  // The lower triangle, mirrored (J_a J_b and J_b J_a are the same product).
  alignas(32) double v[4];
  for (int b = 0; b < 4; ++b) {
    _mm256_store_pd(v, top[b]);
    for (int a = b; a < 4; ++a) A[a + K * b] = A[b + K * a] = v[a];
  }
  for (int b = 0; b < K; ++b) {
    _mm_store_pd(v, bottom[b]);
    for (int a = 4; a < K; ++a)
      if (a >= b) A[a + K * b] = A[b + K * a] = v[a - 4];
  }
  _mm256_store_pd(v, g_top);
  for (int a = 0; a < 4; ++a) jr[a] = v[a];
  _mm_store_pd(v, g_bottom);
  for (int a = 4; a < K; ++a) jr[a] = v[a - 4];
}

}  // namespace

S2C_AVX void axis_normal_equations_avx(int K, const ColumnView& c, const AxisGeometry& g, const double p[3],
                                       const double u[3], const double t[3], double r, double cos_theta,
                                       double sin_theta, const double* res, double* A, double* jr) {
  if (K == 6)
    normal_equations<6>(c, g, p, u, t, r, cos_theta, sin_theta, res, A, jr);
  else
    normal_equations<5>(c, g, p, u, t, r, cos_theta, sin_theta, res, A, jr);
}

S2C_AVX void sphere_residuals_avx(const ColumnView& c, const double center[3], double r, double* out) {
  const __m256d rr = _mm256_set1_pd(r);
  for (int i = 0; i < c.m; i += 4) {
    const int n = c.m - i < 4 ? c.m - i : 4;
    const __m256i mask = lanes(n);
    const Offset v = offset(c, i, n, mask, center);
    const __m256d len = length(v.x, v.y, v.z);
    store(out + i, _mm256_mul_pd(load(c.sw + i, n, mask), _mm256_sub_pd(len, rr)), n, mask);
  }
}

S2C_AVX void sphere_normal_equations_avx(const ColumnView& c, const double center[3], const double* res, double* A,
                                         double* jr) {
  const __m256d zero = _mm256_setzero_pd();
  // Per sample the row (−sw/len) (v, 0) + (0, 0, 0, −sw) with v = sample − c (zero but the last
  // where len is not positive); A's column b gets the row times its entry b: all sixteen entries,
  // each a sum in sample order.
  __m256d a0 = zero, a1 = zero, a2 = zero, a3 = zero, g = zero;
  alignas(32) double rows[4][4];
  for (int i = 0; i < c.m; i += 4) {
    const int n = c.m - i < 4 ? c.m - i : 4;
    const __m256i mask = lanes(n);
    const Offset v = offset(c, i, n, mask, center);
    const __m256d len = length(v.x, v.y, v.z);
    const __m256d minus_sw = negated(load(c.sw + i, n, mask));
    const __m256d positive = _mm256_cmp_pd(len, zero, _CMP_GT_OQ);
    const __m256d t = _mm256_div_pd(minus_sw, len);  // (−sw) / len
    const __m256d j0 = _mm256_and_pd(_mm256_mul_pd(t, v.x), positive);
    const __m256d j1 = _mm256_and_pd(_mm256_mul_pd(t, v.y), positive);
    const __m256d j2 = _mm256_and_pd(_mm256_mul_pd(t, v.z), positive);
    store_rows(j0, j1, j2, minus_sw, rows[0], 4);
    for (int s = 0; s < n; ++s) {
      const double* row = rows[s];
      const __m256d head = _mm256_load_pd(row);
      a0 = _mm256_add_pd(a0, _mm256_mul_pd(head, _mm256_broadcast_sd(row)));
      a1 = _mm256_add_pd(a1, _mm256_mul_pd(head, _mm256_broadcast_sd(row + 1)));
      a2 = _mm256_add_pd(a2, _mm256_mul_pd(head, _mm256_broadcast_sd(row + 2)));
      a3 = _mm256_add_pd(a3, _mm256_mul_pd(head, _mm256_broadcast_sd(row + 3)));
      g = _mm256_add_pd(g, _mm256_mul_pd(head, _mm256_broadcast_sd(res + i + s)));
    }
  }
  _mm256_storeu_pd(A, a0);
  _mm256_storeu_pd(A + 4, a1);
  _mm256_storeu_pd(A + 8, a2);
  _mm256_storeu_pd(A + 12, a3);
  _mm256_storeu_pd(jr, g);
}

}  // namespace s2c::features::fit
