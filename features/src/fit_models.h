#pragma once
// The surface models fit_surface.cpp refines with fit::levenberg_marquardt (sphere, cylinder,
// cone), in a header of their own so the tests can check their analytic Jacobians against finite
// differences.
#include <cmath>
#include <limits>
#include <memory>

#include <Eigen/Dense>

#include "fit_passes.h"
#include "fit_util.h"

namespace s2c::features::fit {

using Eigen::Vector3d;

/// Unit axis tilted from `a` by (d0, d1) in its perpendicular frame `uv`.
inline Vector3d tilt(const Vector3d& a, const Eigen::Matrix<double, 3, 2>& uv, double d0, double d1) {
  return (a + d0 * uv.col(0) + d1 * uv.col(1)).normalized();
}

/// The samples by coordinate, for the axis models' passes (two samples per instruction). Made once
/// per sample set and shared by the models refined on it: a cone's nine starts each copied them.
struct SampleColumns {
  explicit SampleColumns(const Normalized& samples) {
    const int m = samples.size();
    x.resize(m), y.resize(m), z.resize(m), sw.resize(m);
    for (int i = 0; i < m; ++i) {
      x[i] = samples.p[i].x();
      y[i] = samples.p[i].y();
      z[i] = samples.p[i].z();
      sw[i] = samples.sw[i];
    }
  }
  /// The columns as fit_passes.h takes them.
  ColumnView view() const { return {x.data(), y.data(), z.data(), sw.data(), static_cast<int>(x.size())}; }
  Eigen::ArrayXd x, y, z, sw;
};

/// A model's normal_equations() without AVX: its Jacobian stored in `J`, then summed by
/// fit::normal_equations.
template <class Model>
void normal_equations_of_jacobian(const Model& model, Jacobian<Model::kParams>& J, const Eigen::VectorXd& res,
                                  Eigen::Matrix<double, Model::kParams, Model::kParams>& A,
                                  Eigen::Matrix<double, Model::kParams, 1>& g) {
  J.resize(model.residual_count(), Model::kParams);
  model.jacobian(J);
  normal_equations<Model::kParams>(J.data(), res.data(), model.residual_count(), A, g);
}

/// Sphere through centre c, radius r: residual sw (|sample − c| − r).
class SphereModel {
 public:
  static constexpr int kParams = 4;
  using Vec = Eigen::Matrix<double, kParams, 1>;
  /// `columns`, when given, must be those of *samples.
  SphereModel(const Normalized* samples, const Vector3d& center, double radius,
              std::shared_ptr<const SampleColumns> columns = nullptr)
      : s(samples), c(center), r(radius), columns_(std::move(columns)) {}

  const Normalized* s;
  Vector3d c;
  double r;
  /// The passes four samples at a time (fit_passes.h) where the CPU has AVX; the tests turn them
  /// off to compare.
  bool avx = have_avx_passes();

  int residual_count() const { return s->size(); }
  void residuals(const Vec& d, Eigen::VectorXd& out) const {
    const Vector3d c2 = c + d.head<3>();
    const double r2 = r + d[3];
    if (avx) return sphere_residuals_avx(columns(), c2.data(), r2, out.data());
    for (int i = 0; i < s->size(); ++i) out[i] = s->sw[i] * ((s->p[i] - c2).norm() - r2);
  }
  void jacobian(Jacobian<kParams>& J) const {
    for (int i = 0; i < s->size(); ++i) {
      const Vector3d v = s->p[i] - c;
      const double len = v.norm();
      J.row(i) << (len > 0 ? Vector3d(-s->sw[i] / len * v) : Vector3d::Zero()).transpose(), -s->sw[i];
    }
  }
  /// JᵀJ and Jᵀres at the current parameters, each entry summed over the samples in order.
  void normal_equations(const Eigen::VectorXd& res, Eigen::Matrix<double, kParams, kParams>& A, Vec& g) const {
    if (avx) return sphere_normal_equations_avx(columns(), c.data(), res.data(), A.data(), g.data());
    normal_equations_of_jacobian(*this, jacobian_, res, A, g);
  }
  void update(const Vec& d) {
    c += d.head<3>();
    r += d[3];
  }


