// RBF hole filling after ../shared/papers/rbf-hole-filling.txt (see rbf.h).
#include "fill/rbf.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <limits>
#include <mutex>
#include <numeric>
#include <unordered_map>

#include <Eigen/Householder>
#include <Eigen/LU>
#include <Eigen/QR>

#include <f77blas.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "fill/liepa.h"
#include "fill/local_ids.h"
#include "fill/patch_check.h"
#include "fill/rim_surfaces.h"
#include "s2c/core/clock.h"

namespace s2c::repair::fill {
namespace {

/// OpenBLAS runs one thread per call here: the parallelism is TBB's (the holes of a call are
/// planned concurrently), and a threaded call would also sum in another order than a single
/// one, making the fill depend on the threads. The pthread build of OpenBLAS is the one with
/// locks, so concurrent calls are safe. Called before every BLAS/LAPACK use.
void single_threaded_blas() {
  static std::once_flag once;
  std::call_once(once, [] {
    int one = 1;
    openblas_set_num_threads_(&one);
  });
}

/// In-place Cholesky factor (lower triangle) of the SPD matrix K by LAPACK's dpotrf from
/// OpenBLAS: its kernels are picked at run time for the CPU (AVX2 / AVX-512 where present, while
/// the project itself must not be built with -march=native), about 3× Eigen's SSE2 LLT at the
/// hole sizes (N 130–1000). Only the lower triangle is read and meaningful afterwards. False
/// when K is not positive definite.
bool cholesky_in_place(Eigen::Ref<Eigen::MatrixXd> K) {
  single_threaded_blas();
  char lower = 'L';
  blasint n = static_cast<blasint>(K.rows()), lda = static_cast<blasint>(K.outerStride()), info = 0;
  BLASFUNC(dpotrf)(&lower, &n, K.data(), &lda, &info);
  return info == 0;
}

}  // namespace

bool CubicRbf::fit(const std::vector<Eigen::Vector3d>& centers, const std::vector<double>& values, RbfSolver solver,
                   double linear_tolerance) {
  const int n = static_cast<int>(centers.size());
  if (n < 5 || values.size() != centers.size()) return false;
  // Centre and scale to a unit box: keeps Φ (∝ r³) and the linear block comparable.
  Eigen::Vector3d lo = centers[0], hi = centers[0];
  for (const auto& c : centers) {
    lo = lo.cwiseMin(c);
    hi = hi.cwiseMax(c);
  }
  shift_ = 0.5 * (lo + hi);
  const double extent = (hi - lo).maxCoeff();
  if (!(extent > 0)) return false;
  scale_ = 1.0 / extent;
  cx_.resize(n);
  cy_.resize(n);
  cz_.resize(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d c = (centers[i] - shift_) * scale_;
    cx_[i] = c.x();
    cy_[i] = c.y();
    cz_[i] = c.z();
  }
  const Eigen::Map<const Eigen::VectorXd> h(values.data(), n);
  Eigen::MatrixXd P(n, 4);
  P.col(0).setOnes();
  P.col(1) = cx_.matrix();
  P.col(2) = cy_.matrix();
  P.col(3) = cz_.matrix();
  if (linear_tolerance > 0 && fit_linear(P, h, linear_tolerance)) return true;

  // Φ's lower triangle by columns, each a vectorised pass over coordinate arrays (the n²/2
  // square roots dominate the build); columns in parallel only where it pays.
  Eigen::MatrixXd phi(n, n);
  const Eigen::ArrayXd &X = cx_, &Y = cy_, &Z = cz_;
  const auto column = [&](int j) {
    const int m = n - j;
    auto out = phi.col(j).tail(m).array();  // r computed in place: no temporary per column
    out = ((X.tail(m) - X[j]).square() + (Y.tail(m) - Y[j]).square() + (Z.tail(m) - Z[j]).square()).sqrt();
    out = out.cube();
  };
  if (n < 512) {
    for (int j = 0; j < n; ++j) column(j);
  } else {
    tbb::parallel_for(tbb::blocked_range<int>(0, n, 32), [&](const auto& range) {
      for (int j = range.begin(); j != range.end(); ++j) column(j);
    });
  }

  if (solver == RbfSolver::lu) {
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n + 4, n + 4);
    A.topLeftCorner(n, n) = phi.selfadjointView<Eigen::Lower>();
    A.topRightCorner(n, 4) = P;
    A.bottomLeftCorner(4, n) = P.transpose();
    Eigen::VectorXd b = Eigen::VectorXd::Zero(n + 4);
    b.head(n) = h;
    const Eigen::PartialPivLU<Eigen::MatrixXd> lu(A);
    const Eigen::VectorXd x = lu.solve(b);
    // PartialPivLU does not report singularity: check the residual instead.
    if (!x.allFinite() || (A * x - b).norm() > 1e-8 * (b.norm() + 1)) return false;
    w_ = x.head(n).array();
    p_ = x.tail(4);
    return true;
  }

