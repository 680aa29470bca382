#include "features_eval.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <limits>
#include <memory>
#include <numeric>
#include <queue>
#include <set>
#include <sstream>
#include <thread>

#include <nlohmann/json.hpp>

#include "common/sampling.h"
#include "s2c/core/distance.h"
#include "s2c/core/errors.h"
#include "s2c/core/io.h"

namespace s2c::bench {

namespace fs = std::filesystem;
using Eigen::Vector3d;
using features::ConstraintKind;
using features::Shape;
using features::ShapeType;
using nlohmann::json;

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kInf = std::numeric_limits<double>::infinity();

double to_deg(double r) { return r * 180.0 / kPi; }
double to_rad(double d) { return d * kPi / 180.0; }

// Angle between two directions in degrees, [0, 180].
double angle_deg(const Vector3d& a, const Vector3d& b) {
  const double na = a.norm(), nb = b.norm();
  if (na == 0 || nb == 0) return 180.0;
  return to_deg(std::acos(std::clamp(a.dot(b) / (na * nb), -1.0, 1.0)));
}
// Sign-insensitive angle between two axes, [0, 90].
double axis_angle_deg(const Vector3d& a, const Vector3d& b) {
  const double x = angle_deg(a, b);
  return std::min(x, 180.0 - x);
}
Vector3d unit_or_z(const Vector3d& v) {
  const double n = v.norm();
  return n > 0 ? Vector3d(v / n) : Vector3d::UnitZ();
}

double point_line_distance(const Vector3d& p, const Vector3d& q, const Vector3d& dir) {
  const Vector3d d = unit_or_z(dir), v = p - q;
  return (v - v.dot(d) * d).norm();
}
double point_segment_distance(const Vector3d& p, const Vector3d& a, const Vector3d& b) {
  const Vector3d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}
double point_circle_distance(const Vector3d& p, const Vector3d& c, const Vector3d& normal, double r) {
  const Vector3d n = unit_or_z(normal), v = p - c;
  const double h = v.dot(n);
  const double w = (v - h * n).norm();
  return std::hypot(h, w - r);
}

// Two unit vectors completing `n` to an orthonormal basis.
std::pair<Vector3d, Vector3d> basis(const Vector3d& normal) {
  const Vector3d n = unit_or_z(normal);
  const Vector3d u = n.cross(std::abs(n.x()) < 0.9 ? Vector3d::UnitX() : Vector3d::UnitY()).normalized();
  return {u, n.cross(u)};
}

// Outward surface normal (away from the plane side / axis / centre); zero where undefined.
Vector3d shape_normal(const Shape& s, const Vector3d& p) {
  const Vector3d d = unit_or_z(s.dir);
  switch (s.type) {
    case ShapeType::plane:
      return d;
    case ShapeType::cylinder: {
      const Vector3d v = p - s.point, r = v - v.dot(d) * d;
      return r.norm() > 1e-12 ? Vector3d(r.normalized()) : Vector3d::Zero();
    }
    case ShapeType::sphere: {
      const Vector3d v = p - s.point;
      return v.norm() > 1e-12 ? Vector3d(v.normalized()) : Vector3d::Zero();
    }
    case ShapeType::cone: {
      const Vector3d v = p - s.point, r = v - v.dot(d) * d;
      if (r.norm() <= 1e-12) return Vector3d::Zero();
      const double a = to_rad(s.half_angle_deg);
      return std::cos(a) * r.normalized() - std::sin(a) * d;
    }
    default:
      return Vector3d::Zero();
  }
}

Vector3d oriented_normal(const TruthFeature& f, const Vector3d& p) {
  const Vector3d n = shape_normal(f.shape, p);
  return f.inward ? Vector3d(-n) : n;
}

Vector3d line_end(const Shape& s) { return s.point + s.length * unit_or_z(s.dir); }

// ----------------------------------------------------------------------------- parallel loop
template <class F>
void parallel_for(std::size_t n, F&& f) {
  const unsigned nt = static_cast<unsigned>(
      std::clamp<std::size_t>(n / 2000 + 1, 1, std::max(1u, std::thread::hardware_concurrency())));
  if (nt == 1) {
    for (std::size_t i = 0; i < n; ++i) f(i);
    return;
  }
  std::vector<std::thread> threads;
  for (unsigned t = 0; t < nt; ++t)
    threads.emplace_back([&, t] {
      for (std::size_t i = t; i < n; i += nt) f(i);
    });
  for (auto& th : threads) th.join();
}

// ----------------------------------------------------------------------------- JSON
[[noreturn]] void bad(const std::string& where, const std::string& what) { throw InvalidInput(where + ": " + what); }

const json& key(const json& j, const char* k, const std::string& where) {
  if (!j.is_object() || !j.contains(k)) bad(where, std::string("missing key \"") + k + "\"");
  return j.at(k);
}
double number(const json& j, const char* k, const std::string& where) {
  const json& v = key(j, k, where);
  if (!v.is_number()) bad(where + "." + k, "not a number");
  return v.get<double>();
}
std::string text(const json& j, const char* k, const std::string& where) {
  const json& v = key(j, k, where);
  if (!v.is_string()) bad(where + "." + k, "not a string");
  return v.get<std::string>();
}
Vector3d vec3(const json& j, const char* k, const std::string& where) {
  const json& v = key(j, k, where);
  if (!v.is_array() || v.size() != 3 || !v[0].is_number() || !v[1].is_number() || !v[2].is_number())
    bad(where + "." + k, "not an array of 3 numbers");
  return {v[0].get<double>(), v[1].get<double>(), v[2].get<double>()};
}
Vector3d unit_vec3(const json& j, const char* k, const std::string& where) {
  const Vector3d v = vec3(j, k, where);
  if (v.norm() < 1e-12) bad(where + "." + k, "zero vector");
  return v.normalized();
}

Shape parse_shape(const json& j, const std::string& where) {
  Shape s;
  const std::string type = text(j, "type", where);
  if (type == "plane") {
    s.type = ShapeType::plane;
    s.dir = unit_vec3(j, "normal", where);
    s.point = vec3(j, "point", where);
  } else if (type == "cylinder") {
    s.type = ShapeType::cylinder;
    s.point = vec3(j, "axis_point", where);
    s.dir = unit_vec3(j, "axis_dir", where);
    s.radius = number(j, "radius", where);
  } else if (type == "sphere") {
    s.type = ShapeType::sphere;
    s.point = vec3(j, "center", where);
    s.radius = number(j, "radius", where);
  } else if (type == "cone") {
    s.type = ShapeType::cone;
    s.point = vec3(j, "apex", where);
    s.dir = unit_vec3(j, "axis_dir", where);
    s.half_angle_deg = number(j, "half_angle_deg", where);
  } else if (type == "line") {
    s.type = ShapeType::line;
    s.point = vec3(j, "point", where);
    s.dir = unit_vec3(j, "direction", where);
    s.length = number(j, "length", where);
  } else if (type == "circle") {
    s.type = ShapeType::circle;
    s.point = vec3(j, "center", where);
    s.dir = unit_vec3(j, "normal", where);
    s.radius = number(j, "radius", where);
  } else {
    bad(where + ".type", "unknown shape type \"" + type + "\"");
  }
  return s;
}


bool is_equivalence(ConstraintKind k) {
  return k == ConstraintKind::parallel || k == ConstraintKind::coaxial || k == ConstraintKind::concentric ||
         k == ConstraintKind::equal_radius || k == ConstraintKind::equal_length || k == ConstraintKind::collinear;
}

// ----------------------------------------------------------------------------- disjoint sets
struct Dsu {
  std::vector<int> parent;
  explicit Dsu(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  int find(int x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(int a, int b) { parent[find(a)] = find(b); }
};

// ----------------------------------------------------------------------------- truth regions
// The part of the truth mesh each primitive claims, as a BVH (the primitives themselves are
// infinite surfaces; their faces are bounded).
class TruthRegions {
 public:
  explicit TruthRegions(const Truth& truth) : truth_(truth) {
    const std::size_t n = truth.primitives.size();
    soups_.resize(n);
    queries_.resize(n);
    if (truth.mesh.empty()) return;
    for (std::size_t i = 0; i < n; ++i) {
      soups_[i] = std::make_unique<TriangleSoup>();
      soups_[i]->vertices = truth.mesh.vertices;
    }
    for (std::size_t f = 0; f < truth.mesh.faces.size(); ++f)
      if (truth.mesh_labels[f] >= 0) soups_[truth.mesh_labels[f]]->faces.push_back(truth.mesh.faces[f]);
    for (std::size_t i = 0; i < n; ++i)
      if (!soups_[i]->faces.empty()) queries_[i] = std::make_unique<SurfaceQuery>(*soups_[i]);
  }
  // Distance from p to primitive i's region (its infinite surface without a truth mesh); kInf
  // when farther than max_distance.
  double distance(int i, const Vector3d& p, double max_distance) const {
    if (queries_[i]) {
      const auto hit = queries_[i]->closest(p, max_distance);
      return hit ? hit->distance : kInf;
    }
    const double d = shape_distance(truth_.primitives[i].shape, p);
    return d <= max_distance ? d : kInf;
  }

 private:
  const Truth& truth_;
  std::vector<std::unique_ptr<TriangleSoup>> soups_;
  std::vector<std::unique_ptr<SurfaceQuery>> queries_;
};

std::vector<double> face_areas(const Mesh& mesh) {
  std::vector<double> a(mesh.n_faces(), 0.0);
  for (auto f : mesh.faces()) {
    auto h = mesh.halfedge_handle(f);
    const Vector3d p0 = to_eigen(mesh.point(mesh.from_vertex_handle(h)));
    const Vector3d p1 = to_eigen(mesh.point(mesh.to_vertex_handle(h)));
    const Vector3d p2 = to_eigen(mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(h))));
    a[f.idx()] = 0.5 * (p1 - p0).cross(p2 - p0).norm();
  }
  return a;
}

std::array<Vector3d, 3> face_points(const Mesh& mesh, Mesh::FaceHandle f) {
  auto h = mesh.halfedge_handle(f);
  return {to_eigen(mesh.point(mesh.from_vertex_handle(h))), to_eigen(mesh.point(mesh.to_vertex_handle(h))),
          to_eigen(mesh.point(mesh.to_vertex_handle(mesh.next_halfedge_handle(h))))};
}

// ----------------------------------------------------------------------------- shape matching
struct ShapeMatch {
  bool ok = false;
  double score = kInf;  // sum of the errors, each divided by its tolerance
};

ShapeMatch match_surface(const Shape& t, const Shape& d, const Tolerances& tol) {
  ShapeMatch m;
  if (t.type != d.type) return m;
  double score = 0;
  bool ok = true;
  auto add = [&](double err, double limit) {
    ok = ok && std::isfinite(err) && err <= limit;
    score += err / limit;
  };
  switch (t.type) {
    case ShapeType::plane:
      add(axis_angle_deg(t.dir, d.dir), tol.angle_deg);
      add(std::abs((t.point - d.point).dot(unit_or_z(d.dir))), tol.position_mm);
      break;
    case ShapeType::cylinder:
      add(axis_angle_deg(t.dir, d.dir), tol.angle_deg);
      add(std::abs(d.radius - t.radius) / t.radius, tol.radius_rel);
      add(point_line_distance(t.point, d.point, d.dir), tol.position_mm);
      break;
    case ShapeType::sphere:
      add(std::abs(d.radius - t.radius) / t.radius, tol.radius_rel);
      add((t.point - d.point).norm(), tol.position_mm);
      break;
    case ShapeType::cone:
      add(axis_angle_deg(t.dir, d.dir), tol.angle_deg);
      add(std::abs(d.half_angle_deg - t.half_angle_deg), tol.angle_deg);
      add((t.point - d.point).norm(), tol.position_mm);
      break;
    default:
      return m;
  }
  m.ok = ok;
  m.score = score;
  return m;
}

// A detected curve against a truth curve (to map line ids for the constraints).
ShapeMatch match_curve(const Shape& t, const Shape& d, const Tolerances& tol) {
  ShapeMatch m;
  double score = 0;
  bool ok = true;
  auto add = [&](double err, double limit) {
    ok = ok && std::isfinite(err) && err <= limit;
    score += err / limit;
  };
  if (t.type == ShapeType::line && d.type == ShapeType::line) {
    const Vector3d a = t.point, b = line_end(t);
    add(axis_angle_deg(t.dir, d.dir), tol.angle_deg);
    add(point_segment_distance(d.point, a, b), tol.line_tol_mm);
    add(point_segment_distance(line_end(d), a, b), tol.line_tol_mm);
  } else if (t.type == ShapeType::circle && (d.type == ShapeType::circle || d.type == ShapeType::arc)) {
    add(axis_angle_deg(t.dir, d.dir), tol.angle_deg);
    add((t.point - d.point).norm(), tol.position_mm);
    add(std::abs(d.radius - t.radius) / t.radius, tol.radius_rel);
  } else {
    return m;
  }
  m.ok = ok;
  m.score = score;
  return m;
}

// ----------------------------------------------------------------------------- curve samples
struct CurveSamples {
  std::vector<Vector3d> points;
  std::vector<double> weights;  // length each sample stands for, mm
};

void sample_segment(const Vector3d& a, const Vector3d& b, double step, CurveSamples& out) {
  const double len = (b - a).norm();
  const int n = std::max(1, static_cast<int>(std::ceil(len / step)));
  for (int i = 0; i < n; ++i) {
    out.points.push_back(a + (i + 0.5) / n * (b - a));
    out.weights.push_back(len / n);
  }
}

void sample_curve(const Shape& s, double step, CurveSamples& out) {
  if (s.type == ShapeType::line) {
    sample_segment(s.point, line_end(s), step, out);
  } else if (s.type == ShapeType::circle || s.type == ShapeType::arc) {
    const auto [u, v] = basis(s.dir);
    const double len = 2 * kPi * s.radius;
    const int n = std::max(16, static_cast<int>(std::ceil(len / step)));
    for (int i = 0; i < n; ++i) {
      const double a = (i + 0.5) * 2 * kPi / n;
      out.points.push_back(s.point + s.radius * (std::cos(a) * u + std::sin(a) * v));
      out.weights.push_back(len / n);
    }
  }
}

double curve_distance(const Shape& s, const Vector3d& p) {
  if (s.type == ShapeType::line) return point_segment_distance(p, s.point, line_end(s));
  return point_circle_distance(p, s.point, s.dir, s.radius);
}

struct DetectedLine {
  std::string id;
  Shape shape;
  std::vector<Vector3d> polyline;
  bool closed = false;
};

CurveSamples sample_polyline(const DetectedLine& l, double step) {
  CurveSamples out;
  const std::size_t n = l.polyline.size();
  for (std::size_t i = 0; i + 1 < n; ++i) sample_segment(l.polyline[i], l.polyline[i + 1], step, out);
  if (l.closed && n > 2) sample_segment(l.polyline[n - 1], l.polyline[0], step, out);
  if (n == 1) {
    out.points.push_back(l.polyline[0]);
    out.weights.push_back(0.0);
  }
  return out;
}

LineMetrics evaluate_lines(const std::vector<DetectedLine>& lines, const Truth& truth, const Tolerances& tol) {
  LineMetrics m;
  // Precision: detected polyline length within tol of a truth curve.
  CurveSamples det;
  for (const auto& l : lines) {
    CurveSamples s = sample_polyline(l, tol.line_step_mm);
    det.points.insert(det.points.end(), s.points.begin(), s.points.end());
    det.weights.insert(det.weights.end(), s.weights.begin(), s.weights.end());
  }
  double good = 0;
  for (std::size_t i = 0; i < det.points.size(); ++i) {
    m.detected_length += det.weights[i];
    for (const auto& t : truth.lines)
      if (curve_distance(t.shape, det.points[i]) <= tol.line_tol_mm) {
        good += det.weights[i];
        break;
      }
  }
  m.precision = m.detected_length > 0 ? good / m.detected_length : (truth.lines.empty() ? 1.0 : 0.0);
  // Recall: truth curve length within tol of a detected polyline (its samples every step, so
  // the test is conservative by at most step/2).
  const PointGrid grid(det.points, std::max(tol.line_tol_mm, 1e-3));
  double covered = 0;
  for (const auto& t : truth.lines) {
    CurveSamples s;
    sample_curve(t.shape, tol.line_step_mm, s);
    for (std::size_t i = 0; i < s.points.size(); ++i) {
      m.truth_length += s.weights[i];
      if (grid.any_within(s.points[i], tol.line_tol_mm)) covered += s.weights[i];
    }
  }
  m.recall = m.truth_length > 0 ? covered / m.truth_length : 1.0;
  m.f1 = m.precision + m.recall > 0 ? 2 * m.precision * m.recall / (m.precision + m.recall) : 0.0;

  // Circle radius error: truth circles against detected circles/arcs with the centre within
  // position_mm and a parallel normal; one-to-one, greedy by relative radius error.
  struct Cand {
    double err;
    int t, d;
  };
  std::vector<Cand> cands;
  for (std::size_t t = 0; t < truth.lines.size(); ++t) {
    const Shape& ts = truth.lines[t].shape;
    if (ts.type != ShapeType::circle) continue;
    ++m.truth_circles;
    for (std::size_t d = 0; d < lines.size(); ++d) {
      const Shape& ds = lines[d].shape;
      if (ds.type != ShapeType::circle && ds.type != ShapeType::arc) continue;
      if ((ds.point - ts.point).norm() > tol.position_mm || axis_angle_deg(ds.dir, ts.dir) > tol.angle_deg) continue;
      const double err = std::abs(ds.radius - ts.radius) / ts.radius;
      if (err <= tol.circle_radius_window) cands.push_back({err, int(t), int(d)});
    }
  }
  std::sort(cands.begin(), cands.end(), [](const Cand& a, const Cand& b) { return a.err < b.err; });
  std::vector<char> tused(truth.lines.size(), 0), dused(lines.size(), 0);
  double sum = 0;
  for (const auto& c : cands) {
    if (tused[c.t] || dused[c.d]) continue;
    tused[c.t] = dused[c.d] = 1;
    ++m.matched_circles;
    sum += c.err;
    m.circle_err_max = std::max(m.circle_err_max, c.err);
  }
  m.circle_err_mean = m.matched_circles ? sum / m.matched_circles : 0.0;
  return m;
}

// ----------------------------------------------------------------------------- constraints
// A truth feature reference: primitives 0..P-1, lines P..P+L-1.
struct TruthRefs {
  const Truth& truth;
  const TruthRegions& regions;
  const Tolerances& tol;
  int n_prim() const { return int(truth.primitives.size()); }
  bool is_line(int r) const { return r >= n_prim(); }
  const TruthFeature& feature(int r) const { return is_line(r) ? truth.lines[r - n_prim()] : truth.primitives[r]; }
  const Shape& shape(int r) const { return feature(r).shape; }
  const std::string& id(int r) const { return feature(r).id; }

