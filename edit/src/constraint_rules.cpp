#include "constraint_rules.h"

#include <algorithm>
#include <cmath>

#include <nlohmann/json.hpp>

namespace s2c::edit {

using Eigen::Matrix3d;
using Eigen::Vector3d;
using features::ConstraintKind;
using features::Shape;
using features::ShapeType;

namespace {

constexpr double kDeg = M_PI / 180.0;

bool has_axis(const Shape& s) { return s.type == ShapeType::cylinder || s.type == ShapeType::cone; }
bool is_round_curve(const Shape& s) { return s.type == ShapeType::circle || s.type == ShapeType::arc; }

double distance_to_line(const Vector3d& p, const Vector3d& origin, const Vector3d& dir) {
  const Vector3d d = dir.normalized();
  const Vector3d q = p - origin;
  return (q - q.dot(d) * d).norm();
}
Vector3d onto_line(const Vector3d& p, const Vector3d& origin, const Vector3d& dir) {
  const Vector3d d = dir.normalized();
  return origin + (p - origin).dot(d) * d;
}
Vector3d midpoint(const Shape& line) { return line.point + 0.5 * line.length * line.dir.normalized(); }
Vector3d line_end(const Shape& line) { return line.point + line.length * line.dir.normalized(); }

Vector3d any_perpendicular(const Vector3d& a) {
  Vector3d p = a.cross(Vector3d::UnitX());
  if (p.squaredNorm() < 1e-6) p = a.cross(Vector3d::UnitY());
  return p.normalized();
}

// The point a rotation of b turns about: on b's axis / plane / line, nearest its centre.
Vector3d pivot_of(const Shape& b, const Vector3d& centre) {
  switch (b.type) {
    case ShapeType::cylinder:
    case ShapeType::cone: return onto_line(centre, b.point, b.dir);
    case ShapeType::plane: return centre - (centre - b.point).dot(b.dir.normalized()) * b.dir.normalized();
    case ShapeType::line: return midpoint(b);
    case ShapeType::circle:
    case ShapeType::arc:
    case ShapeType::sphere: return b.point;
    default: return centre;
  }
}

// b's direction turned to be parallel to a's, keeping its sense.
Vector3d parallel_target(const Vector3d& a, const Vector3d& b) { return a.dot(b) >= 0.0 ? a : Vector3d(-a); }

Vector3d reflect_point(const Mirror& m, const Vector3d& x) { return x - 2.0 * (x - m.point).dot(m.normal) * m.normal; }
Vector3d reflect_dir(const Mirror& m, const Vector3d& d) { return d - 2.0 * d.dot(m.normal) * m.normal; }

// The mirror image of a shape (directions as lines: their sense is not compared).
Shape reflect(const Mirror& m, const Shape& s) {
  Shape out = s;
  out.point = reflect_point(m, s.point);
  out.dir = reflect_dir(m, s.dir);
  out.start = reflect_point(m, s.end);  // a reflection reverses the sense of an arc
  out.end = reflect_point(m, s.start);
  return out;
}

// How far b is from being a's mirror image: directions, then positions and sizes.
ConstraintResidual mirror_residual(const Mirror& m, const Shape& a, const Shape& b) {
  ConstraintResidual r;
  if (a.type != b.type) return r;
  const Shape img = reflect(m, a);
  switch (a.type) {
    case ShapeType::plane:
      r.angle_deg = line_angle_deg(img.dir, b.dir);
      r.length = std::abs((img.point - b.point).dot(b.dir.normalized()));
      break;
    case ShapeType::cylinder:
      r.angle_deg = line_angle_deg(img.dir, b.dir);
      r.length = std::max(distance_to_line(img.point, b.point, b.dir), std::abs(a.radius - b.radius));
      break;
    case ShapeType::cone:
      r.angle_deg = std::max(line_angle_deg(img.dir, b.dir), std::abs(a.half_angle_deg - b.half_angle_deg));
      r.length = (img.point - b.point).norm();
      break;
    case ShapeType::sphere: r.length = std::max((img.point - b.point).norm(), std::abs(a.radius - b.radius)); break;
    case ShapeType::circle:
    case ShapeType::arc:
      r.angle_deg = line_angle_deg(img.dir, b.dir);
      r.length = std::max((img.point - b.point).norm(), std::abs(a.radius - b.radius));
      break;
    default: return r;
  }
  r.checked = true;
  return r;
}

}  // namespace

ConstraintSpec spec_of(const features::Group& g) {
  ConstraintSpec c;
  c.kind = *g.constraint;
  c.value = g.value;
  if (auto it = g.attributes.find("mirror"); it != g.attributes.end()) {
    const auto j = nlohmann::json::parse(it->second, nullptr, false);
    if (j.is_object() && j.contains("point") && j.contains("normal") && j["point"].is_array() && j["normal"].is_array() &&
        j["point"].size() == 3 && j["normal"].size() == 3) {
      Mirror m;
      bool ok = true;
      for (int k = 0; k < 3; ++k) {
        ok = ok && j["point"][k].is_number() && j["normal"][k].is_number();
        if (!ok) break;
        m.point[k] = j["point"][k].get<double>();
        m.normal[k] = j["normal"][k].get<double>();
      }
      if (ok && m.point.allFinite() && m.normal.allFinite() && m.normal.norm() > 0.0) {
        m.normal.normalize();
        c.mirror = m;
      }
    }
  }
  return c;
}

ConstraintResidual pair_residual(const ConstraintSpec& c, const Shape& a, const Shape& b) {
  const ConstraintKind kind = c.kind;
  const std::optional<double>& value = c.value;
  ConstraintResidual r;
  const Vector3d da = direction_of(a), db = direction_of(b);
  const bool dirs = da.squaredNorm() > 0.0 && db.squaredNorm() > 0.0;
  switch (kind) {
    case ConstraintKind::parallel:
      if (!dirs) return r;
      r.angle_deg = line_angle_deg(da, db);
      break;
    case ConstraintKind::perpendicular:
      if (!dirs) return r;
      r.angle_deg = std::abs(90.0 - line_angle_deg(da, db));
      break;
    case ConstraintKind::fixed_angle:
      if (a.type != ShapeType::plane || b.type != ShapeType::plane || !value) return r;
      r.angle_deg = std::abs(line_angle_deg(da, db) - *value);
      break;
    case ConstraintKind::coaxial:
      if (has_axis(a) && has_axis(b)) {
        r.angle_deg = line_angle_deg(da, db);
        r.length = std::max(distance_to_line(b.point, a.point, da), distance_to_line(a.point, b.point, db));
      } else if (has_axis(a) && b.type == ShapeType::sphere) {
        r.length = distance_to_line(b.point, a.point, da);
      } else if (a.type == ShapeType::sphere && has_axis(b)) {
        r.length = distance_to_line(a.point, b.point, db);
      } else if (a.type == ShapeType::sphere && b.type == ShapeType::sphere) {
        r.length = (a.point - b.point).norm();
      } else {
        return r;
      }
      break;
    case ConstraintKind::concentric:
      if (is_round_curve(a) && is_round_curve(b)) r.angle_deg = line_angle_deg(da, db);
      else if (!(a.type == ShapeType::sphere && b.type == ShapeType::sphere)) return r;
      r.length = (a.point - b.point).norm();
      break;
    case ConstraintKind::equal_radius:
      if (radius_of(a) <= 0.0 || radius_of(b) <= 0.0) return r;
      r.length = std::abs(radius_of(a) - radius_of(b));
      break;
    case ConstraintKind::equal_length:
      if (a.type != ShapeType::line || b.type != ShapeType::line) return r;
      r.length = std::abs(a.length - b.length);
      break;
    case ConstraintKind::collinear:
      if (a.type != ShapeType::line || b.type != ShapeType::line) return r;
      r.angle_deg = line_angle_deg(da, db);
      r.length = std::max(distance_to_line(b.point, a.point, da), distance_to_line(line_end(b), a.point, da));
      break;
    case ConstraintKind::symmetric:
      return c.mirror ? mirror_residual(*c.mirror, a, b) : r;
    default: return r;  // connected (kept by the mesh) and equal_angle (its fixed_angle groups): not measured here
  }
  r.checked = true;
  return r;
}

std::optional<ShapeMap> adjustment(const ConstraintSpec& c, const Shape& a, const Shape& b, const Vector3d& b_centre) {
  const ConstraintKind kind = c.kind;
  const std::optional<double>& value = c.value;
  const Vector3d da = direction_of(a), db = direction_of(b);
  const bool dirs = da.squaredNorm() > 0.0 && db.squaredNorm() > 0.0;
  const Vector3d pivot = pivot_of(b, b_centre);
  switch (kind) {
    case ConstraintKind::parallel:
      if (!dirs) return std::nullopt;
      return ShapeMap::align(db, parallel_target(da, db), pivot);
    case ConstraintKind::perpendicular: {
      if (!dirs) return std::nullopt;
      Vector3d t = db - db.dot(da) * da;
      t = t.norm() > 1e-9 ? Vector3d(t.normalized()) : any_perpendicular(da);
      return ShapeMap::align(db, t, pivot);
    }
    case ConstraintKind::fixed_angle: {
      if (a.type != ShapeType::plane || b.type != ShapeType::plane || !value) return std::nullopt;
      Vector3d u = db - db.dot(da) * da;
      u = u.norm() > 1e-9 ? Vector3d(u.normalized()) : any_perpendicular(da);
      const double sense = da.dot(db) >= 0.0 ? 1.0 : -1.0;
      const Vector3d t = sense * std::cos(*value * kDeg) * da + std::sin(*value * kDeg) * u;
      return ShapeMap::align(db, t, pivot);
    }
    case ConstraintKind::coaxial: {
      if (has_axis(a) && has_axis(b)) {
        const ShapeMap turn = ShapeMap::align(db, parallel_target(da, db), pivot);
        const Vector3d p = turn.apply(pivot);
        return ShapeMap::translation(onto_line(p, a.point, da) - p).after(turn);
      }
      if (has_axis(a) && b.type == ShapeType::sphere)
        return ShapeMap::translation(onto_line(b.point, a.point, da) - b.point);
      if (a.type == ShapeType::sphere && has_axis(b))
        return ShapeMap::translation(a.point - onto_line(a.point, b.point, db));
      if (a.type == ShapeType::sphere && b.type == ShapeType::sphere) return ShapeMap::translation(a.point - b.point);
      return std::nullopt;
    }
    case ConstraintKind::concentric: {
      if (is_round_curve(a) && is_round_curve(b)) {
        const ShapeMap turn = ShapeMap::align(db, parallel_target(da, db), b.point);
        return ShapeMap::translation(a.point - b.point).after(turn);
      }
      if (a.type == ShapeType::sphere && b.type == ShapeType::sphere) return ShapeMap::translation(a.point - b.point);
      return std::nullopt;
    }
    case ConstraintKind::equal_radius: {
      if (radius_of(a) <= 0.0 || radius_of(b) <= 0.0) return std::nullopt;
      Shape t = b;
      t.radius = radius_of(a);
      return ShapeMap::resize(b, t);
    }
    case ConstraintKind::equal_length: {
      if (a.type != ShapeType::line || b.type != ShapeType::line || b.length <= 0.0) return std::nullopt;
      const Vector3d d = b.dir.normalized(), mid = midpoint(b);
      ShapeMap m;
      m.linear = Matrix3d::Identity() + (a.length / b.length - 1.0) * d * d.transpose();
      m.offset = mid - m.linear * mid;
      m.similarity = false;
      return m;
    }
    case ConstraintKind::collinear: {
      if (a.type != ShapeType::line || b.type != ShapeType::line) return std::nullopt;
      const ShapeMap turn = ShapeMap::align(db, parallel_target(da, db), midpoint(b));
      const Vector3d p = turn.apply(midpoint(b));
      return ShapeMap::translation(onto_line(p, a.point, da) - p).after(turn);
    }
    default: return std::nullopt;
  }
}

}  // namespace s2c::edit