  // Null-space method (rbf.h), on Φ's lower triangle only. P = Q R by 4 Householder
  // reflectors, Q = H0 H1 H2 H3 = I − V T Vᵀ in compact form (V unit lower N×4, T upper 4×4).
  // Then Qᵀ Φ Q = Φ − U Vᵀ − V Uᵀ with W = Φ V and U = W T − ½ V Tᵀ (Vᵀ W) T: one symmetric
  // rank-8 update, two passes over Φ instead of 16 for the reflectors one at a time.
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(P);
  const Eigen::Matrix4d R = qr.matrixQR().topLeftCorner(4, 4).triangularView<Eigen::Upper>();
  if (std::abs(R.diagonal().prod()) < 1e-14) return false;  // centres in a plane: linear part undetermined
  const Eigen::MatrixXd V = qr.matrixQR().triangularView<Eigen::UnitLower>();
  Eigen::Matrix4d T = Eigen::Matrix4d::Zero();
  for (int i = 0; i < 4; ++i) {
    const double tau = qr.hCoeffs()[i];
    T(i, i) = tau;
    if (i > 0)
      T.col(i).head(i) = -tau * (T.topLeftCorner(i, i) * (V.leftCols(i).transpose() * V.col(i)));  // T is upper
  }
  // W = Φ V and the update by BLAS (dsymm, dsyr2k): OpenBLAS's kernels are picked at run time
  // (AVX2 / AVX-512), Eigen's are SSE2 here.
  single_threaded_blas();
  Eigen::MatrixXd W(n, 4);
  {
    char left = 'L', lower = 'L';
    blasint nn = n, k = 4, ld = n;
    double one = 1, zero = 0;
    BLASFUNC(dsymm)(&left, &lower, &nn, &k, &one, phi.data(), &ld, const_cast<double*>(V.data()), &ld, &zero,
                    W.data(), &ld);
  }
  Eigen::MatrixXd U = W * T - 0.5 * V * (T.transpose() * (V.transpose() * W) * T);
  {
    char lower = 'L', plain = 'N';
    blasint nn = n, k = 4, ld = n;
    double minus_one = -1, one = 1;
    BLASFUNC(dsyr2k)(&lower, &plain, &nn, &k, &minus_one, U.data(), &ld, const_cast<double*>(V.data()), &ld, &one,
                     phi.data(), &ld);
  }
  const auto Q = qr.householderQ();
  Eigen::VectorXd qh = h;
  qh.applyOnTheLeft(Q.adjoint());
  Eigen::Ref<Eigen::MatrixXd> K = phi.bottomRightCorner(n - 4, n - 4);
  if (!cholesky_in_place(K)) return false;  // in place: the other blocks stay intact
  Eigen::VectorXd y = qh.tail(n - 4);
  K.triangularView<Eigen::Lower>().solveInPlace(y);
  K.triangularView<Eigen::Lower>().adjoint().solveInPlace(y);
  Eigen::VectorXd z(n);
  z << Eigen::Vector4d::Zero(), y;
  z.applyOnTheLeft(Q);
  w_ = z.array();
  // P p = h - Φ w  ⇒  R p = (Qᵀ h)_{0..3} - (Qᵀ Φ Q)_{0..3, 4..} y, that block read from the
  // lower triangle as its transpose.
  const Eigen::Vector4d rhs = qh.head(4) - phi.bottomLeftCorner(n - 4, 4).transpose() * y;
  p_ = R.triangularView<Eigen::Upper>().solve(rhs);
  return w_.allFinite() && p_.allFinite();
}

