#pragma once
// Private helpers of the shape fits (fit_surface.cpp, fit_curve.cpp): sample checks, normalised
// and subsampled copies of the samples, weighted PCA, the algebraic circle fit and a small
// Levenberg–Marquardt solver for models with a handful of parameters.
#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <type_traits>
#include <utility>
#include <vector>

#include <emmintrin.h>

#include <Eigen/Dense>

#include "s2c/features/shape.h"

namespace s2c::features::fit {

/// At most this many samples enter the nonlinear refinement (metrics use all of them).
constexpr int kMaxRefineSamples = 5000;
constexpr int kMaxIterations = 50;

/// The samples the refinement runs on, in normalised coordinates: centred on the weighted
/// centroid and scaled to unit RMS radius, so every parameter is O(1) and the tolerances of the
/// solver are scale free. Subsampled (stratified, deterministic) to kMaxRefineSamples.
struct Normalized {
  Eigen::Vector3d center = Eigen::Vector3d::Zero();
  double scale = 1.0;                  ///< mm per normalised unit
  std::vector<Eigen::Vector3d> p;      ///< normalised positions
  std::vector<Eigen::Vector3d> n;      ///< unit normals, zero where unknown
  std::vector<double> w;               ///< weights, mean 1
  std::vector<double> sw;              ///< sqrt(w): residual factors
  int normal_count = 0;                ///< samples with a known normal

  Eigen::Vector3d to_world(const Eigen::Vector3d& q) const { return center + scale * q; }
  int size() const { return static_cast<int>(p.size()); }
};

/// Indices of a deterministic stratified subsample of 0..n-1: all of them when n ≤ max, else one
/// per stratum of n/max at a pseudo-random offset, ascending.
std::vector<std::size_t> stratified_pick(std::size_t n, std::size_t max);

/// Checks `s` and builds its normalised subsample. False when the samples cannot determine a shape
/// with `min_count` parameters: NaN/inf anywhere, negative weights, fewer than `min_count`
/// samples of positive weight, or all points (numerically) equal.
/// \throw InvalidInput if normals or weights are neither empty nor as many as the points.
bool normalize(const Samples& s, int min_count, Normalized& out, int max_samples = kMaxRefineSamples);

/// normalize() without its minimum count, for the fits of several types of one sample set (each
/// normalised the same samples anew): enough(k) is what normalize(s, k, …) returns.
struct Normalization {
  Normalized samples;
  int positive = 0;       ///< samples of positive weight
  int pick_positive = 0;  ///< of them in the subsample
  bool valid = false;     ///< finite, of positive total weight, not all at one point
  bool enough(int min_count) const;
};
/// \throw InvalidInput as normalize.
Normalization normalization(const Samples& s, int max_samples = kMaxRefineSamples);

/// Weighted principal axes of points: eigenvalues ascending, eigenvectors in the columns.
struct Pca {
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d values = Eigen::Vector3d::Zero();
  Eigen::Matrix3d vectors = Eigen::Matrix3d::Identity();
};
/// `w` may be empty (all 1).
Pca pca(const std::vector<Eigen::Vector3d>& p, const std::vector<double>& w);

struct SampleColumns;

/// The surface fits of one sample set (fit_plane … fit_cone, refit_surface) on one normalisation
/// and its columns, and the cylinder's and the cone's starts on one set of principal axes:
/// choose_shape fits every type to the same samples, and each fit normalised (and copied) them
/// anew. The fits may run side by side.
class SurfaceFits {
 public:
  /// \throw InvalidInput as the fits.
  explicit SurfaceFits(const Samples& s);
  /// As fit_plane, fit_sphere, fit_cylinder, fit_cone; Fit{} for other types.
  Fit fit(ShapeType type) const;
  /// As refit_surface.
  Fit refit(const Shape& start) const;

 private:
  const Pca& principal_axes() const;
  const std::shared_ptr<const SampleColumns>& columns() const;