  // 'N' normal-like (plane, circle normal), 'A' axis-like (cylinder/cone axis, line), 0 none.
  char dir_class(int r) const {
    switch (shape(r).type) {
      case ShapeType::plane:
      case ShapeType::circle:
      case ShapeType::arc:
        return 'N';
      case ShapeType::cylinder:
      case ShapeType::cone:
      case ShapeType::line:
        return 'A';
      default:
        return 0;
    }
  }
  bool has_axis(int r) const {
    const ShapeType t = shape(r).type;
    return t == ShapeType::cylinder || t == ShapeType::cone || t == ShapeType::circle || t == ShapeType::arc;
  }
  bool has_centre(int r) const {
    const ShapeType t = shape(r).type;
    return t == ShapeType::sphere || t == ShapeType::circle || t == ShapeType::arc;
  }
  std::optional<double> radius(int r) const {
    const ShapeType t = shape(r).type;
    if (t == ShapeType::cylinder || t == ShapeType::sphere || t == ShapeType::circle || t == ShapeType::arc)
      return shape(r).radius;
    return std::nullopt;
  }

  bool parallel(int a, int b) const {
    const char ca = dir_class(a), cb = dir_class(b);
    if (!ca || !cb) return false;
    const double x = axis_angle_deg(shape(a).dir, shape(b).dir);
    return ca == cb ? x <= tol.angle_deg : std::abs(90 - x) <= tol.angle_deg;
  }
  bool perpendicular(int a, int b) const {
    const char ca = dir_class(a), cb = dir_class(b);
    if (!ca || !cb) return false;
    const double x = axis_angle_deg(shape(a).dir, shape(b).dir);
    return ca == cb ? std::abs(90 - x) <= tol.angle_deg : x <= tol.angle_deg;
  }
  // b lies on a's axis line (a has an axis).
  bool on_axis(int a, int b) const {
    const Shape &sa = shape(a), &sb = shape(b);
    if (has_axis(b) && axis_angle_deg(sa.dir, sb.dir) > tol.angle_deg) return false;
    return point_line_distance(sb.point, sa.point, sa.dir) <= tol.position_mm;
  }
  bool coaxial(const std::vector<int>& m) const {
    auto ref = std::find_if(m.begin(), m.end(), [&](int r) { return has_axis(r); });
    if (ref == m.end()) return concentric_centres(m);
    return std::all_of(m.begin(), m.end(), [&](int r) { return (has_axis(r) || has_centre(r)) && on_axis(*ref, r); });
  }
  bool concentric_centres(const std::vector<int>& m) const {
    if (!std::all_of(m.begin(), m.end(), [&](int r) { return has_centre(r); })) return false;
    for (int r : m) {
      if ((shape(r).point - shape(m[0]).point).norm() > tol.position_mm) return false;
      if (dir_class(r) && dir_class(m[0]) && axis_angle_deg(shape(r).dir, shape(m[0]).dir) > tol.angle_deg) return false;
    }
    return true;
  }
  bool concentric(const std::vector<int>& m) const {
    if (std::all_of(m.begin(), m.end(), [&](int r) { return has_centre(r); })) return concentric_centres(m);
    return coaxial(m);
  }
  bool equal_radius(const std::vector<int>& m) const {
    for (int r : m)
      if (!radius(r)) return false;
    for (int r : m) {
      const double a = *radius(r), b = *radius(m[0]);
      if (std::abs(a - b) > tol.radius_rel * std::max(a, b)) return false;
    }
    return true;
  }
  bool equal_length(const std::vector<int>& m) const {
    for (int r : m)
      if (shape(r).type != ShapeType::line) return false;
    for (int r : m) {
      const double a = shape(r).length, b = shape(m[0]).length;
      if (std::abs(a - b) > tol.radius_rel * std::max(a, b)) return false;
    }
    return true;
  }
  bool collinear(const std::vector<int>& m) const {
    if (!std::all_of(m.begin(), m.end(), [&](int r) { return shape(r).type == ShapeType::line; })) return coaxial(m);
    const Shape& s0 = shape(m[0]);
    for (int r : m) {
      const Shape& s = shape(r);
      if (axis_angle_deg(s.dir, s0.dir) > tol.angle_deg) return false;
      if (point_line_distance(s.point, s0.point, s0.dir) > tol.position_mm ||
          point_line_distance(line_end(s), s0.point, s0.dir) > tol.position_mm)
        return false;
    }
    return true;
  }
  // Angle between the two features' normals (across their common truth edge when they have
  // one; between their directions otherwise), folded into [0, 90].
  std::optional<double> folded_angle(int a, int b) const {
    if (!is_line(a) && !is_line(b)) {
      const auto it = truth.primitive_edges.find({std::min(a, b), std::max(a, b)});
      if (it != truth.primitive_edges.end()) {
        const double x = angle_deg(oriented_normal(feature(a), it->second), oriented_normal(feature(b), it->second));
        return std::min(x, 180 - x);
      }
    }
    const char ca = dir_class(a), cb = dir_class(b);
    if (!ca || !cb) return std::nullopt;
    const double x = axis_angle_deg(shape(a).dir, shape(b).dir);
    return ca == cb ? x : 90 - x;
  }
  bool connected(int a, int b) const {
    if (!is_line(a) && !is_line(b)) return truth.primitive_edges.count({std::min(a, b), std::max(a, b)}) > 0;
    if (is_line(a) && !is_line(b)) std::swap(a, b);
    CurveSamples sb;
    sample_curve(shape(b), tol.line_step_mm, sb);
    if (is_line(a)) {  // two curves touch
      CurveSamples sa;
      sample_curve(shape(a), tol.line_step_mm, sa);
      for (const auto& p : sa.points)
        for (const auto& q : sb.points)
          if ((p - q).norm() <= tol.position_mm + tol.line_step_mm) return true;
      return false;
    }
    // a curve on the boundary of a primitive's face: all of it on the face's region
    for (const auto& p : sb.points)
      if (!(regions.distance(a, p, tol.position_mm) <= tol.position_mm)) return false;
    return true;
  }