bool CubicRbf::fit_linear(const Eigen::MatrixXd& P, const Eigen::Ref<const Eigen::VectorXd>& h, double tolerance) {
  // Least squares over the 4 polynomial columns (O(N)); accepted only when every value is met.
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(P);
  if (qr.rank() < 4) return false;  // centres in a plane: the linear part is undetermined
  const Eigen::Vector4d p = qr.solve(h);
  if (!p.allFinite() || (P * p - h).cwiseAbs().maxCoeff() > tolerance) return false;
  p_ = p;
  cx_.resize(0);  // no radial term: evaluate is the polynomial alone
  cy_.resize(0);
  cz_.resize(0);
  w_.resize(0);
  return true;
}

namespace {

// value and gradient alone, from a surface's evaluate (which computes both in one pass).
template <class Surface>
double value_of(const Surface& s, const Eigen::Vector3d& x) {
  double f;
  Eigen::Vector3d g;
  s.evaluate(x, f, g);
  return f;
}
template <class Surface>
Eigen::Vector3d gradient_of(const Surface& s, const Eigen::Vector3d& x) {
  double f;
  Eigen::Vector3d g;
  s.evaluate(x, f, g);
  return g;
}

}  // namespace

void CubicRbf::evaluate(const Eigen::Vector3d& x, double& f, Eigen::Vector3d& g) const {
  const Eigen::Vector3d y = (x - shift_) * scale_;
  // Blocks of kLanes centres with fixed-size arrays: vectorised square roots, no allocation,
  // one pass for f = Σ wⱼ rⱼ³ and ∇f = Σ 3 wⱼ rⱼ dⱼ (∇|d|³ = 3|d| d).
  constexpr int kLanes = 8;
  using Lanes = Eigen::Array<double, kLanes, 1>;
  Lanes sf = Lanes::Zero(), sx = Lanes::Zero(), sy = Lanes::Zero(), sz = Lanes::Zero();
  const Eigen::Index n = cx_.size(), full = n - n % kLanes;
  for (Eigen::Index j = 0; j < full; j += kLanes) {
    const Lanes dx = y.x() - cx_.segment<kLanes>(j), dy = y.y() - cy_.segment<kLanes>(j),
                dz = y.z() - cz_.segment<kLanes>(j);
    const Lanes r = (dx * dx + dy * dy + dz * dz).sqrt();
    const Lanes wr = w_.segment<kLanes>(j) * r;
    sf += wr * r * r;
    sx += wr * dx;
    sy += wr * dy;
    sz += wr * dz;
  }
  double tf = sf.sum(), tx = sx.sum(), ty = sy.sum(), tz = sz.sum();
  for (Eigen::Index j = full; j < n; ++j) {
    const double dx = y.x() - cx_[j], dy = y.y() - cy_[j], dz = y.z() - cz_[j];
    const double r = std::sqrt(dx * dx + dy * dy + dz * dz), wr = w_[j] * r;
    tf += wr * r * r;
    tx += wr * dx;
    ty += wr * dy;
    tz += wr * dz;
  }
  f = p_[0] + p_.tail(3).dot(y) + tf;
  g = scale_ * (p_.tail<3>() + 3.0 * Eigen::Vector3d(tx, ty, tz));  // chain rule through the normalisation
}

double CubicRbf::value(const Eigen::Vector3d& x) const { return value_of(*this, x); }
Eigen::Vector3d CubicRbf::gradient(const Eigen::Vector3d& x) const { return gradient_of(*this, x); }

// ---------------------------------------------------------------------------------------------

namespace {

double wendland(double r) { return r >= 1 ? 0.0 : std::pow(1 - r, 4) * (4 * r + 1); }
double wendland_derivative(double r) { return r >= 1 ? 0.0 : -20.0 * r * std::pow(1 - r, 3); }

bool fit_samples(CubicRbf& rbf, const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals,
                 const std::vector<int>& which, double offset) {
  std::vector<Eigen::Vector3d> c;
  std::vector<double> v;
  c.reserve(2 * which.size());
  v.reserve(2 * which.size());
  for (int i : which) {
    c.push_back(points[i]);
    v.push_back(0);
    if (normals[i].squaredNorm() > 0) {
      c.push_back(points[i] + offset * normals[i]);
      v.push_back(offset);
    }
  }
  // Linear within a millionth of the offset (under a thousandth of what the projection
  // resolves): a flat piece, exactly what the full solve would return up to rounding.
  const double linear = 1e-6 * offset;
  return rbf.fit(c, v, RbfSolver::nullspace_llt, linear) || rbf.fit(c, v, RbfSolver::lu);
}

}  // namespace