 private:
  ColumnView columns() const {
    if (!columns_) columns_ = std::make_shared<const SampleColumns>(*s);
    return columns_->view();
  }

  mutable std::shared_ptr<const SampleColumns> columns_;  // of *s, made on first use
  mutable Jacobian<kParams> jacobian_;                    // the path without AVX
};

/// Cylinder (theta fixed at 0) or cone around the axis through p along a: in the half plane of a
/// sample, (h, rho) = (along the axis from p, away from it), the surface is the line through
/// (0, r) at angle theta from the axis; the residual is the signed distance to that line. Unlike
/// an apex parameterisation this stays regular as the cone tends to a cylinder. Parameters: axis
/// tilt (2), shift of p perpendicular to the axis (2; a shift along the axis changes nothing), r,
/// and for a cone theta.
template <int K>
struct AxisModel {
  static constexpr int kParams = K;
  using Vec = Eigen::Matrix<double, K, 1>;
  using Array = Eigen::ArrayXd;
  const Normalized* s;
  Vector3d a, p;
  double r, theta;
  Eigen::Matrix<double, 3, 2> uv;

  /// On `columns`, which must be those of `samples`.
  AxisModel(const Normalized& samples, std::shared_ptr<const SampleColumns> columns, const Vector3d& axis,
            const Vector3d& point, double radius, double angle)
      : s(&samples), a(axis.normalized()), p(point), r(radius), theta(angle), uv(perpendicular_frame(a)),
        columns_(std::move(columns)) {}
  AxisModel(const Normalized& samples, const Vector3d& axis, const Vector3d& point, double radius, double angle)
      : AxisModel(samples, std::make_shared<const SampleColumns>(samples), axis, point, radius, angle) {}

  void moved(const Vec& d, Vector3d& a2, Vector3d& p2, double& r2, double& t2) const {
    a2 = tilt(a, uv, d[0], d[1]);
    p2 = p + uv * d.template segment<2>(2);
    r2 = r + d[4];
    t2 = K > 5 ? theta + d[K - 1] : theta;
  }
  int residual_count() const { return s->size(); }
  void residuals(const Vec& d, Eigen::VectorXd& out) const {
    Vector3d a2, p2;
    double r2, t2;
    moved(d, a2, p2, r2, t2);
    const double ct = std::cos(t2), st = std::sin(t2);
    if (avx) {
      resize_geometry();
      axis_residuals_avx(columns(), p2.data(), a2.data(), r2, ct, st, geometry_arrays(), out.data());
    } else {
      geometry(a2, p2);
      out.array() = columns_->sw * ((rho_ - r2) * ct - h_ * st);
    }
    last_ = d;
    at_current_ = false;  // they are at the moved parameters until update(d) moves there
  }
  /// JᵀJ and Jᵀres of the Jacobian at the current parameters (see jacobian()), each entry summed
  /// over the samples in order: with AVX straight from the geometry, without storing J.
  void normal_equations(const Eigen::VectorXd& res, Eigen::Matrix<double, K, K>& A, Vec& g) const {
    if (!avx) return normal_equations_of_jacobian(*this, jacobian_, res, A, g);
    if (!at_current_) {
      resize_geometry();
      axis_residuals_avx(columns(), p.data(), a.data(), r, 0.0, 0.0, geometry_arrays(), nullptr);
      at_current_ = true;
    }
    const Vector3d u = uv.col(0), t = uv.col(1);
    axis_normal_equations_avx(K, columns(), geometry_arrays(), p.data(), u.data(), t.data(), r, std::cos(theta),
                              std::sin(theta), res.data(), A.data(), g.data());
  }
  /// At delta = 0 the tilts move a along u and v (they are perpendicular to it), the shifts move p
  /// along them; with w = v − h a (length rho, perpendicular to a): ∂h/∂tilt_u = u·v,
  /// ∂rho/∂tilt_u = −h (w·u)/rho, ∂rho/∂shift_u = −(w·u)/rho, and the same for v.
  void jacobian(Jacobian<K>& J) const {
    // After an accepted step the last residual pass was at exactly these parameters.
    if (!at_current_) geometry(a, p);
    const double ct = std::cos(theta), st = std::sin(theta);
    const Vector3d u = uv.col(0), t = uv.col(1);
    // One pass straight into J's rows, the u and v entries side by side, two per instruction;
    // each lane is the arithmetic of its entry alone, in the order the per-entry array passes
    // had (their eight temporaries cost a malloc each per iteration).
    const Eigen::Array2d ex(u.x(), t.x()), ey(u.y(), t.y()), ez(u.z(), t.z());
    const SampleColumns& c = *columns_;
    for (Eigen::Index i = 0; i < c.x.size(); ++i) {
      const double vx = c.x[i] - p.x(), vy = c.y[i] - p.y(), vz = c.z[i] - p.z();
      const double rho = rho_[i], h = h_[i], sw = c.sw[i];
      // (w·u, w·t)/rho; on the axis the distance is not differentiable, any direction is a
      // subgradient.
      Eigen::Array2d w = ((wx_[i] * ex + wy_[i] * ey) + wz_[i] * ez) / rho;
      if (!(rho > 0)) w.setZero();
      const Eigen::Array2d d = (vx * ex + vy * ey) + vz * ez;  // (u·v, t·v)
      double* row = J.data() + i * K;
      Eigen::Map<Eigen::Array2d> tilts(row), shifts(row + 2);
      tilts = sw * (((-ct) * h) * w - st * d);
      shifts = ((-sw) * ct) * w;
      row[4] = (-sw) * ct;
      if constexpr (K > 5) row[K - 1] = sw * ((-(rho - r)) * st - h * ct);
    }
  }
  void update(const Vec& d) {
    moved(d, a, p, r, theta);
    uv = perpendicular_frame(a);
    at_current_ = d == last_;  // moved() gives the same a and p as that residual pass did
  }