  // nullopt: a kind this evaluation cannot check (equal_angle, symmetric, fixed_angle without value).
  std::optional<bool> holds(ConstraintKind kind, const std::vector<int>& m, std::optional<double> value) const {
    if (m.size() < 2) return false;
    auto all_pairs = [&](auto&& pred) {
      for (std::size_t i = 0; i < m.size(); ++i)
        for (std::size_t j = i + 1; j < m.size(); ++j)
          if (!pred(m[i], m[j])) return false;
      return true;
    };
    switch (kind) {
      case ConstraintKind::parallel:
        return all_pairs([&](int a, int b) { return parallel(a, b); });
      case ConstraintKind::perpendicular:
        return all_pairs([&](int a, int b) { return perpendicular(a, b); });
      case ConstraintKind::coaxial:
        return coaxial(m);
      case ConstraintKind::concentric:
        return concentric(m);
      case ConstraintKind::equal_radius:
        return equal_radius(m);
      case ConstraintKind::equal_length:
        return equal_length(m);
      case ConstraintKind::collinear:
        return collinear(m);
      case ConstraintKind::fixed_angle: {
        if (!value) return std::nullopt;
        const double v = std::min(std::abs(*value), 180 - std::abs(*value));
        return all_pairs([&](int a, int b) {
          const auto x = folded_angle(a, b);
          return x && std::abs(*x - v) <= tol.angle_deg;
        });
      }
      case ConstraintKind::connected: {
        Dsu dsu(m.size());
        for (std::size_t i = 0; i < m.size(); ++i)
          for (std::size_t j = i + 1; j < m.size(); ++j)
            if (connected(m[i], m[j])) dsu.unite(int(i), int(j));
        for (std::size_t i = 1; i < m.size(); ++i)
          if (dsu.find(int(i)) != dsu.find(0)) return false;
        return true;
      }
      default:
        return std::nullopt;
    }
  }
};

std::string describe(ConstraintKind kind, const std::vector<std::string>& names) {
  std::string s = std::string(features::constraint_name(kind)) + "(";
  const std::size_t shown = names.size() > 8 ? 6 : names.size();
  for (std::size_t i = 0; i < shown; ++i) s += (i ? "," : "") + names[i];
  if (shown < names.size()) s += ",… " + std::to_string(names.size()) + " members";
  return s + ")";
}

ConstraintMetrics evaluate_constraints(const features::FeatureSet& fs, const std::map<std::string, int>& to_truth,
                                       const TruthRefs& refs) {
  ConstraintMetrics m;
  const Truth& truth = refs.truth;
  const int n_refs = int(truth.primitives.size() + truth.lines.size());
  std::map<std::string, int> truth_index;
  for (int r = 0; r < n_refs; ++r) truth_index[refs.id(r)] = r;

  // Precision: each detected constraint group.
  struct Mapped {
    ConstraintKind kind;
    std::vector<int> refs;
  };
  std::vector<Mapped> mapped;
  for (const auto& g : fs.groups) {
    if (g.kind != "constraint" || !g.constraint) continue;
    ++m.detected;
    const ConstraintKind kind = *g.constraint;
    std::vector<int> r;
    std::vector<std::string> names, missing;
    for (const auto& id : g.members) {
      const auto it = to_truth.find(id);
      if (it == to_truth.end()) {
        missing.push_back(id);
        names.push_back(id + "→?");
      } else {
        r.push_back(it->second);
        names.push_back(id + "→" + refs.id(it->second));
      }
    }
    mapped.push_back({kind, r});
    const bool checkable = kind != ConstraintKind::equal_angle && kind != ConstraintKind::symmetric &&
                           !(kind == ConstraintKind::fixed_angle && !g.value);
    if (!checkable) continue;
    ++m.checked;
    if (!missing.empty()) {
      ++m.unmapped;
      m.wrong.push_back(g.id + " " + describe(kind, names) + ": unmapped member(s)");
      continue;
    }
    const auto ok = refs.holds(kind, r, g.value);
    if (ok && *ok)
      ++m.correct;
    else
      m.wrong.push_back(g.id + " " + describe(kind, names) + (g.value ? " value " + std::to_string(*g.value) : "") +
                        ": does not hold on the truth shapes");
  }
  m.precision = m.checked ? double(m.correct) / m.checked : 1.0;

  // Recall: the truth constraints as implied pairs.
  std::map<ConstraintKind, std::set<std::pair<int, int>>> truth_pairs;
  std::map<ConstraintKind, Dsu> truth_classes;
  for (const auto& c : truth.constraints) {
    std::vector<int> r;
    for (const auto& id : c.members) r.push_back(truth_index.at(id));
    if (is_equivalence(c.kind)) {
      auto& dsu = truth_classes.try_emplace(c.kind, n_refs).first->second;
      for (int x : r) dsu.unite(x, r[0]);
    } else {
      for (std::size_t i = 0; i < r.size(); ++i)
        for (std::size_t j = i + 1; j < r.size(); ++j)
          truth_pairs[c.kind].insert({std::min(r[i], r[j]), std::max(r[i], r[j])});
    }
  }
  for (auto& [kind, dsu] : truth_classes)
    for (int a = 0; a < n_refs; ++a)
      for (int b = a + 1; b < n_refs; ++b)
        if (dsu.find(a) == dsu.find(b)) truth_pairs[kind].insert({a, b});

  std::map<ConstraintKind, Dsu> det_classes;
  for (const auto& g : mapped)
    if (is_equivalence(g.kind) && !g.refs.empty()) {
      auto& dsu = det_classes.try_emplace(g.kind, n_refs).first->second;
      for (int x : g.refs) dsu.unite(x, g.refs[0]);
    }
  Dsu det_parallel = det_classes.count(ConstraintKind::parallel) ? det_classes.at(ConstraintKind::parallel) : Dsu(n_refs);
  std::map<ConstraintKind, std::set<std::pair<int, int>>> det_pairs;  // direct kinds, both orders
  for (const auto& g : mapped) {
    if (is_equivalence(g.kind)) continue;
    for (std::size_t i = 0; i < g.refs.size(); ++i)
      for (std::size_t j = 0; j < g.refs.size(); ++j) {
        if (i == j) continue;
        int a = g.refs[i], b = g.refs[j];
        // perpendicular is recalled through the detected parallel classes
        if (g.kind == ConstraintKind::perpendicular) a = det_parallel.find(a), b = det_parallel.find(b);
        det_pairs[g.kind].insert({a, b});
      }
  }
  for (const auto& [kind, pairs] : truth_pairs)
    for (const auto& [a, b] : pairs) {
      ++m.truth_pairs;
      bool ok = false;
      if (is_equivalence(kind)) {
        auto it = det_classes.find(kind);
        ok = it != det_classes.end() && it->second.find(a) == it->second.find(b);
      } else {
        const auto it = det_pairs.find(kind);
        const int x = kind == ConstraintKind::perpendicular ? det_parallel.find(a) : a;
        const int y = kind == ConstraintKind::perpendicular ? det_parallel.find(b) : b;
        ok = it != det_pairs.end() && it->second.count({x, y});
      }
      if (ok) {
        ++m.recalled_pairs;
        m.recalled.push_back(describe(kind, {refs.id(a), refs.id(b)}));
      } else {
        m.missed.push_back(describe(kind, {refs.id(a), refs.id(b)}));
      }
    }
  m.recall = m.truth_pairs ? double(m.recalled_pairs) / m.truth_pairs : 1.0;
  return m;
}

}  // namespace