bool HoleSurface::fit(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals,
                      double offset, const std::vector<Eigen::Vector3d>& cover, std::size_t local_limit,
                      std::string& why) {
  constraints_ = points.size();
  for (const auto& n : normals) constraints_ += n.squaredNorm() > 0;
  locals_.clear();
  std::vector<int> all(points.size());
  std::iota(all.begin(), all.end(), 0);
  if (constraints_ <= local_limit) {
    if (!fit_samples(global_, points, normals, all, offset)) {
      why = "RBF system is singular";
      return false;
    }
    return true;
  }
  // Partition of unity over a bisection of the box around constraints and patch (rbf.h).
  constexpr std::size_t kLeaf = 600, kMin = 150, kMax = 1000;
  Eigen::Vector3d lo = points[0], hi = points[0];
  for (const auto* set : {&points, &cover})
    for (const auto& p : *set) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  struct Cell {
    Eigen::Vector3d lo, hi;
    std::vector<int> pts;
    bool covers = false;
  };
  std::vector<Cell> stack{{lo, hi, all, !cover.empty()}};
  while (!stack.empty()) {
    Cell cell = std::move(stack.back());
    stack.pop_back();
    if (cell.pts.empty() && !cell.covers) continue;
    if (cell.pts.size() > kLeaf) {
      int axis;
      (cell.hi - cell.lo).maxCoeff(&axis);
      const double mid = 0.5 * (cell.lo[axis] + cell.hi[axis]);
      Cell a{cell.lo, cell.hi, {}, false}, b{cell.lo, cell.hi, {}, false};
      a.hi[axis] = mid;
      b.lo[axis] = mid;
      for (int i : cell.pts) (points[i][axis] <= mid ? a : b).pts.push_back(i);
      for (const auto& q : cover) {
        if ((q.array() >= a.lo.array()).all() && (q.array() <= a.hi.array()).all()) a.covers = true;
        if ((q.array() >= b.lo.array()).all() && (q.array() <= b.hi.array()).all()) b.covers = true;
      }
      stack.push_back(std::move(a));
      stack.push_back(std::move(b));
      continue;
    }
    Local local;
    local.center = 0.5 * (cell.lo + cell.hi);
    local.radius = 0.75 * (cell.hi - cell.lo).norm();
    if (!(local.radius > 0)) continue;
    // Nearest points to the centre: everything in the support, at least kMin, at most kMax.
    std::vector<std::pair<double, int>> by_distance;
    for (int i : all) by_distance.push_back({(points[i] - local.center).norm(), i});
    std::sort(by_distance.begin(), by_distance.end());
    std::vector<int> chosen;
    for (const auto& [d, i] : by_distance) {
      if (chosen.size() >= kMax || (chosen.size() >= kMin && d > local.radius)) break;
      chosen.push_back(i);
    }
    if (!fit_samples(local.rbf, points, normals, chosen, offset)) {
      why = "local RBF system is singular";
      return false;
    }
    locals_.push_back(std::move(local));
  }
  if (locals_.empty()) {
    why = "no local RBF patch";
    return false;
  }
  return true;
}

bool HoleSurface::evaluate(const Eigen::Vector3d& x, double& f, Eigen::Vector3d& g) const {
  if (locals_.empty()) {
    global_.evaluate(x, f, g);
    return std::isfinite(f);
  }
  // f = Σ wᵢ fᵢ / Σ wᵢ  ⇒  ∇f = (Σ (∇wᵢ fᵢ + wᵢ ∇fᵢ) - f Σ ∇wᵢ) / Σ wᵢ; one pass over each
  // local RBF gives its fᵢ and ∇fᵢ.
  double sw = 0, swf = 0;
  Eigen::Vector3d sgw = Eigen::Vector3d::Zero(), sgwf = Eigen::Vector3d::Zero();
  for (const auto& l : locals_) {
    const Eigen::Vector3d d = x - l.center;
    const double dist = d.norm(), r = dist / l.radius;
    const double w = wendland(r);
    if (w <= 0) continue;
    const Eigen::Vector3d gw = dist > 0 ? Eigen::Vector3d(wendland_derivative(r) / (l.radius * dist) * d) : Eigen::Vector3d::Zero();
    double fi;
    Eigen::Vector3d gi;
    l.rbf.evaluate(x, fi, gi);
    sw += w;
    swf += w * fi;
    sgw += gw;
    sgwf += gw * fi + w * gi;
  }
  if (!(sw > 0)) {
    f = std::numeric_limits<double>::quiet_NaN();
    g = Eigen::Vector3d::Constant(f);
    return false;
  }
  f = swf / sw;
  g = (sgwf - f * sgw) / sw;
  return std::isfinite(f);
}