  /// The passes four samples at a time (fit_passes.h) where the CPU has AVX; the tests turn them
  /// off to compare with the two-lane passes below.
  bool avx = have_avx_passes();

 private:
  ColumnView columns() const { return columns_->view(); }
  AxisGeometry geometry_arrays() const { return {h_.data(), wx_.data(), wy_.data(), wz_.data(), rho_.data()}; }
  void resize_geometry() const {
    const Eigen::Index m = columns_->x.size();
    h_.resize(m), wx_.resize(m), wy_.resize(m), wz_.resize(m), rho_.resize(m);
  }
  /// Per sample, for the axis through q along b: h = b·v and w = v − h b with v = sample − q,
  /// rho = |w| (Eigen's 3-vector dot product and norm: (x + y) + z).
  void geometry(const Vector3d& b, const Vector3d& q) const {
    const SampleColumns& c = *columns_;
    const auto vx = c.x - q.x(), vy = c.y - q.y(), vz = c.z - q.z();
    h_ = (vx * b.x() + vy * b.y()) + vz * b.z();
    wx_ = vx - h_ * b.x();
    wy_ = vy - h_ * b.y();
    wz_ = vz - h_ * b.z();
    rho_ = ((wx_.square() + wy_.square()) + wz_.square()).sqrt();
  }

  // The samples by coordinate: the passes above run two samples per instruction (each lane does
  // the arithmetic the per-sample loop did, in the same order, so the values are equal).
  std::shared_ptr<const SampleColumns> columns_;
  // The last residual pass's geometry, reused by the Jacobian at the parameters it was for.
  mutable Array h_, wx_, wy_, wz_, rho_;
  mutable Jacobian<K> jacobian_;  // the two-lane path's, for normal_equations()
  mutable Vec last_ = Vec::Constant(std::numeric_limits<double>::quiet_NaN());
  mutable bool at_current_ = false;
};
using CylinderModel = AxisModel<5>;
using ConeModel = AxisModel<6>;

}  // namespace s2c::features::fit