double shape_distance(const Shape& s, const Vector3d& p) {
  const Vector3d d = unit_or_z(s.dir);
  switch (s.type) {
    case ShapeType::plane:
      return std::abs((p - s.point).dot(d));
    case ShapeType::cylinder:
      return std::abs(point_line_distance(p, s.point, d) - s.radius);
    case ShapeType::sphere:
      return std::abs((p - s.point).norm() - s.radius);
    case ShapeType::cone: {
      const Vector3d v = p - s.point;
      const double along = v.dot(d), radial = (v - along * d).norm(), a = to_rad(s.half_angle_deg);
      if (along * std::cos(a) + radial * std::sin(a) < 0) return v.norm();  // behind the apex
      return std::abs(radial * std::cos(a) - along * std::sin(a));
    }
    case ShapeType::line:
    case ShapeType::circle:
    case ShapeType::arc:
      return curve_distance(s, p);
    default:
      return kInf;
  }
}

// ----------------------------------------------------------------------------- PointGrid
PointGrid::PointGrid(std::vector<Vector3d> points, double cell) : points_(std::move(points)), cell_(cell) {
  if (!(cell_ > 0)) throw InvalidInput("PointGrid: cell must be positive");
  cells_.reserve(points_.size());
  for (std::size_t i = 0; i < points_.size(); ++i) {
    const Vector3d& p = points_[i];
    cells_[key(long(std::floor(p.x() / cell_)), long(std::floor(p.y() / cell_)), long(std::floor(p.z() / cell_)))]
        .push_back(int(i));
  }
}