  const Samples& s_;
  Normalization n_;
  mutable std::once_flag pca_once_, columns_once_;
  mutable Pca pca_;
  mutable std::shared_ptr<const SampleColumns> columns_;
};

/// Orthonormal u, v (columns) perpendicular to the unit vector a.
Eigen::Matrix<double, 3, 2> perpendicular_frame(const Eigen::Vector3d& a);

/// Weighted algebraic (Kåsa) circle fit of 2D points: minimises Σ w (|q|² + D·q + F)².
/// False when the points are collinear or too few.
bool kasa_circle(const std::vector<Eigen::Vector2d>& q, const std::vector<double>& w, Eigen::Vector2d& center,
                 double& radius);

/// The straight line through `point` along the unit `dir`, clipped to the projections of the first
/// and last of the ordered points.
Shape clipped_line(const Eigen::Vector3d& point, const Eigen::Vector3d& dir, const std::vector<Eigen::Vector3d>& pts);

/// The point of the circle (centre, unit normal, radius) nearest to p.
Eigen::Vector3d onto_circle(const Shape& circle, const Eigen::Vector3d& p);

/// Types `circle` (centre, unit normal and radius set) by the angle the ordered points sweep
/// around it: a circle when the chain is closed or sweeps ≥ 350°, otherwise an arc from the first
/// to the last point. `orient` turns the normal so the sweep is counter-clockwise about it.
void circle_or_arc(Shape& circle, const std::vector<Eigen::Vector3d>& pts, bool closed, bool orient);

/// Fills rms, max_error, normal_rms_deg over all samples of `s` (weighted) and sets ok when the
/// shape and the metrics are finite. Normal angles are unsigned (a hole's inward normals agree).
void finish(Fit& f, const Samples& s);

/// True when every number of the shape is finite.
bool finite(const Shape& s);

/// The Jacobian of a model's residuals: one row per residual, rows contiguous (the solver reads
/// it row by row).
template <int K>
using Jacobian = Eigen::Matrix<double, Eigen::Dynamic, K, Eigen::RowMajor>;

/// True when Model has `void jacobian(Jacobian<kParams>& J) const`: the analytic Jacobian of its
/// residuals at delta = 0.
template <class Model, class = void>
struct has_jacobian : std::false_type {};
template <class Model>
struct has_jacobian<Model, std::void_t<decltype(std::declval<const Model&>().jacobian(
                               std::declval<Jacobian<Model::kParams>&>()))>>
    : std::true_type {};

/// JᵀJ into A and Jᵀr into g for the m rows of J (row-major, K columns), each entry summed over
/// the rows in order. Only the lower triangle is summed, in packets of two neighbouring entries of
/// one matrix row: (J_ia J_ib, J_ia J_ib+1) is J_ia times two neighbouring entries of the row, one
/// unaligned load: twelve packets for K = 6, and g's three (the whole outer product took
/// eighteen, most of them spilled to the stack on every row; GCC still spills a few of these).
/// The upper triangle is copied from the lower: J_ia J_ib and J_ib J_ia are the same product, so
/// A is what the full sums give.
template <int K>
void normal_equations(const double* J, const double* r, int m, Eigen::Matrix<double, K, K>& A,
                      Eigen::Matrix<double, K, 1>& g) {
  static_assert(K >= 1 && K <= 8, "a model with a handful of parameters");
  constexpr int kPairs = (K + 1) / 2;
  // The pair of row entries (b, b + 1); the last alone when K is odd (its neighbour is the next
  // row's first entry, or past the end of J).
  auto pair = [](const double* row, int b) { return b + 1 < K ? _mm_loadu_pd(row + b) : _mm_load_sd(row + b); };
  __m128d acc[K][kPairs], gacc[kPairs];
  for (int a = 0; a < K; ++a)
    for (int j = 0; j < kPairs; ++j) acc[a][j] = _mm_setzero_pd();
  for (int j = 0; j < kPairs; ++j) gacc[j] = _mm_setzero_pd();
  for (int i = 0; i < m; ++i) {
    const double* row = J + static_cast<std::ptrdiff_t>(i) * K;
    const __m128d ri = _mm_set1_pd(r[i]);
    for (int j = 0; j < kPairs; ++j) gacc[j] = _mm_add_pd(gacc[j], _mm_mul_pd(pair(row, 2 * j), ri));
    for (int a = 0; a < K; ++a) {
      const __m128d ra = _mm_set1_pd(row[a]);
      for (int j = 0; 2 * j <= a; ++j) acc[a][j] = _mm_add_pd(acc[a][j], _mm_mul_pd(ra, pair(row, 2 * j)));
    }
  }
  alignas(16) double out[2];
  for (int a = 0; a < K; ++a)
    for (int j = 0; 2 * j <= a; ++j) {
      _mm_store_pd(out, acc[a][j]);
      for (int t = 0; t < 2 && 2 * j + t <= a; ++t) A(a, 2 * j + t) = A(2 * j + t, a) = out[t];
    }
  for (int j = 0; j < kPairs; ++j) {
    _mm_store_pd(out, gacc[j]);
    for (int t = 0; t < 2 && 2 * j + t < K; ++t) g[2 * j + t] = out[t];
  }
}

/// True when Model has `void normal_equations(const Eigen::VectorXd& r, Matrix<k, k>& A, Vector<k>& g)
/// const`: JᵀJ and Jᵀr of its analytic Jacobian at delta = 0, summed as normal_equations() sums.
template <class Model, class = void>
struct has_normal_equations : std::false_type {};
template <class Model>
struct has_normal_equations<
    Model, std::void_t<decltype(std::declval<const Model&>().normal_equations(
               std::declval<const Eigen::VectorXd&>(),
               std::declval<Eigen::Matrix<double, Model::kParams, Model::kParams>&>(),
               std::declval<Eigen::Matrix<double, Model::kParams, 1>&>()))>> : std::true_type {};

/// Minimises Σ r_i² with Levenberg–Marquardt (the model's analytic Jacobian when it has one, a
/// forward-difference Jacobian otherwise: k more residual passes per iteration). The model holds its
/// current parameters and is re-based after each accepted step, so a parameterisation local to
/// the current estimate (axis tilts in its perpendicular frame) stays non-degenerate. Model:
///   static constexpr int kParams;
///   int residual_count() const;
///   void residuals(const Eigen::Matrix<double, kParams, 1>& delta, Eigen::VectorXd& r) const;
///   void update(const Eigen::Matrix<double, kParams, 1>& delta);  // residuals(0) afterwards == residuals(delta) before
/// Returns the final cost Σ r_i² (inf/NaN when the model is not evaluable).
template <class Model>
double levenberg_marquardt(Model& model, int max_iterations = kMaxIterations) {
  constexpr int k = Model::kParams;
  using Vec = Eigen::Matrix<double, k, 1>;
  using Mat = Eigen::Matrix<double, k, k>;
  const int m = model.residual_count();
  Eigen::VectorXd r(m), r_try(m);
  Jacobian<k> J(has_normal_equations<Model>::value ? 0 : m, k);
  model.residuals(Vec::Zero(), r);
  double cost = r.squaredNorm();
  if (!std::isfinite(cost)) return cost;
  // Parameters are O(1) in normalised coordinates: an absolute step suits all of them.
  [[maybe_unused]] constexpr double h = 1e-7;
  double lambda = 1e-3;
  for (int it = 0; it < max_iterations && cost > 1e-28; ++it) {
    Mat A;
    Vec g;
    if constexpr (has_normal_equations<Model>::value) {
      model.normal_equations(r, A, g);
    } else {
      if constexpr (has_jacobian<Model>::value) {
        model.jacobian(J);
      } else {
        for (int j = 0; j < k; ++j) {
          Vec d = Vec::Zero();
          d[j] = h;
          model.residuals(d, r_try);
          J.col(j) = (r_try - r) / h;
        }
      }
      normal_equations<k>(J.data(), r.data(), m, A, g);
    }
    const double floor = 1e-12 * std::max(A.trace() / k, 1e-300);
    bool accepted = false, converged = false;
    while (lambda < 1e12) {
      Mat B = A;
      for (int j = 0; j < k; ++j) B(j, j) += lambda * std::max(A(j, j), floor);
      const Vec step = -B.ldlt().solve(g);
      if (!step.allFinite()) {
        lambda *= 10;
        continue;
      }
      model.residuals(step, r_try);
      const double c = r_try.squaredNorm();
      if (std::isfinite(c) && c < cost) {
        model.update(step);
        r.swap(r_try);
        // At 1e-12 four of five cone runs went on to the iteration cap, creeping along a flat
        // valley by 1e-5 of the cost per step. Ceres' default, 1e-6, split a sphere patch of the
        // CGAL fandisk (a 17-face cone and a lone face beside it); at 1e-7 every patch is the one
        // 1e-12 gave, in the time 1e-6 takes.
        converged = (cost - c) < 1e-7 * cost || step.norm() < 1e-12;
        cost = c;
        lambda = std::max(lambda / 3.0, 1e-12);
        accepted = true;
        break;
      }
      lambda *= 4;
    }
    if (!accepted || converged) break;
  }
  return cost;
}

}  // namespace s2c::features::fit
