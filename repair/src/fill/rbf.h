#pragma once
// The implicit surface of ../shared/papers/rbf-hole-filling.txt: f(x) = Σ w_j |x - c_j|³ + p0 + p·x
// (eqs. 5, 6, 10) with on-surface constraints f = 0 and normal-offset constraints f = d, and the
// gradient projection of the patch vertices onto f = 0 (eqs. 11, 12).
#include <cstddef>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "fill/patch.h"
#include "s2c/repair/fill.h"

namespace s2c::repair::fill {

enum class RbfSolver {
  /// Null-space method: with P = Q [R; 0] (Householder QR of the N×4 polynomial block),
  /// w = Z y for Z = the last N-4 columns of Q, and Zᵀ Φ Z y = Zᵀ h. r³ is conditionally
  /// positive definite of order 2, so Zᵀ Φ Z is SPD: Cholesky (LAPACK dpotrf), N³/3 flops.
  nullspace_llt,
  /// The paper's (N+4)² saddle-point system (eq. 9) by LU with partial pivoting, 2N³/3 flops.
  /// (Not LDLT: the system is indefinite and Eigen's LDLT fails on it without saying so.)
  lu,
};

/// One global cubic RBF (eq. 5–9). Coordinates are centred and scaled to a unit box inside.
class CubicRbf {
 public:
  /// Fits f(centers[i]) = values[i]. \return false when the system is singular (e.g.
  /// coincident centres, or all centres in one plane with the linear part undetermined).
  /// When a linear function meets every value within `linear_tolerance` (the values' unit), it
  /// is the fit: the interpolant is unique and for linear data it has no radial part, so the
  /// N×N solve would only return zero weights (a planar piece of a CAD mesh: a flat face).
  bool fit(const std::vector<Eigen::Vector3d>& centers, const std::vector<double>& values,
           RbfSolver solver = RbfSolver::nullspace_llt, double linear_tolerance = 0);
  double value(const Eigen::Vector3d& x) const;
  /// ∇f (eq. 11).
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const;
  /// f and ∇f in one pass over the centres (what the projection needs at every step).
  void evaluate(const Eigen::Vector3d& x, double& f, Eigen::Vector3d& g) const;
  /// Centres with a radial term: 0 when the fit is linear.
  std::size_t size() const { return static_cast<std::size_t>(cx_.size()); }

 private:
  /// The linear fit of `h` over the polynomial block P (normalised coordinates) when it meets
  /// every value within `tolerance`; then the weights are empty.
  bool fit_linear(const Eigen::MatrixXd& P, const Eigen::Ref<const Eigen::VectorXd>& h, double tolerance);

  Eigen::Vector3d shift_ = Eigen::Vector3d::Zero();
  double scale_ = 1;                              // normalised = (x - shift) * scale
  Eigen::ArrayXd cx_, cy_, cz_;                   // normalised centres, one array per coordinate
  Eigen::ArrayXd w_;                              // #N weights
  Eigen::Vector4d p_ = Eigen::Vector4d::Zero();   // p0, p1, p2, p3 (normalised coordinates)
};

/// The hole's implicit surface: one CubicRbf up to `local_limit` constraints; beyond, a
/// partition of unity of local CubicRbfs (the box around the constraints and the patch is split
/// at the middle of its longest side until a cell holds at most 600 on-surface points; each
/// cell fits its nearest ≤ 1000 points, at least 150, and is blended with the Wendland weight
/// (1-r)⁴(4r+1), r = distance to the cell centre / (0.75 · cell diagonal), which covers the cell).
class HoleSurface {
 public:
  /// points/normals: on-surface samples and unit normals (zero normal: no offset point);
  /// offset: distance of the normal-offset points, mm; cover: points f must be defined at.
  bool fit(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals,
           double offset, const std::vector<Eigen::Vector3d>& cover, std::size_t local_limit,
           std::string& why);
  /// NaN outside every local patch.
  double value(const Eigen::Vector3d& x) const;
  Eigen::Vector3d gradient(const Eigen::Vector3d& x) const;
  /// value and gradient at once; false where the value is not finite.
  bool evaluate(const Eigen::Vector3d& x, double& f, Eigen::Vector3d& g) const;
  std::size_t constraints() const { return constraints_; }
  std::size_t local_patches() const { return locals_.size(); }

 private:
  struct Local {
    Eigen::Vector3d center;
    double radius = 0;
    CubicRbf rbf;
  };
  CubicRbf global_;
  std::vector<Local> locals_;
  std::size_t constraints_ = 0;
};

struct RbfStats {
  std::size_t constraints = 0;   ///< on-surface + offset centres
  std::size_t local_patches = 0; ///< 0: one global RBF
  double solve_seconds = 0;
  double project_seconds = 0;
  double noise = 0;              ///< surface_noise of the rings around the hole, mm
  bool smoothed = false;         ///< whether the rings were smoothed before the fit
  std::size_t pieces = 1;        ///< smooth pieces fitted separately (creases cross the rings)
};

/// The RBF fill of one hole into `patch` (rim and points set): smoothing of the rim region when
/// it is noisy, split at sharp creases, initial patch, fit, gradient projection.
/// When the projection turns a face of the initial patch over (a fold: the C1 fairing can
/// overshoot where a large hole wraps round an edge), `alternative`, if given, gets the projection
/// of the refined patch faired harmonically instead (it cannot overshoot its rim), to be tried
/// when `patch` fails validation; it stays empty otherwise.
/// \return false with `why` on failure.
bool rbf_fill(const TriangleSoup& soup, const MeshIndex& index, Patch& patch, const HoleShape& shape,
              const FillOptions& options, RbfStats& stats, std::string& why, Patch* alternative = nullptr);

}  // namespace s2c::repair::fill