std::uint64_t PointGrid::key(long x, long y, long z) const {
  constexpr long kOff = 1L << 20;
  auto u = [](long v) { return std::uint64_t(v + kOff) & ((1ull << 21) - 1); };
  return (u(x) << 42) | (u(y) << 21) | u(z);
}

template <class F>
bool PointGrid::visit(const Vector3d& p, double radius, F&& f) const {
  const long r = long(std::ceil(radius / cell_));
  const long cx = long(std::floor(p.x() / cell_)), cy = long(std::floor(p.y() / cell_)),
             cz = long(std::floor(p.z() / cell_));
  const double r2 = radius * radius;
  for (long x = cx - r; x <= cx + r; ++x)
    for (long y = cy - r; y <= cy + r; ++y)
      for (long z = cz - r; z <= cz + r; ++z) {
        const auto it = cells_.find(key(x, y, z));
        if (it == cells_.end()) continue;
        for (int i : it->second)
          if ((points_[i] - p).squaredNorm() <= r2 && f(i)) return true;
      }
  return false;
}

std::vector<int> PointGrid::within(const Vector3d& p, double radius) const {
  std::vector<int> out;
  visit(p, radius, [&](int i) {
    out.push_back(i);
    return false;
  });
  return out;
}

bool PointGrid::any_within(const Vector3d& p, double radius) const {
  return visit(p, radius, [](int) { return true; });
}

