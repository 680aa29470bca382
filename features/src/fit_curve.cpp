// Curve fits of ordered polyline samples: line (PCA) and circle / arc (PCA plane, algebraic circle,
// then Levenberg–Marquardt on the 3D distance to the circle).
#include <cmath>
#include <vector>

#include "fit_util.h"

namespace s2c::features {
namespace {

using Eigen::Vector3d;

/// A circle in space: centre c, unit normal n (tilted in its perpendicular frame), radius r. Two
/// residuals per sample, the offsets from the circle's plane and from its radius, whose squares
/// sum to the squared distance to the circle.
struct CircleModel {
  static constexpr int kParams = 6;
  using Vec = Eigen::Matrix<double, kParams, 1>;
  const fit::Normalized* s;
  Vector3d c, n;
  double r;
  Eigen::Matrix<double, 3, 2> uv;

  CircleModel(const fit::Normalized& samples, const Vector3d& center, const Vector3d& normal, double radius)
      : s(&samples), c(center), n(normal), r(radius), uv(fit::perpendicular_frame(normal)) {}

  void moved(const Vec& d, Vector3d& c2, Vector3d& n2, double& r2) const {
    c2 = c + d.head<3>();
    n2 = (n + d[3] * uv.col(0) + d[4] * uv.col(1)).normalized();
    r2 = r + d[5];
  }
  int residual_count() const { return 2 * s->size(); }
  void residuals(const Vec& d, Eigen::VectorXd& out) const {
    Vector3d c2, n2;
    double r2;
    moved(d, c2, n2, r2);
    for (int i = 0; i < s->size(); ++i) {
      const Vector3d v = s->p[i] - c2;
      const double h = n2.dot(v);
      out[2 * i] = s->sw[i] * h;
      out[2 * i + 1] = s->sw[i] * ((v - h * n2).norm() - r2);
    }
  }
  void update(const Vec& d) {
    moved(d, c, n, r);
    uv = fit::perpendicular_frame(n);
  }
};

}  // namespace

namespace fit {

Shape clipped_line(const Vector3d& point, const Vector3d& dir, const std::vector<Vector3d>& pts) {
  const Vector3d a = point + dir * dir.dot(pts.front() - point);
  const Vector3d b = point + dir * dir.dot(pts.back() - point);
  Shape s;
  s.type = ShapeType::line;
  s.point = a;
  s.length = (b - a).norm();
  s.dir = s.length > 0 ? Vector3d((b - a) / s.length) : dir;
  return s;
}

Vector3d onto_circle(const Shape& circle, const Vector3d& p) {
  Vector3d v = p - circle.point;
  v -= circle.dir * circle.dir.dot(v);
  const double len = v.norm();
  v = len > 0 ? Vector3d(v / len) : Vector3d(perpendicular_frame(circle.dir).col(0));
  return circle.point + circle.radius * v;
}

void circle_or_arc(Shape& circle, const std::vector<Vector3d>& pts, bool closed, bool orient) {
  double swept = 0;
  for (std::size_t i = 1; i < pts.size(); ++i) {
    const Vector3d a = pts[i - 1] - circle.point, b = pts[i] - circle.point;
    swept += std::atan2(circle.dir.dot(a.cross(b)), a.dot(b));
  }
  if (orient && swept < 0) circle.dir = -circle.dir;
  const double swept_deg = std::abs(swept) * 180.0 / M_PI;
  if (closed || swept_deg >= 350.0) {
    circle.type = ShapeType::circle;
    return;
  }
  circle.type = ShapeType::arc;
  circle.start = onto_circle(circle, pts.front());
  circle.end = onto_circle(circle, pts.back());
  circle.angle_deg = swept_deg;
}

}  // namespace fit

Fit fit_line(const Samples& s) {
  Fit out;
  out.shape.type = ShapeType::line;
  fit::Normalized ns;
  if (!fit::normalize(s, 2, ns)) return out;
  // PCA is the exact orthogonal least-squares line: nothing left to refine.
  const fit::Pca pc = fit::pca(s.points, s.weights);
  out.shape = fit::clipped_line(pc.mean, pc.vectors.col(2), s.points);
  fit::finish(out, s);
  return out;
}

Fit fit_circle(const Samples& s, bool closed) {
  Fit out;
  out.shape.type = closed ? ShapeType::circle : ShapeType::arc;
  fit::Normalized ns;
  if (!fit::normalize(s, 3, ns)) return out;
  const fit::Pca pc = fit::pca(ns.p, ns.w);
  if (!(pc.values[1] > 1e-10 * pc.values[2])) return out;  // collinear
  const Vector3d n = pc.vectors.col(0);
  const auto uv = fit::perpendicular_frame(n);
  std::vector<Eigen::Vector2d> q(ns.size());
  for (int i = 0; i < ns.size(); ++i) q[i] = uv.transpose() * (ns.p[i] - pc.mean);
  Eigen::Vector2d c2;
  double r;
  if (!fit::kasa_circle(q, ns.w, c2, r)) return out;
  CircleModel m(ns, pc.mean + uv * c2, n, r);
  if (!std::isfinite(fit::levenberg_marquardt(m)) || !(m.r > 0)) return out;

  Shape& sh = out.shape;
  sh.point = ns.to_world(m.c);
  sh.dir = m.n.normalized();
  sh.radius = m.r * ns.scale;
  // The normal is turned so the walk through the ordered samples is counter-clockwise about it.
  fit::circle_or_arc(sh, s.points, closed, true);
  fit::finish(out, s);
  return out;
}

}  // namespace s2c::features