double HoleSurface::value(const Eigen::Vector3d& x) const { return value_of(*this, x); }
Eigen::Vector3d HoleSurface::gradient(const Eigen::Vector3d& x) const { return gradient_of(*this, x); }

// ---------------------------------------------------------------------------------------------

namespace {

// The implicit surfaces of the smooth pieces around a hole, combined: one piece is its own RBF;
// pieces meeting at convex creases bound the intersection of their insides (f = max fᵢ), at
// concave ones the union (f = min fᵢ). The gradient is the active piece's.
struct PieceSurfaces {
  std::vector<HoleSurface> surfaces;
  bool convex = true;
  bool evaluate(const Eigen::Vector3d& x, double& f, Eigen::Vector3d& g) const {
    bool any = false;
    for (const auto& s : surfaces) {
      double v;
      Eigen::Vector3d gv;
      if (!s.evaluate(x, v, gv)) continue;
      if (!any || (convex ? v > f : v < f)) {
        f = v;
        g = gv;
        any = true;
      }
    }
    return any;
  }
};

// Whether fitting `split` needs the patch's points: a piece with more centres than the local
// limit is fitted as a partition of unity whose cells must cover the patch (HoleSurface::fit).
bool fit_needs_cover(const CreaseSplit& split, std::size_t local_limit) {
  for (const SmoothPiece& piece : split.pieces) {
    std::size_t centres = piece.vertices.size();
    for (const auto& n : piece.normals) centres += n.squaredNorm() > 0;
    if (centres > local_limit) return true;  // an upper bound (coincident vertices count once)
  }
  return false;
}

// Fits one RBF per piece: its on-surface points (value 0) and their normal offsets (value d).
// The pieces' fits are independent: in parallel (a hole across a crease has 2–4).
bool fit_pieces(const CreaseSplit& split, const Position& at, const std::vector<Eigen::Vector3d>& cover,
                const HoleShape& shape, const FillOptions& options, PieceSurfaces& combined, RbfStats& stats,
                std::string& why) {
  const auto t0 = std::chrono::steady_clock::now();
  const std::size_t count = split.pieces.size();
  combined = PieceSurfaces{};
  combined.convex = split.convex;
  combined.surfaces.resize(count);
  std::vector<std::string> whys(count);
  std::vector<char> ok(count, 0);
  const auto fit_one = [&](std::size_t k) {
    const SmoothPiece& piece = split.pieces[k];
    // Different vertices at one position give one constraint (the first of them): found by
    // sorting the positions, no set of nodes.
    const std::size_t m = piece.vertices.size();
    std::vector<std::size_t> order(m);
    std::iota(order.begin(), order.end(), 0);
    const auto key = [&](std::size_t i) {
      const Eigen::Vector3d& p = at(piece.vertices[i]);
      return std::array<double, 3>{p.x(), p.y(), p.z()};
    };
    std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return key(a) < key(b); });
    std::vector<char> repeated(m, 0);
    for (std::size_t j = 1; j < m; ++j) repeated[order[j]] = key(order[j]) == key(order[j - 1]);
    std::vector<Eigen::Vector3d> points, normals;
    for (std::size_t i = 0; i < m; ++i) {
      if (repeated[i]) continue;
      points.push_back(at(piece.vertices[i]));
      normals.push_back(piece.normals[i]);
    }
    ok[k] = combined.surfaces[k].fit(points, normals, options.rbf_offset * shape.edge, cover, options.rbf_local_limit,
                                     whys[k]);
  };
  // Largest first (the solve is cubic in the centres): the calling thread takes the front of
  // the range and a thread that comes free steals from the back, so the other core, once done
  // with its half of the hole (the initial patch), picks up the small pieces instead of leaving
  // the largest to start last. Each piece writes its own slot: the order changes no result.
  std::vector<std::size_t> order(count);
  std::iota(order.begin(), order.end(), std::size_t{0});
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return split.pieces[a].vertices.size() > split.pieces[b].vertices.size();
  });
  if (count > 1)
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1), [&](const auto& range) {
      for (std::size_t k = range.begin(); k != range.end(); ++k) fit_one(order[k]);
    });
  else if (count == 1)
    fit_one(0);
  stats.constraints = 0;
  stats.local_patches = 0;
  for (std::size_t k = 0; k < count; ++k) {
    if (!ok[k]) {
      why = whys[k];
      return false;
    }
    stats.constraints += combined.surfaces[k].constraints();
    stats.local_patches += combined.surfaces[k].local_patches();
  }
  stats.solve_seconds = seconds_since(t0);
  return true;
}