// ----------------------------------------------------------------------------- truth
Truth read_truth(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw IoError(path.string() + ": cannot open");
  std::stringstream ss;
  ss << in.rdbuf();
  json j;
  try {
    j = json::parse(ss.str());
  } catch (const json::exception& e) {
    bad(path.string(), std::string("not JSON: ") + e.what());
  }
  const std::string where = path.string();
  if (text(j, "format", where) != "scan2cad.truth/1") bad(where, "format is not scan2cad.truth/1");
  Truth t;
  t.part = j.value("part", path.stem().string());
  std::set<std::string> ids;
  auto read_features = [&](const char* k, std::vector<TruthFeature>& out, bool surfaces) {
    const json& arr = key(j, k, where);
    if (!arr.is_array()) bad(where + "." + k, "not an array");
    for (std::size_t i = 0; i < arr.size(); ++i) {
      const std::string w = where + "." + k + "[" + std::to_string(i) + "]";
      TruthFeature f;
      f.id = text(arr[i], "id", w);
      if (!ids.insert(f.id).second) bad(w, "duplicate id \"" + f.id + "\"");
      f.shape = parse_shape(key(arr[i], "shape", w), w + ".shape");
      if (features::is_surface(f.shape.type) != surfaces) bad(w, "shape type not allowed here");
      f.inward = arr[i].value("inward", false);
      out.push_back(f);
    }
  };
  read_features("primitives", t.primitives, true);
  read_features("lines", t.lines, false);
  const json& cons = key(j, "constraints", where);
  if (!cons.is_array()) bad(where + ".constraints", "not an array");
  for (std::size_t i = 0; i < cons.size(); ++i) {
    const std::string w = where + ".constraints[" + std::to_string(i) + "]";
    TruthConstraint c;
    const std::string kind = text(cons[i], "kind", w);
    try {
      c.kind = features::constraint_kind(kind);
    } catch (const InvalidInput&) {
      bad(w + ".kind", "unknown constraint kind \"" + kind + "\"");
    }
    const json& mem = key(cons[i], "members", w);
    if (!mem.is_array() || mem.size() < 2) bad(w + ".members", "not an array of at least 2 ids");
    for (const auto& x : mem) {
      if (!x.is_string() || !ids.count(x.get<std::string>())) bad(w + ".members", "unknown id " + x.dump());
      c.members.push_back(x.get<std::string>());
    }
    if (cons[i].contains("value")) c.value = number(cons[i], "value", w);
    t.constraints.push_back(c);
  }
  if (j.contains("bbox")) t.diagonal = (vec3(j["bbox"], "max", where + ".bbox") - vec3(j["bbox"], "min", where + ".bbox")).norm();

  // The truth mesh and which primitive claims each of its triangles (README "Verification").
  if (j.contains("mesh")) {
    const fs::path mp = path.parent_path() / text(j, "mesh", where);
    if (fs::exists(mp)) {
      t.mesh = read_soup(mp);
      t.mesh_labels.assign(t.mesh.faces.size(), -1);
      for (std::size_t f = 0; f < t.mesh.faces.size(); ++f) {
        const auto& tri = t.mesh.faces[f];
        const Vector3d &a = t.mesh.vertices[tri[0]], &b = t.mesh.vertices[tri[1]], &c = t.mesh.vertices[tri[2]];
        const Vector3d n = (b - a).cross(c - a), centroid = (a + b + c) / 3.0;
        for (std::size_t i = 0; i < t.primitives.size(); ++i) {
          const Shape& s = t.primitives[i].shape;
          if (std::max({shape_distance(s, a), shape_distance(s, b), shape_distance(s, c)}) > 0.01) continue;
          if (angle_deg(n, oriented_normal(t.primitives[i], centroid)) > 10.0) continue;
          t.mesh_labels[f] = int(i);
          break;
        }
      }
      std::unordered_map<std::uint64_t, std::vector<int>> edge_faces;
      for (std::size_t f = 0; f < t.mesh.faces.size(); ++f)
        for (int k = 0; k < 3; ++k)
          edge_faces[undirected_edge_key(t.mesh.faces[f][k], t.mesh.faces[f][(k + 1) % 3])].push_back(int(f));
      for (const auto& [ek, fl] : edge_faces) {
        if (fl.size() != 2) continue;
        const int a = t.mesh_labels[fl[0]], b = t.mesh_labels[fl[1]];
        if (a < 0 || b < 0 || a == b) continue;
        const Vector3d mid = 0.5 * (t.mesh.vertices[int(ek >> 32)] + t.mesh.vertices[int(ek & 0xffffffffu)]);
        t.primitive_edges.try_emplace({std::min(a, b), std::max(a, b)}, mid);
      }
      if (t.diagonal == 0) t.diagonal = bounds(t.mesh).diagonal();
    }
  }
  return t;
}

// ----------------------------------------------------------------------------- labelling
std::vector<int> label_faces(const Mesh& mesh, const Truth& truth, const Tolerances& tol) {
  const TruthRegions regions(truth);
  std::vector<int> labels(mesh.n_faces(), -1);
  parallel_for(mesh.n_faces(), [&](std::size_t fi) {
    const auto p = face_points(mesh, Mesh::FaceHandle(int(fi)));
    const Vector3d c = (p[0] + p[1] + p[2]) / 3.0, n = (p[1] - p[0]).cross(p[2] - p[0]);
    int best = -1, any = -1;
    double best_d = kInf, any_d = kInf;
    for (std::size_t i = 0; i < truth.primitives.size(); ++i) {
      if (shape_distance(truth.primitives[i].shape, c) > tol.label_max_mm) continue;  // region is farther still
      const double d = regions.distance(int(i), c, tol.label_max_mm);
      if (!(d <= tol.label_max_mm)) continue;
      if (d < any_d) any_d = d, any = int(i);
      if (n.norm() > 0 && angle_deg(n, oriented_normal(truth.primitives[i], c)) <= tol.label_normal_deg && d < best_d)
        best_d = d, best = int(i);
    }
    labels[fi] = best >= 0 ? best : any;
  });
  return labels;
}

