#include "shape_map.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace s2c::edit {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using features::Shape;
using features::ShapeType;

namespace {
constexpr double kDeg = M_PI / 180.0;

// A unit vector perpendicular to a.
Vector3d any_perpendicular(const Vector3d& a) {
  Vector3d p = a.cross(Vector3d::UnitX());
  if (p.squaredNorm() < 1e-6) p = a.cross(Vector3d::UnitY());
  return p.normalized();
}
}  // namespace

bool finite_shape(const Shape& s) {
  return s.point.allFinite() && s.dir.allFinite() && std::isfinite(s.radius) && std::isfinite(s.half_angle_deg) &&
         std::isfinite(s.length) && s.start.allFinite() && s.end.allFinite() && std::isfinite(s.angle_deg);
}

Vector3d direction_of(const Shape& s) {
  switch (s.type) {
    case ShapeType::plane:
    case ShapeType::cylinder:
    case ShapeType::cone:
    case ShapeType::line:
    case ShapeType::circle:
    case ShapeType::arc: return s.dir.normalized();
    default: return Vector3d::Zero();
  }
}

double radius_of(const Shape& s) {
  switch (s.type) {
    case ShapeType::cylinder:
    case ShapeType::sphere:
    case ShapeType::circle:
    case ShapeType::arc: return s.radius;
    default: return 0.0;
  }
}

double line_angle_deg(const Vector3d& a, const Vector3d& b) {
  const double c = std::min(1.0, std::abs(a.normalized().dot(b.normalized())));
  // acos loses precision near 0°: use atan2 of sine and cosine instead.
  const double s = a.normalized().cross(b.normalized()).norm();
  return std::atan2(s, c) / kDeg;
}

ShapeMap ShapeMap::translation(const Vector3d& by) {
  ShapeMap m;
  m.offset = by;
  return m;
}

ShapeMap ShapeMap::rotation(const Vector3d& axis, double degrees, const Vector3d& pivot) {
  ShapeMap m;
  m.linear = Eigen::AngleAxisd(degrees * kDeg, axis.normalized()).toRotationMatrix();
  m.offset = pivot - m.linear * pivot;
  return m;
}

ShapeMap ShapeMap::align(const Vector3d& from, const Vector3d& to, const Vector3d& pivot) {
  ShapeMap m;
  const Vector3d a = from.normalized(), b = to.normalized();
  if (a.dot(b) < -1.0 + 1e-12) {
    m.linear = Eigen::AngleAxisd(M_PI, any_perpendicular(a)).toRotationMatrix();
  } else {
    m.linear = Eigen::Quaterniond::FromTwoVectors(a, b).toRotationMatrix();
  }
  m.offset = pivot - m.linear * pivot;
  return m;
}

ShapeMap ShapeMap::scaling(double factor, const Vector3d& pivot) {
  ShapeMap m;
  m.scale = factor;
  m.linear = factor * Matrix3d::Identity();
  m.offset = pivot - m.linear * pivot;
  return m;
}

ShapeMap ShapeMap::resize(const Shape& source, const Shape& target) {
  ShapeMap m;
  m.kind = Kind::resize;
  m.source = source;
  m.target = target;
  return m;
}

Vector3d project_onto(const Shape& s, const Vector3d& p) {
  const Vector3d d = s.dir.normalized();
  const Vector3d q = p - s.point;
  switch (s.type) {
    case ShapeType::plane: return p - q.dot(d) * d;
    case ShapeType::sphere: return q.norm() > 0.0 ? Vector3d(s.point + s.radius * q.normalized()) : p;
    case ShapeType::cylinder: {
      const double h = q.dot(d);
      const Vector3d r = q - h * d;
      return r.norm() > 0.0 ? Vector3d(s.point + h * d + s.radius * r.normalized()) : p;
    }
    case ShapeType::cone: {
      // Nearest point on the generator line through p's azimuth.
      const double h = q.dot(d);
      const Vector3d r = q - h * d;
      if (r.norm() <= 0.0) return p;
      const double a = s.half_angle_deg * kDeg;
      const Vector3d g = (std::cos(a) * d + std::sin(a) * r.normalized()).normalized();
      return s.point + std::max(0.0, q.dot(g)) * g;
    }
    default: return p;
  }
}