// Projects the patch's new vertices onto the combined surface (eq. 12) until a step is below
// the tolerance.
bool project(const PieceSurfaces& combined, const HoleShape& shape, const FillOptions& options, Patch& patch,
             RbfStats& stats, std::string& why) {
  const auto t1 = std::chrono::steady_clock::now();
  const double tol = options.projection_tolerance * shape.edge;
  std::vector<Eigen::Vector3d> moved(patch.points.begin() + patch.rim_size(), patch.points.end());
  for (auto& x : moved) {
    const Eigen::Vector3d start = x;
    bool converged = false;
    for (int it = 0; it < 50 && !converged; ++it) {
      double f = 0;
      Eigen::Vector3d g;
      if (!combined.evaluate(x, f, g)) break;
      const double gg = g.squaredNorm();
      if (!std::isfinite(f) || !(gg > 0) || !std::isfinite(gg)) break;
      const Eigen::Vector3d step = (f / gg) * g;
      x -= step;
      converged = step.norm() < tol;
    }
    if (!converged || (x - start).norm() > shape.diameter) {
      why = "gradient projection did not converge";
      return false;
    }
  }
  std::copy(moved.begin(), moved.end(), patch.points.begin() + patch.rim_size());
  stats.project_seconds = seconds_since(t1);
  return true;
}

// The ring of every vertex reached by the search around a hole: a vertex table (a hole's rings
// hold a few hundred vertices; no allocation per vertex, no sort per ring) and the list of
// (vertex, ring) sorted when it is read.
class Rings {
 public:
  /// Gives ring r to the vertices of `candidates` not reached yet; returns them.
  std::vector<int> add(const std::vector<int>& candidates, int r) {
    std::vector<int> fresh;
    for (int v : candidates)
      if (table_.insert(v, r)) {
        fresh.push_back(v);
        list_.emplace_back(v, r);
        sorted_ = false;
      }
    return fresh;
  }
  /// v's ring, -1 when not reached.
  int of(int v) const { return table_.find(v); }
  /// (vertex, ring), ascending by vertex.
  const std::vector<std::pair<int, int>>& all() {
    if (!sorted_) std::sort(list_.begin(), list_.end());
    sorted_ = true;
    return list_;
  }

 private:
  VertexTable table_{256};
  std::vector<std::pair<int, int>> list_;
  bool sorted_ = true;
};

// Whether moving the patch's points from `before` to where they are in `after` turns some face
// over (its normal reverses).
bool folds(const std::vector<Eigen::Vector3d>& before, const Patch& after) {
  for (const auto& t : after.faces) {
    const auto normal = [&](const std::vector<Eigen::Vector3d>& p) {
      return Eigen::Vector3d((p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]));
    };
    if (normal(before).dot(normal(after.points)) < 0) return true;
  }
  return false;
}

}  // namespace