// ----------------------------------------------------------------------------- primitives
PrimitiveMetrics evaluate_surfaces(const Mesh& mesh, const std::vector<DetectedSurface>& surfaces, const Truth& truth,
                                   const std::vector<int>& labels, const Tolerances& tol) {
  PrimitiveMetrics m;
  const std::size_t nf = mesh.n_faces();
  if (labels.size() != nf) throw InvalidInput("evaluate_surfaces: labels do not match the mesh");
  const std::vector<double> area = face_areas(mesh);
  m.truth = int(truth.primitives.size());
  m.detected = int(surfaces.size());

  std::vector<int> face_surface(nf, -1);
  std::vector<std::map<int, double>> overlap(surfaces.size());
  for (std::size_t s = 0; s < surfaces.size(); ++s)
    for (int f : surfaces[s].faces) {
      if (f < 0 || std::size_t(f) >= nf)
        throw InvalidInput("surface " + surfaces[s].id + ": face " + std::to_string(f) + " not in the mesh");
      if (face_surface[f] < 0) face_surface[f] = int(s);
      if (labels[f] >= 0) overlap[s][labels[f]] += area[f];
    }

  struct Cand {
    double overlap, score;
    int t, s;
  };
  std::vector<Cand> cands;
  for (std::size_t s = 0; s < surfaces.size(); ++s)
    for (const auto& [t, a] : overlap[s]) {
      const ShapeMatch sm = match_surface(truth.primitives[t].shape, surfaces[s].shape, tol);
      if (sm.ok && a > 0) cands.push_back({a, sm.score, t, int(s)});
    }
  std::sort(cands.begin(), cands.end(), [](const Cand& a, const Cand& b) {
    return a.overlap != b.overlap ? a.overlap > b.overlap : a.score < b.score;
  });
  std::vector<int> truth_surface(truth.primitives.size(), -1);
  m.surface_truth.assign(surfaces.size(), -1);
  for (const auto& c : cands) {
    if (truth_surface[c.t] >= 0 || m.surface_truth[c.s] >= 0) continue;
    truth_surface[c.t] = c.s;
    m.surface_truth[c.s] = c.t;
    m.matches.emplace_back(truth.primitives[c.t].id, surfaces[c.s].id);
  }
  m.matched = int(m.matches.size());
  for (std::size_t t = 0; t < truth.primitives.size(); ++t)
    if (truth_surface[t] < 0) m.missed.push_back(truth.primitives[t].id);
  m.recall = m.truth ? double(m.matched) / m.truth : 1.0;
  // Surfaces left over that still satisfy every tolerance against a truth primitive they
  // overlap (a face split in two) map to it for the constraints; they do not add to recall.
  const std::vector<int> one_to_one = m.surface_truth;
  std::vector<double> best_score(surfaces.size(), kInf);
  for (const auto& c : cands)
    if (one_to_one[c.s] < 0 && c.score < best_score[c.s]) {
      best_score[c.s] = c.score;
      m.surface_truth[c.s] = c.t;
    }

  std::vector<double> truth_area(truth.primitives.size(), 0.0);
  for (std::size_t f = 0; f < nf; ++f)
    if (labels[f] >= 0) truth_area[labels[f]] += area[f];
  std::vector<char> found(truth.primitives.size(), 0);
  for (std::size_t s = 0; s < surfaces.size(); ++s)
    for (const auto& [t, a] : overlap[s])
      if (surfaces[s].shape.type == truth.primitives[t].shape.type && a >= 0.5 * truth_area[t]) found[t] = 1;
  m.found = int(std::count(found.begin(), found.end(), 1));

  double labelled = 0, right = 0, total = 0;
  for (std::size_t f = 0; f < nf; ++f) {
    total += area[f];
    if (labels[f] < 0) continue;
    labelled += area[f];
    if (face_surface[f] >= 0 && surfaces[face_surface[f]].shape.type == truth.primitives[labels[f]].shape.type)
      right += area[f];
  }
  m.type_accuracy = labelled > 0 ? right / labelled : 0.0;
  m.labelled_share = total > 0 ? labelled / total : 0.0;
  return m;
}

// ----------------------------------------------------------------------------- everything
FeatureMetrics evaluate(const Mesh& mesh, const features::FeatureSet& fs, const Truth& truth, const Tolerances& tol) {
  FeatureMetrics out;
  const std::vector<int> labels = label_faces(mesh, truth, tol);
  std::vector<DetectedSurface> surfaces;
  for (const auto& p : fs.patches) surfaces.push_back({p.id, p.shape, p.faces});
  out.primitives = evaluate_surfaces(mesh, surfaces, truth, labels, tol);

  std::vector<DetectedLine> lines;
  for (const auto& l : fs.lines) {
    DetectedLine d{l.id, l.shape, {}, l.closed};
    for (int v : l.vertices) {
      if (v < 0 || std::size_t(v) >= mesh.n_vertices())
        throw InvalidInput("line " + l.id + ": vertex " + std::to_string(v) + " not in the mesh");
      d.polyline.push_back(to_eigen(mesh.point(Mesh::VertexHandle(v))));
    }
    lines.push_back(std::move(d));
  }
  out.lines = evaluate_lines(lines, truth, tol);

  // Detected ids → truth features: the primitive matches (and their leftovers), lines by shape.
  std::map<std::string, int> to_truth;
  for (std::size_t s = 0; s < surfaces.size(); ++s)
    if (out.primitives.surface_truth[s] >= 0) to_truth[surfaces[s].id] = out.primitives.surface_truth[s];
  const int np = int(truth.primitives.size());
  for (const auto& l : lines) {
    double best = kInf;
    for (std::size_t t = 0; t < truth.lines.size(); ++t) {
      const ShapeMatch sm = match_curve(truth.lines[t].shape, l.shape, tol);
      if (sm.ok && sm.score < best) best = sm.score, to_truth[l.id] = np + int(t);
    }
  }
  const TruthRegions regions(truth);
  const TruthRefs refs{truth, regions, tol};
  out.constraints = evaluate_constraints(fs, to_truth, refs);
  return out;
}

// ----------------------------------------------------------------------------- self-check input
features::FeatureSet truth_as_features(const Truth& truth, Mesh& mesh) {
  if (truth.mesh.empty()) throw InvalidInput("truth_as_features: the truth has no mesh");
  mesh.clear();
  soup_to_mesh(truth.mesh, mesh);
  mesh.update_normals();
  features::FeatureSet fs;
  fs.mesh_vertices = int(mesh.n_vertices());
  fs.mesh_faces = int(mesh.n_faces());
  std::map<std::string, std::string> ids;
  const std::vector<double> area = face_areas(mesh);
  for (std::size_t i = 0; i < truth.primitives.size(); ++i) {
    features::Patch p;
    p.id = "P" + std::to_string(i);
    p.shape = truth.primitives[i].shape;
    for (std::size_t f = 0; f < truth.mesh_labels.size(); ++f)
      if (truth.mesh_labels[f] == int(i)) {
        p.faces.push_back(int(f));
        p.area += area[f];
      }
    ids[truth.primitives[i].id] = p.id;
    fs.patches.push_back(std::move(p));
  }
  for (std::size_t j = 0; j < truth.lines.size(); ++j) {
    const Shape& s = truth.lines[j].shape;
    features::Line l;
    l.id = "L" + std::to_string(j);
    l.shape = s;
    l.closed = s.type == ShapeType::circle;
    std::vector<std::pair<double, int>> on;
    const auto [u, v] = basis(s.dir);
    for (std::size_t k = 0; k < truth.mesh.vertices.size(); ++k) {
      const Vector3d& p = truth.mesh.vertices[k];
      if (curve_distance(s, p) > 1e-3) continue;
      const Vector3d w = p - s.point;
      on.emplace_back(s.type == ShapeType::line ? w.dot(s.dir) : std::atan2(w.dot(v), w.dot(u)), int(k));
    }
    std::sort(on.begin(), on.end());
    for (const auto& x : on) l.vertices.push_back(x.second);
    ids[truth.lines[j].id] = l.id;
    fs.lines.push_back(std::move(l));
  }
  for (std::size_t k = 0; k < truth.constraints.size(); ++k) {
    const auto& c = truth.constraints[k];
    features::Group g;
    g.id = "G" + std::to_string(k);
    g.kind = "constraint";
    g.constraint = c.kind;
    g.value = c.value;
    for (const auto& id : c.members) g.members.push_back(ids.at(id));
    fs.groups.push_back(std::move(g));
  }
  return fs;
}

