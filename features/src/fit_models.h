#pragma once
// The surface models fit_surface.cpp refines with fit::levenberg_marquardt (sphere, cylinder,
// cone), in a header of their own so the tests can check their analytic Jacobians against finite
// differences.
#include <cmath>

#include <Eigen/Dense>

#include "fit_util.h"

namespace s2c::features::fit {

using Eigen::Vector3d;

/// Unit axis tilted from `a` by (d0, d1) in its perpendicular frame `uv`.
inline Vector3d tilt(const Vector3d& a, const Eigen::Matrix<double, 3, 2>& uv, double d0, double d1) {
  return (a + d0 * uv.col(0) + d1 * uv.col(1)).normalized();
}

struct SphereModel {
  static constexpr int kParams = 4;
  using Vec = Eigen::Matrix<double, kParams, 1>;
  const Normalized* s;
  Vector3d c;
  double r;

  int residual_count() const { return s->size(); }
  void residuals(const Vec& d, Eigen::VectorXd& out) const {
    const Vector3d c2 = c + d.head<3>();
    const double r2 = r + d[3];
    for (int i = 0; i < s->size(); ++i) out[i] = s->sw[i] * ((s->p[i] - c2).norm() - r2);
  }
  void jacobian(Jacobian<kParams>& J) const {
    for (int i = 0; i < s->size(); ++i) {
      const Vector3d v = s->p[i] - c;
      const double len = v.norm();
      J.row(i) << (len > 0 ? Vector3d(-s->sw[i] / len * v) : Vector3d::Zero()).transpose(), -s->sw[i];
    }
  }
  void update(const Vec& d) {
    c += d.head<3>();
    r += d[3];
  }
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
  const Normalized* s;
  Vector3d a, p;
  double r, theta;
  Eigen::Matrix<double, 3, 2> uv;

  AxisModel(const Normalized& samples, const Vector3d& axis, const Vector3d& point, double radius, double angle)
      : s(&samples), a(axis.normalized()), p(point), r(radius), theta(angle), uv(perpendicular_frame(a)) {}

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
    for (int i = 0; i < s->size(); ++i) {
      const Vector3d v = s->p[i] - p2;
      const double h = a2.dot(v);
      const double rho = (v - h * a2).norm();
      out[i] = s->sw[i] * ((rho - r2) * ct - h * st);
    }
  }
  /// At delta = 0 the tilts move a along u and v (they are perpendicular to it), the shifts move p
  /// along them; with w = v − h a (length rho, perpendicular to a): ∂h/∂tilt_u = u·v,
  /// ∂rho/∂tilt_u = −h (w·u)/rho, ∂rho/∂shift_u = −(w·u)/rho, and the same for v.
  void jacobian(Jacobian<K>& J) const {
    const double ct = std::cos(theta), st = std::sin(theta);
    const Vector3d u = uv.col(0), t = uv.col(1);
    for (int i = 0; i < s->size(); ++i) {
      const Vector3d v = s->p[i] - p;
      const double h = a.dot(v);
      const Vector3d w = v - h * a;
      const double rho = w.norm();
      // On the axis the distance is not differentiable; any direction is a subgradient.
      const double wu = rho > 0 ? w.dot(u) / rho : 0.0, wt = rho > 0 ? w.dot(t) / rho : 0.0;
      const double sw = s->sw[i];
      J(i, 0) = sw * (-ct * h * wu - st * u.dot(v));
      J(i, 1) = sw * (-ct * h * wt - st * t.dot(v));
      J(i, 2) = -sw * ct * wu;
      J(i, 3) = -sw * ct * wt;
      J(i, 4) = -sw * ct;
      if constexpr (K > 5) J(i, K - 1) = sw * (-(rho - r) * st - h * ct);
    }
  }
  void update(const Vec& d) {
    moved(d, a, p, r, theta);
    uv = perpendicular_frame(a);
  }
};
using CylinderModel = AxisModel<5>;
using ConeModel = AxisModel<6>;

}  // namespace s2c::features::fit
