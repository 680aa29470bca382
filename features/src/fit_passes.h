#pragma once
// The per-sample passes of the fits' models (fit_models.h: sphere, cylinder, cone) four samples
// per instruction, where the CPU has AVX. The build targets x86-64 without AVX (no -march=native,
// see CMakeLists.txt), so these are compiled for AVX function by function and chosen at run time.
// Each lane does the arithmetic of the models' own passes, operation for operation, and AVX
// without FMA rounds each operation as SSE2 does: the results are the same to the bit on either
// path (tests/unit/features/fit_models_test.cpp compares them).
namespace s2c::features::fit {

/// The samples by coordinate (SampleColumns), m of them.
struct ColumnView {
  const double *x, *y, *z, *sw;
  int m;
};

/// Per sample, for an axis through q along b: h = b·v, w = v − h b with v = sample − q, rho = |w|.
struct AxisGeometry {
  double *h, *wx, *wy, *wz, *rho;
};

/// True when the CPU (and the operating system) run AVX: checked once.
bool have_avx_passes();

/// The geometry of the axis through q along b into `g`, and the residuals
/// sw ((rho − r) cos θ − h sin θ) into `out` unless it is null. Only when have_avx_passes().
void axis_residuals_avx(const ColumnView& c, const double q[3], const double b[3], double r, double cos_theta,
                        double sin_theta, const AxisGeometry& g, double* out);

/// JᵀJ into A (K × K, column-major) and Jᵀres into jr for the Jacobian of AxisModel<K> (K = 5
/// or 6) at its current parameters: the axis through p, its perpendicular frame (u, t), radius r,
/// half angle θ, with `g` the geometry at those parameters. Each entry is summed over the samples
/// in order, as normal_equations() sums the rows of the stored Jacobian; the Jacobian itself is
/// never stored. Only when have_avx_passes().
void axis_normal_equations_avx(int K, const ColumnView& c, const AxisGeometry& g, const double p[3],
                               const double u[3], const double t[3], double r, double cos_theta, double sin_theta,
                               const double* res, double* A, double* jr);

/// The sphere's residuals sw (|sample − c| − r) into `out`. Only when have_avx_passes().
void sphere_residuals_avx(const ColumnView& c, const double center[3], double r, double* out);

/// JᵀJ into A (4 × 4, column-major) and Jᵀres into jr for the sphere's Jacobian at centre c,
/// summed over the samples in order as normal_equations() sums. Only when have_avx_passes().
void sphere_normal_equations_avx(const ColumnView& c, const double center[3], const double* res, double* A,
                                 double* jr);

}  // namespace s2c::features::fit