// ----------------------------------------------------------------------------- inputs
Mesh refine_mesh(const Mesh& input, double max_edge) {
  Mesh m = input;
  using Item = std::pair<double, int>;
  std::priority_queue<Item> queue;  // every edge's current length has an entry; stale ones are skipped
  // Lawson flips towards Delaunay between coplanar faces (the OpenSCAD triangulation of a flat
  // face is full of slivers, which bisection alone would keep: it preserves the smallest angle).
  const double cos_flat = std::cos(to_rad(0.5));
  auto should_flip = [&](Mesh::EdgeHandle e) {
    if (m.is_boundary(e)) return false;
    const auto h0 = m.halfedge_handle(e, 0), h1 = m.halfedge_handle(e, 1);
    const Vector3d a = to_eigen(m.point(m.from_vertex_handle(h0))), b = to_eigen(m.point(m.to_vertex_handle(h0)));
    const Vector3d c = to_eigen(m.point(m.to_vertex_handle(m.next_halfedge_handle(h0))));
    const Vector3d d = to_eigen(m.point(m.to_vertex_handle(m.next_halfedge_handle(h1))));
    const Vector3d n0 = (b - a).cross(c - a), n1 = (a - b).cross(d - b);
    if (n0.norm() == 0 || n1.norm() == 0 || n0.normalized().dot(n1.normalized()) < cos_flat) return false;
    if (angle_deg(a - c, b - c) + angle_deg(a - d, b - d) <= 180.0 + 1e-9) return false;
    return m.is_flip_ok(e);
  };
  auto legalize = [&](std::vector<Mesh::EdgeHandle> stack) {
    for (int budget = 100000; !stack.empty() && budget > 0; --budget) {
      const auto e = stack.back();
      stack.pop_back();
      if (!should_flip(e)) continue;
      const auto h0 = m.halfedge_handle(e, 0), h1 = m.halfedge_handle(e, 1);
      const std::array<Mesh::HalfedgeHandle, 4> outer = {m.next_halfedge_handle(h0), m.prev_halfedge_handle(h0),
                                                        m.next_halfedge_handle(h1), m.prev_halfedge_handle(h1)};
      m.flip(e);
      queue.emplace(m.calc_edge_length(e), e.idx());
      for (auto h : outer) stack.push_back(m.edge_handle(h));
    }
  };
  {
    std::vector<Mesh::EdgeHandle> all(m.edges().begin(), m.edges().end());
    for (int pass = 0; pass < 20; ++pass) legalize(all);
  }
  for (auto e : m.edges()) queue.emplace(m.calc_edge_length(e), e.idx());
  // Longest-edge bisection, globally longest first (so the split edge is the longest of both its
  // triangles), each midpoint followed by local Delaunay flips as in incremental insertion.
  while (!queue.empty()) {
    const auto [len, idx] = queue.top();
    queue.pop();
    if (len <= max_edge) break;
    const Mesh::EdgeHandle e(idx);
    if (m.calc_edge_length(e) != len) continue;  // stale
    const auto h = m.halfedge_handle(e, 0);
    const auto v = m.add_vertex(0.5 * (m.point(m.from_vertex_handle(h)) + m.point(m.to_vertex_handle(h))));
    m.split(e, v);
    std::vector<Mesh::EdgeHandle> link;
    for (auto oh : m.voh_range(v)) {
      queue.emplace(m.calc_edge_length(m.edge_handle(oh)), m.edge_handle(oh).idx());
      if (!m.is_boundary(oh)) link.push_back(m.edge_handle(m.next_halfedge_handle(oh)));
    }
    legalize(link);
  }
  m.update_normals();
  return m;
}

double mean_edge_length(const Mesh& mesh) {
  double sum = 0;
  std::size_t n = 0;
  for (auto e : mesh.edges()) {
    sum += mesh.calc_edge_length(e);
    ++n;
  }
  return n ? sum / double(n) : 0.0;
}

void add_noise(Mesh& mesh, double sigma, std::uint64_t seed) {
  Rng rng{seed};
  auto gauss = [&] {
    const double u1 = std::max(rng.uniform(), 1e-300), u2 = rng.uniform();
    return std::sqrt(-2 * std::log(u1)) * std::cos(2 * kPi * u2);
  };
  for (auto v : mesh.vertices()) {
    auto p = mesh.point(v);
    for (int k = 0; k < 3; ++k) p[k] += sigma * gauss();
    mesh.set_point(v, p);
  }
  mesh.update_normals();
}

std::string input_label(const SweepInput& in) {
  if (in.input == "OpenSCAD") return "OpenSCAD (clean CAD)";
  char label[64];
  std::snprintf(label, sizeof label, "refined h=%.3f", in.h);
  return label;
}

std::vector<SweepInput> sweep_inputs(const fs::path& stl, const std::vector<double>& sigmas, double div,
                                     std::uint64_t seed) {
  std::vector<SweepInput> out;
  Mesh cad = read_mesh(stl);
  cad.update_normals();
  const std::string part = stl.stem().string();
  SweepInput clean;
  clean.part = part;
  clean.input = "OpenSCAD";
  clean.h = mean_edge_length(cad);
  clean.line_tol_mm = 0.5;
  clean.mesh = cad;
  out.push_back(std::move(clean));
  const Mesh fine = refine_mesh(cad, bounds(cad).diagonal() / div);
  const double h = mean_edge_length(fine);
  for (std::size_t k = 0; k < sigmas.size(); ++k) {
    SweepInput in;
    in.part = part;
    in.input = "refined";
    in.sigma_rel = sigmas[k];
    in.h = h;
    in.sigma_mm = sigmas[k] * h;
    in.line_tol_mm = std::max(0.5, 1.5 * h);
    in.mesh = fine;
    if (in.sigma_mm > 0) add_noise(in.mesh, in.sigma_mm, seed + k);
    out.push_back(std::move(in));
  }
  return out;
}

OrientedSamples sample_oriented(const Mesh& mesh, std::size_t n, std::uint64_t seed) {
  const std::vector<double> area = face_areas(mesh);
  std::vector<double> cdf(area.size());
  std::partial_sum(area.begin(), area.end(), cdf.begin());
  if (cdf.empty() || cdf.back() <= 0) throw InvalidInput("sample_oriented: the mesh has zero area");
  OrientedSamples out;
  Rng rng{seed};
  for (std::size_t i = 0; i < n; ++i) {
    const double r = rng.uniform() * cdf.back();
    const std::size_t f = std::min<std::size_t>(std::upper_bound(cdf.begin(), cdf.end(), r) - cdf.begin(), cdf.size() - 1);
    const auto p = face_points(mesh, Mesh::FaceHandle(int(f)));
    const double s = std::sqrt(rng.uniform()), u = rng.uniform();
    out.points.push_back((1 - s) * p[0] + s * (1 - u) * p[1] + s * u * p[2]);
    out.normals.push_back(unit_or_z((p[1] - p[0]).cross(p[2] - p[0])));
    out.faces.push_back(int(f));
  }
  return out;
}

}  // namespace s2c::bench