ShapeMap ShapeMap::after(const ShapeMap& first) const {
  ShapeMap m;
  m.linear = linear * first.linear;
  m.offset = linear * first.offset + offset;
  m.similarity = similarity && first.similarity;
  m.scale = scale * first.scale;
  return m;
}

Vector3d resize_point(const Shape& source, const Shape& target, const Vector3d& p0, const Vector3d& current) {
  // Curves (circle, arc) resize like the cylinder through them.
  auto as_surface = [](Shape s) {
    if (s.type == ShapeType::circle || s.type == ShapeType::arc) s.type = ShapeType::cylinder;
    return s;
  };
  const Shape src = as_surface(source), dst = as_surface(target);
  const Vector3d on_src = project_onto(src, p0);
  const double offset = (p0 - on_src).dot(features::surface_normal(src, p0));
  const Vector3d on_dst = project_onto(dst, current);
  if (on_dst == current && (current - dst.point).norm() == 0.0) return current;  // on the axis / at the centre
  return on_dst + offset * features::surface_normal(dst, current);
}

Vector3d ShapeMap::apply(const Vector3d& p) const {
  if (kind == Kind::affine) return linear * p + offset;
  return resize_point(source, target, p, p);
}

Shape ShapeMap::apply(const Shape& s) const {
  if (kind == Kind::resize) {
    Shape out = s;
    out.radius = target.radius;
    out.half_angle_deg = target.half_angle_deg;
    if (s.type == ShapeType::arc) {
      out.start = apply(s.start);
      out.end = apply(s.end);
    }
    return out;
  }
  Shape out = s;
  // For a similarity s·R: directions rotate, lengths scale by s.
  const Matrix3d rot = scale > 0.0 ? Matrix3d(linear / scale) : Matrix3d::Identity();
  out.point = apply(s.point);
  out.dir = (rot * s.dir).normalized();
  out.radius = s.radius * scale;
  out.length = s.length * scale;
  out.start = apply(s.start);
  out.end = apply(s.end);
  return out;
}

bool ShapeMap::is_identity(double tol) const {
  return kind == Kind::affine && (linear - Matrix3d::Identity()).cwiseAbs().maxCoeff() <= tol &&
         offset.cwiseAbs().maxCoeff() <= tol;
}

std::string ShapeMap::describe(const Shape& before) const {
  if (kind == Kind::resize) {
    if (target.type == ShapeType::cone)
      return fmt::format("half angle {:.4g}° → {:.4g}°", before.half_angle_deg, target.half_angle_deg);
    return fmt::format("radius {:.4g} → {:.4g} mm", before.radius, target.radius);
  }
  if (!similarity) return "stretched";
  const Eigen::AngleAxisd aa(Matrix3d(linear / scale));
  std::string s;
  if (std::abs(aa.angle()) > 1e-9)
    s += fmt::format("rotated {:.4g}° about [{:.3g}, {:.3g}, {:.3g}]", aa.angle() / kDeg, aa.axis().x(), aa.axis().y(),
                     aa.axis().z());
  if (std::abs(scale - 1.0) > 1e-12) s += fmt::format("{}scaled by {:.4g}", s.empty() ? "" : ", ", scale);
  const Vector3d c = before.point;
  const Vector3d moved = apply(c) - c;
  if (s.empty() || moved.norm() > 1e-9)
    s += fmt::format("{}moved by [{:.4g}, {:.4g}, {:.4g}]", s.empty() ? "" : ", ", moved.x(), moved.y(), moved.z());
  return s;
}

}  // namespace s2c::edit