bool rbf_fill(const TriangleSoup& soup, const MeshIndex& index, Patch& patch, const HoleShape& shape,
              const FillOptions& options, RbfStats& stats, std::string& why, Patch* alternative) {
  // Two independent halves, run side by side: the implicit surface from the mesh around the hole
  // (steps 1–3 and its fit) and the initial patch (step 4). Both only read the soup.
  Rings ring;                         // vertex → ring
  std::vector<int> samples;           // constraint vertices (rings 0..3), sorted
  std::unordered_map<int, Eigen::Vector3d> pos;  // smoothed positions
  const Position at{soup.vertices, pos};
  CreaseSplit split;
  // On clean rings (not smoothed) the on-surface points of rings 0..3 pin the surface and the
  // offsets only set the implicit function's sign and scale: rings 0 and 2 carry them, a quarter
  // fewer centres and a 2.4× cheaper solve at the same deviation (bench/README.md, hole filling).
  // Noisy rings keep the paper's offset at every vertex: there the offsets also average noise.
  const auto thin_offsets = [&](CreaseSplit& s) {
    if (stats.smoothed) return;
    for (SmoothPiece& piece : s.pieces)
      for (std::size_t i = 0; i < piece.vertices.size(); ++i)
        if (ring.of(piece.vertices[i]) % 2) piece.normals[i].setZero();
  };
  PieceSurfaces combined;
  enum class Fit { later, done, failed } fit = Fit::later;
  std::string fit_why, patch_why;
  const auto surface_side = [&] {
    // 1. Rings around the hole by breadth-first search over mesh edges (ring 0 = the rim), as far
    //    as the constraints need; on to the smoothing rings only if the surface is smoothed.
    std::vector<int> frontier = ring.add(patch.rim, 0);
    int reached = 0;
    // A ring is also a distance: the search goes on only from vertices within kRingReach · r rim
    // edges of the rim. On even meshes that stops nothing; through a fan's centre (a cylinder's
    // cap, a cone's apex) one ring would otherwise jump to the whole far side: hundreds of
    // centres (the solve is N³) that say nothing about the surface over the hole. The far vertex
    // itself stays (its faces carry the fan's surface into the crease split).
    constexpr double kRingReach = 2.0;
    const auto near_rim = [&](int u, int r) {
      const double reach = kRingReach * r * shape.edge, reach2 = reach * reach;
      const Eigen::Vector3d& p = soup.vertices[u];
      for (int g : patch.rim)
        if ((soup.vertices[g] - p).squaredNorm() <= reach2) return true;
      return false;
    };
    const auto grow_to = [&](int rings) {
      std::vector<int> reachable;
      for (; reached < rings && !frontier.empty(); ++reached) {
        reachable.clear();
        for (int v : frontier)  // (the ring a vertex gets does not depend on the visiting order)
          index.for_each_face_of(v, [&](int f) {
            for (int u : soup.faces[static_cast<std::size_t>(f)]) reachable.push_back(u);
          });
        frontier.clear();
        for (int u : ring.add(reachable, reached + 1))
          if (near_rim(u, reached + 1)) frontier.push_back(u);
      }
    };
    grow_to(std::max(options.rbf_constraint_rings, 0));
    std::vector<int> inner;  // constraint vertices off the rim
    for (const auto& [v, r] : ring.all())  // ascending by vertex
      if (r <= options.rbf_constraint_rings) {
        samples.push_back(v);
        if (r >= 1) inner.push_back(v);
      }
    // 2. Laplacian smoothing (eq. 4, uniform weights) of rings 1..5 on a copy, when the surface
    //    there is noisy (on clean input it would only move correct vertices); the rim stays
    //    where it is because the patch must meet it exactly. Taubin's μ step after each λ step
    //    removes the shrinkage that would otherwise pull the fitted surface off a clean one.
    split = split_at_creases(soup, index, samples, at, options.rbf_crease_angle, 8);
    // (Sharp edges everywhere are noise themselves: then no vertex is left out.)
    const bool few_creases = 2 * split.crease_vertices.size() < inner.size();
    stats.noise = surface_noise(soup, index, inner, at, few_creases ? split.crease_vertices : std::vector<int>{});
    stats.smoothed = options.rbf_smoothing_passes > 0 && stats.noise > options.rbf_noise_threshold * shape.edge;
    if (stats.smoothed) {
      grow_to(std::max(options.rbf_smoothing_rings, 0));
      for (const auto& [v, r] : ring.all()) pos[v] = soup.vertices[v];
      std::vector<int> movable;  // ascending
      for (const auto& [v, r] : ring.all())
        if (r >= 1 && r <= options.rbf_smoothing_rings) movable.push_back(v);
      std::unordered_map<int, std::vector<int>> nbrs;
      for (int v : movable) nbrs[v] = index.neighbours(v);
      for (int pass = 0; pass < options.rbf_smoothing_passes; ++pass)
        for (const double step : {0.5, -0.53}) {
          std::vector<Eigen::Vector3d> next(movable.size());
          for (std::size_t i = 0; i < movable.size(); ++i) {
            const auto& list = nbrs[movable[i]];
            Eigen::Vector3d mean = Eigen::Vector3d::Zero();
            for (int u : list) mean += at(u);
            const Eigen::Vector3d& x = at(movable[i]);
            next[i] = list.empty() ? x : Eigen::Vector3d(x + step * (mean / double(list.size()) - x));
          }
          for (std::size_t i = 0; i < movable.size(); ++i) pos[movable[i]] = next[i];
        }
    }
    // 3. Constraints: the vertices of rings 0..3 (value 0) and their normal offsets (value d),
    //    normals area-weighted from the (smoothed) positions, oriented like the mesh; one set per
    //    smooth piece when sharp creases cross the rings (rim_surfaces.h).
    if (stats.smoothed) split = split_at_creases(soup, index, samples, at, options.rbf_crease_angle, 8);
    stats.pieces = split.pieces.size();
    thin_offsets(split);
    // 5. The implicit surface of each piece, unless a partition of unity must cover the patch.
    if (!fit_needs_cover(split, options.rbf_local_limit))
      fit = fit_pieces(split, at, {}, shape, options, combined, stats, fit_why) ? Fit::done : Fit::failed;
  };
  // 4. Initial patch: minimum-weight triangulation refined to the target density (the paper's
  //    barycentric subdivision, done with Liepa's density rule so it works for non-convex
  //    holes too), faired with a C1 join so that the projection starts near the surface.
  bool patch_built = false;
  Patch refined;  // before fairing, for the alternative start
  const auto patch_side = [&] {
    patch_built = triangulate(soup, index, patch, patch_why) &&
                  refine(index, patch, options.max_patch_vertices, patch_why);
    if (!patch_built) return;
    if (alternative) refined = patch;
    // Ahead of the fit: the patch's topology (final once refined: fairing moves vertices only,
    // so the check runs beside it, on the core the surface half frees when it finishes first)
    // and, where the index scans the whole mesh for a query, the faces near where the patch can
    // end up (projection moves a vertex at most shape.diameter; a quarter of it is plenty in
    // practice, and check_patch scans again when the patch left the box).
    bool topology_ok = false;
    tbb::parallel_invoke([&] { topology_ok = check_patch_topology(soup, index, patch).empty(); },
                         [&] { patch_built = fair(soup, index, patch, true, patch_why); });
    patch.topology_ok = topology_ok;
    if (!patch_built) return;
    if (index.scanning()) {
      Eigen::Vector3d lo = patch.points[0], hi = lo;
      for (const auto& q : patch.points) {
        lo = lo.cwiseMin(q);
        hi = hi.cwiseMax(q);
      }
      const Eigen::Vector3d margin = Eigen::Vector3d::Constant(0.25 * shape.diameter);
      patch.near_lo = lo - margin;
      patch.near_hi = hi + margin;
      index.faces_near(patch.near_lo, patch.near_hi, patch.near_faces);
    }
  };
  tbb::parallel_invoke(surface_side, patch_side);
  if (!patch_built) {
    why = patch_why;
    return false;
  }
  const std::vector<Eigen::Vector3d> cover(patch.points.begin() + patch.rim_size(), patch.points.end());
  if (fit == Fit::later)
    fit = fit_pieces(split, at, cover, shape, options, combined, stats, fit_why) ? Fit::done : Fit::failed;
  // 6. The gradient projection; one surface over the creases when the pieces' combination does
  //    not fit or does not converge.
  const std::vector<Eigen::Vector3d> faired = alternative ? patch.points : std::vector<Eigen::Vector3d>{};
  if (fit == Fit::done && project(combined, shape, options, patch, stats, why)) {
    // A face turned over against the faired start or the flat refined patch: the C1 fairing
    // overshot (a large hole round an edge) and the patch likely intersects itself; validation
    // decides, with the harmonic start's projection as the next candidate.
    if (alternative && (folds(faired, patch) || folds(refined.points, patch))) {
      std::string ignored;
      Patch other = refined;
      if (fair(soup, index, other, false, ignored) && project(combined, shape, options, other, stats, ignored))
        *alternative = std::move(other);
    }
    return true;
  }
  if (fit == Fit::failed) why = fit_why;
  if (split.pieces.size() < 2) return false;
  split = one_piece(soup, index, samples, at);
  thin_offsets(split);
  stats.pieces = 1;
  return fit_pieces(split, at, cover, shape, options, combined, stats, why) &&
         project(combined, shape, options, patch, stats, why);
}

}  // namespace s2c::repair::fill
