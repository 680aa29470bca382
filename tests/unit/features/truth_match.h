#pragma once
// Test helpers: read a fixture part's ground truth (scan2cad.truth/1) and match detected
// features against it with the tolerances (axis ≤ 2°, radius ≤ 2%, position ≤ 0.2 mm).
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "s2c/features/feature_set.h"

namespace s2c::test {

struct TruthItem {
  std::string id;
  features::Shape shape;
};
struct Truth {
  std::vector<TruthItem> primitives, lines;
  nlohmann::json constraints;
};

inline Eigen::Vector3d vec3(const nlohmann::json& j) { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }

inline features::Shape truth_shape(const nlohmann::json& j) {
  using features::ShapeType;
  features::Shape s;
  s.type = features::shape_type(j["type"].get<std::string>());
  switch (s.type) {
    case ShapeType::plane: s.dir = vec3(j["normal"]); s.point = vec3(j["point"]); break;
    case ShapeType::cylinder: s.point = vec3(j["axis_point"]); s.dir = vec3(j["axis_dir"]); s.radius = j["radius"]; break;
    case ShapeType::sphere: s.point = vec3(j["center"]); s.radius = j["radius"]; break;
    case ShapeType::cone: s.point = vec3(j["apex"]); s.dir = vec3(j["axis_dir"]); s.half_angle_deg = j["half_angle_deg"]; break;
    case ShapeType::line: s.point = vec3(j["point"]); s.dir = vec3(j["direction"]); s.length = j["length"]; break;
    case ShapeType::circle: s.point = vec3(j["center"]); s.dir = vec3(j["normal"]); s.radius = j["radius"]; break;
    default: break;
  }
  s.dir.normalize();
  return s;
}

inline Truth read_truth(const std::string& path) {
  std::ifstream in(path);
  const auto doc = nlohmann::json::parse(in);
  Truth t;
  for (const auto& p : doc["primitives"]) t.primitives.push_back({p["id"], truth_shape(p["shape"])});
  for (const auto& l : doc["lines"]) t.lines.push_back({l["id"], truth_shape(l["shape"])});
  t.constraints = doc["constraints"];
  return t;
}

inline double angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {  // sign-insensitive
  return std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized())))) * 180.0 / M_PI;
}
inline double line_distance(const Eigen::Vector3d& p, const Eigen::Vector3d& point, const Eigen::Vector3d& dir) {
  const Eigen::Vector3d d = p - point;
  return (d - dir * dir.dot(d)).norm();
}

/// Does the detected shape match the truth shape within the tolerances?
inline bool shapes_match(const features::Shape& truth, const features::Shape& got, double pos_tol = 0.2,
                         double angle_tol = 2.0, double radius_rel = 0.02) {
  using features::ShapeType;
  const bool curve_arc = truth.type == ShapeType::circle && got.type == ShapeType::arc;
  if (truth.type != got.type && !curve_arc) return false;
  switch (truth.type) {
    case ShapeType::plane:
      return angle_deg(truth.dir, got.dir) <= angle_tol && std::abs(got.dir.normalized().dot(truth.point - got.point)) <= pos_tol;
    case ShapeType::cylinder:
      return angle_deg(truth.dir, got.dir) <= angle_tol && line_distance(truth.point, got.point, got.dir) <= pos_tol &&
             std::abs(got.radius - truth.radius) <= radius_rel * truth.radius;
    case ShapeType::sphere:
      return (truth.point - got.point).norm() <= pos_tol && std::abs(got.radius - truth.radius) <= radius_rel * truth.radius;
    case ShapeType::cone:
      return angle_deg(truth.dir, got.dir) <= angle_tol && (truth.point - got.point).norm() <= pos_tol &&
             std::abs(got.half_angle_deg - truth.half_angle_deg) <= angle_tol;
    case ShapeType::line: {
      const Eigen::Vector3d end = truth.point + truth.length * truth.dir;
      return angle_deg(truth.dir, got.dir) <= angle_tol && line_distance(truth.point, got.point, got.dir) <= pos_tol &&
             line_distance(end, got.point, got.dir) <= pos_tol && std::abs(got.length - truth.length) <= 2 * pos_tol;
    }
    case ShapeType::circle:
      return angle_deg(truth.dir, got.dir) <= angle_tol && (truth.point - got.point).norm() <= pos_tol &&
             std::abs(got.radius - truth.radius) <= radius_rel * truth.radius;
    default: return false;
  }
}

/// Greedy one-to-one matching: truth id → detected feature id.
template <typename Feature>
std::map<std::string, std::string> match(const std::vector<TruthItem>& truth, const std::vector<Feature>& got) {
  std::map<std::string, std::string> out;
  std::vector<char> used(got.size(), 0);
  for (const auto& t : truth)
    for (std::size_t i = 0; i < got.size(); ++i)
      if (!used[i] && shapes_match(t.shape, got[i].shape)) {
        out[t.id] = got[i].id;
        used[i] = 1;
        break;
      }
  return out;
}

}  // namespace s2c::test
