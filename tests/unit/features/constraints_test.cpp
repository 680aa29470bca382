// Constraint detection on feature sets built by hand from the fixture parts' ground truth
// (fixtures/parts/*.truth.json: the primitives become patches, the lines lines, the faces named by
// each line adjacent): every truth constraint must be implied by the output (groups expanded into
// pairs, perpendicular through the parallel classes), and every emitted constraint must hold when
// recomputed here. Then tolerances, adjacency, redundancy, ids and bad input.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <vector>

#include <Eigen/Geometry>
#include <nlohmann/json.hpp>

#include "s2c/core/clock.h"
#include "s2c/core/disjoint_sets.h"
#include "s2c/features/constraints.h"

namespace s2c::features {
namespace {

using Eigen::Vector3d;
using nlohmann::json;
constexpr double kPi = 3.14159265358979323846;

Vector3d vec3(const json& j) { return {j[0].get<double>(), j[1].get<double>(), j[2].get<double>()}; }

Shape make_shape(ShapeType type, Vector3d point, Vector3d dir, double radius = 0, double length = 0,
                 double half_angle = 0) {
  Shape s;
  s.type = type;
  s.point = point;
  s.dir = dir.normalized();
  s.radius = radius;
  s.length = length;
  s.half_angle_deg = half_angle;
  return s;
}

Shape truth_shape(const json& j) {
  const std::string t = j["type"];
  if (t == "plane") return make_shape(ShapeType::plane, vec3(j["point"]), vec3(j["normal"]));
  if (t == "cylinder") return make_shape(ShapeType::cylinder, vec3(j["axis_point"]), vec3(j["axis_dir"]), j["radius"]);
  if (t == "sphere") return make_shape(ShapeType::sphere, vec3(j["center"]), Vector3d::UnitZ(), j["radius"]);
  if (t == "cone")
    return make_shape(ShapeType::cone, vec3(j["apex"]), vec3(j["axis_dir"]), 0, 0, j["half_angle_deg"].get<double>());
  if (t == "line") return make_shape(ShapeType::line, vec3(j["point"]), vec3(j["direction"]), 0, j["length"]);
  if (t == "circle") return make_shape(ShapeType::circle, vec3(j["center"]), vec3(j["normal"]), j["radius"]);
  ADD_FAILURE() << "unknown truth shape " << t;
  return {};
}

/// A fixture part as a FeatureSet: truth names ↔ feature ids, and its truth constraints.
struct Part {
  FeatureSet f;
  std::map<std::string, std::string> id, name;  // truth name → feature id, feature id → truth name
  json constraints;
  double diagonal = 1.0;

  Shape& shape(const std::string& n) {
    const std::string& i = id.at(n);
    for (auto& p : f.patches)
      if (p.id == i) return p.shape;
    for (auto& l : f.lines)
      if (l.id == i) return l.shape;
    throw std::out_of_range(n);
  }
  void adjacent(const std::string& a, const std::string& b) { f.adjacency.emplace_back(id.at(a), id.at(b)); }
  bool has_adjacency(const std::string& a, const std::string& b) const {
    for (const auto& [x, y] : f.adjacency)
      if ((x == id.at(a) && y == id.at(b)) || (x == id.at(b) && y == id.at(a))) return true;
    return false;
  }
};

/// Areas (mm²) of the parts' faces, from their dimensions (fixtures/parts/README.md).
std::map<std::string, double> areas(const std::string& part) {
  const double pi = kPi;
  if (part == "plate")
    return {{"top", 2400 - 72 * pi}, {"bottom", 2400 - 72 * pi}, {"side_xp", 320}, {"side_xn", 320},
            {"side_yp", 480},        {"side_yn", 480},           {"hole_0", 48 * pi}, {"hole_1", 48 * pi},
            {"hole_2", 48 * pi},     {"hole_3", 48 * pi},        {"hole_center", 96 * pi}};
  if (part == "shaft")
    return {{"end", 64 * pi}, {"chamfer", pi * 18 * 2 * std::sqrt(2.0)}, {"shaft_body", 760 * pi}, {"tip", 200 * pi}};
  if (part == "pocket")
    return {{"top", 1900},           {"bottom", 2500 - 9 * pi},        {"side_xp", 1000},
            {"side_xn", 1000},       {"side_yp", 1000},                {"side_yn", 1000},
            {"pocket_floor", 600 - 36 * pi}, {"pocket_wall_xp", 160},  {"pocket_wall_xn", 160},
            {"pocket_wall_yp", 240}, {"pocket_wall_yn", 240},          {"counterbore_floor", 27 * pi},
            {"counterbore", 48 * pi}, {"hole", 48 * pi}};
  if (part == "bracket")
    return {{"bottom", 2400 - 32 * pi}, {"base_top", 2040 - 32 * pi}, {"wall_top", 360},    {"front", 360},
            {"wall_front", 2040 - 25 * pi}, {"back", 2400 - 25 * pi}, {"side_xp", 444},     {"side_xn", 444},
            {"hole_base_0", 48 * pi},   {"hole_base_1", 48 * pi},     {"hole_wall", 60 * pi}};
  return {};
}

/// Reads NAME.truth.json: primitives → patches P<i>, lines → lines L<i> (ends on shared vertex
/// ids, circles closed). A line "edge_A_B" / "rim_A_B" makes A and B adjacent and is adjacent to
/// both; a line is adjacent to every face of the lines it shares an end with (one shared vertex
/// counts), and to the lines it shares an end with.
Part load_part(const std::string& part) {
  std::ifstream in(std::string(S2C_SOURCE_DIR) + "/fixtures/parts/" + part + ".truth.json");
  EXPECT_TRUE(in.good()) << part;
  const json doc = json::parse(in);
  Part p;
  p.constraints = doc["constraints"];
  p.diagonal = (vec3(doc["bbox"]["max"]) - vec3(doc["bbox"]["min"])).norm();
  const auto area = areas(part);
  for (const auto& prim : doc["primitives"]) {
    Patch patch;
    patch.id = "P" + std::to_string(p.f.patches.size());
    patch.shape = truth_shape(prim["shape"]);
    patch.area = area.count(prim["id"]) ? area.at(prim["id"]) : 0.0;
    p.id[prim["id"]] = patch.id;
    p.name[patch.id] = prim["id"];
    p.f.patches.push_back(patch);
  }
  std::map<std::tuple<long, long, long>, int> vertex;
  auto vertex_at = [&](const Vector3d& x) {
    const auto key = std::make_tuple(std::lround(x.x() * 1e3), std::lround(x.y() * 1e3), std::lround(x.z() * 1e3));
    return vertex.emplace(key, static_cast<int>(vertex.size())).first->second;
  };
  int interior = 100000;
  std::map<std::string, std::vector<std::string>> faces_of;  // line → its two faces
  std::map<int, std::set<std::string>> at_vertex;            // vertex → lines ending there
  for (const auto& l : doc["lines"]) {
    Line line;
    line.id = "L" + std::to_string(p.f.lines.size());
    line.shape = truth_shape(l["shape"]);
    if (line.shape.type == ShapeType::line) {
      line.vertices = {vertex_at(line.shape.point), interior++,
                       vertex_at(line.shape.point + line.shape.length * line.shape.dir)};
      at_vertex[line.vertices.front()].insert(line.id);
      at_vertex[line.vertices.back()].insert(line.id);
    } else {
      line.vertices = {interior, interior + 1, interior + 2};
      interior += 3;
      line.closed = true;
    }
    const std::string n = l["id"];
    p.id[n] = line.id;
    p.name[line.id] = n;
    // The shaft's rims are not named after their faces.
    static const std::map<std::string, std::vector<std::string>> kNamedOtherwise = {
        {"rim_end", {"end", "chamfer"}}, {"rim_chamfer", {"chamfer", "shaft_body"}}};
    const std::string rest = n.substr(n.find('_') + 1);
    for (std::size_t k = rest.find('_'); k != std::string::npos; k = rest.find('_', k + 1)) {
      const std::string a = rest.substr(0, k), b = rest.substr(k + 1);
      if (area.count(a) && area.count(b)) faces_of[line.id] = {a, b};
    }
    if (kNamedOtherwise.count(n)) faces_of[line.id] = kNamedOtherwise.at(n);
    EXPECT_EQ(faces_of[line.id].size(), 2u) << n;
    p.f.lines.push_back(line);
  }
  std::set<std::pair<std::string, std::string>> adj;
  auto add = [&](const std::string& a, const std::string& b) {
    if (a != b) adj.emplace(std::min(a, b), std::max(a, b));
  };
  for (const auto& [l, faces] : faces_of) {
    if (faces.size() != 2) continue;
    add(p.id.at(faces[0]), p.id.at(faces[1]));
    for (const auto& face : faces) add(l, p.id.at(face));
  }
  for (const auto& [v, ls] : at_vertex)
    for (const auto& a : ls)
      for (const auto& b : ls) {
        add(a, b);
        for (const auto& face : faces_of[b]) add(a, p.id.at(face));
      }
  p.f.adjacency.assign(adj.begin(), adj.end());
  return p;
}

ConstraintOptions options_for(const Part& p) {
  ConstraintOptions o;
  o.diagonal = p.diagonal;
  return o;
}

std::vector<const Group*> constraints(const FeatureSet& f) {
  std::vector<const Group*> out;
  for (const auto& g : f.groups)
    if (g.kind == "constraint") out.push_back(&g);
  return out;
}

bool equivalence(ConstraintKind k) {
  return k == ConstraintKind::parallel || k == ConstraintKind::coaxial || k == ConstraintKind::equal_radius ||
         k == ConstraintKind::concentric || k == ConstraintKind::equal_length || k == ConstraintKind::collinear ||
         k == ConstraintKind::equal_angle;
}

/// The output expanded into implied relations over feature ids.
class Implied {
 public:
  explicit Implied(const FeatureSet& f) {
    for (const auto& p : f.patches) index_[p.id] = static_cast<int>(index_.size());
    for (const auto& l : f.lines) index_[l.id] = static_cast<int>(index_.size());
    for (const auto& g : f.groups) index_.emplace(g.id, static_cast<int>(index_.size()));
    for (int k = 0; k <= static_cast<int>(ConstraintKind::equal_radius); ++k) sets_.emplace_back(index_.size());
    for (const Group* g : constraints(f)) {
      const ConstraintKind k = *g->constraint;
      if (equivalence(k)) {
        for (const auto& m : g->members) sets_[static_cast<int>(k)].unite(index_.at(g->members[0]), index_.at(m));
      } else {
        pairs_.push_back({k, g->members, g->value});
      }
    }
  }
  bool holds(ConstraintKind k, const std::vector<std::string>& members, std::optional<double> value) {
    if (equivalence(k)) {
      auto& s = sets_[static_cast<int>(k)];
      for (const auto& m : members)
        if (s.find(index_.at(m)) != s.find(index_.at(members[0]))) return false;
      return true;
    }
    const std::set<std::string> want(members.begin(), members.end());
    auto& par = sets_[static_cast<int>(ConstraintKind::parallel)];
    for (const auto& e : pairs_) {
      if (e.kind != k) continue;
      if (k == ConstraintKind::perpendicular && members.size() == 2 && e.members.size() == 2) {
        const int a = par.find(index_.at(members[0])), b = par.find(index_.at(members[1]));
        const int x = par.find(index_.at(e.members[0])), y = par.find(index_.at(e.members[1]));
        if ((a == x && b == y) || (a == y && b == x)) return true;
        continue;
      }
      if (std::set<std::string>(e.members.begin(), e.members.end()) != want) continue;
      if (value && (!e.value || std::abs(*e.value - *value) > 0.5)) continue;
      return true;
    }
    return false;
  }

 private:
  struct Pair {
    ConstraintKind kind;
    std::vector<std::string> members;
    std::optional<double> value;
  };
  std::map<std::string, int> index_;
  std::vector<DisjointSets> sets_;
  std::vector<Pair> pairs_;
};

ConstraintKind kind_of(const std::string& name) {
  static const std::map<std::string, ConstraintKind> kinds = {
      {"equal_length", ConstraintKind::equal_length}, {"connected", ConstraintKind::connected},
      {"collinear", ConstraintKind::collinear},       {"parallel", ConstraintKind::parallel},
      {"concentric", ConstraintKind::concentric},     {"coaxial", ConstraintKind::coaxial},
      {"perpendicular", ConstraintKind::perpendicular}, {"fixed_angle", ConstraintKind::fixed_angle},
      {"equal_angle", ConstraintKind::equal_angle},   {"symmetric", ConstraintKind::symmetric},
      {"equal_radius", ConstraintKind::equal_radius}};
  return kinds.at(name);
}

/// Every truth constraint of the part is implied by the output.
void expect_truth_implied(const Part& p) {
  Implied implied(p.f);
  for (const auto& c : p.constraints) {
    std::vector<std::string> members;
    for (const auto& m : c["members"]) members.push_back(p.id.at(m.get<std::string>()));
    std::optional<double> value;
    if (c.contains("value")) value = c["value"].get<double>();
    EXPECT_TRUE(implied.holds(kind_of(c["kind"]), members, value)) << "not implied: " << c.dump();
  }
}

// ---- independent geometric checks of what was emitted ------------------------------------------

constexpr double kAngTol = 0.05;  // degrees: the hand-built shapes are exact
constexpr double kPosTol = 1e-6;  // mm

const Shape& shape_of(const FeatureSet& f, const std::string& id) {
  for (const auto& p : f.patches)
    if (p.id == id) return p.shape;
  for (const auto& l : f.lines)
    if (l.id == id) return l.shape;
  throw std::out_of_range(id);
}
const Group& group_of(const FeatureSet& f, const std::string& id) {
  for (const auto& g : f.groups)
    if (g.id == id) return g;
  throw std::out_of_range(id);
}
double angle_between_lines(const Vector3d& a, const Vector3d& b) {
  return std::acos(std::min(1.0, std::abs(a.normalized().dot(b.normalized())))) * 180.0 / kPi;
}
double to_line(const Vector3d& p, const Vector3d& q, const Vector3d& d) {
  const Vector3d v = p - q;
  return (v - v.dot(d.normalized()) * d.normalized()).norm();
}
std::vector<Vector3d> ends_of(const Shape& s) {
  if (s.type == ShapeType::line) return {s.point, s.point + s.length * s.dir.normalized()};
  if (s.type == ShapeType::arc) return {s.start, s.end};
  return {};
}
/// Outward-from-axis / centre unit normal of a surface at p (on it).
Vector3d normal_at(const Shape& s, const Vector3d& p) {
  const Vector3d a = s.dir.normalized();
  switch (s.type) {
    case ShapeType::plane: return a;
    case ShapeType::sphere: return (p - s.point).normalized();
    case ShapeType::cylinder: {
      const Vector3d v = p - s.point;
      return (v - v.dot(a) * a).normalized();
    }
    case ShapeType::cone: {
      const Vector3d v = p - s.point;
      const Vector3d radial = (v - v.dot(a) * a).normalized();
      const double h = s.half_angle_deg * kPi / 180;
      return std::cos(h) * radial - std::sin(h) * a;
    }
    default: return Vector3d::Zero();
  }
}
double surface_distance(const Shape& s, const Vector3d& p) {
  switch (s.type) {
    case ShapeType::plane: return std::abs(s.dir.normalized().dot(p - s.point));
    case ShapeType::sphere: return std::abs((p - s.point).norm() - s.radius);
    case ShapeType::cylinder: return std::abs(to_line(p, s.point, s.dir) - s.radius);
    case ShapeType::cone: {
      const Vector3d v = p - s.point;
      const double h = v.dot(s.dir.normalized()), r = to_line(p, s.point, s.dir);
      return std::abs(r - h * std::tan(s.half_angle_deg * kPi / 180));
    }
    default: return 1e9;
  }
}
/// Same infinite surface (and size), orientation-free.
bool same_surface(const Shape& a, const Shape& b) {
  if (a.type != b.type) return false;
  switch (a.type) {
    case ShapeType::plane:
      return angle_between_lines(a.dir, b.dir) < kAngTol && surface_distance(b, a.point) < kPosTol;
    case ShapeType::cylinder:
      return angle_between_lines(a.dir, b.dir) < kAngTol && to_line(a.point, b.point, b.dir) < kPosTol &&
             std::abs(a.radius - b.radius) < kPosTol;
    case ShapeType::sphere: return (a.point - b.point).norm() < kPosTol && std::abs(a.radius - b.radius) < kPosTol;
    case ShapeType::cone:
      return (a.point - b.point).norm() < kPosTol && a.dir.normalized().dot(b.dir.normalized()) > 0.9999 &&
             std::abs(a.half_angle_deg - b.half_angle_deg) < kAngTol;
    default: return false;
  }
}

/// The constraint holds on the (exact) shapes.
void expect_holds(const FeatureSet& f, const Group* g) {
  {
    SCOPED_TRACE(g->id + " " + std::to_string(static_cast<int>(*g->constraint)));
    const ConstraintKind k = *g->constraint;
    std::vector<const Shape*> s;
    if (k != ConstraintKind::equal_angle)
      for (const auto& m : g->members) s.push_back(&shape_of(f, m));
    ASSERT_GE(g->members.size(), 2u);
    std::set<std::string> distinct(g->members.begin(), g->members.end());
    EXPECT_EQ(distinct.size(), g->members.size());
    switch (k) {
      case ConstraintKind::parallel:
        for (const Shape* x : s) {
          EXPECT_EQ(x->type == ShapeType::cone ? ShapeType::cylinder : x->type,
                    s[0]->type == ShapeType::cone ? ShapeType::cylinder : s[0]->type);
          EXPECT_LT(angle_between_lines(x->dir, s[0]->dir), kAngTol);
        }
        break;
      case ConstraintKind::perpendicular:
        ASSERT_EQ(s.size(), 2u);
        EXPECT_NEAR(angle_between_lines(s[0]->dir, s[1]->dir), 90.0, kAngTol);
        break;
      case ConstraintKind::coaxial: {
        const Shape* axis = nullptr;
        for (const Shape* x : s)
          if (x->type != ShapeType::sphere && !axis) axis = x;
        ASSERT_NE(axis, nullptr);
        for (const Shape* x : s) {
          EXPECT_LT(to_line(x->point, axis->point, axis->dir), kPosTol);
          if (x->type != ShapeType::sphere) {
            EXPECT_LT(angle_between_lines(x->dir, axis->dir), kAngTol);
          }
        }
        break;
      }
      case ConstraintKind::equal_radius:
        for (const Shape* x : s) EXPECT_NEAR(x->radius, s[0]->radius, kPosTol);
        break;
      case ConstraintKind::concentric:
        for (const Shape* x : s) {
          EXPECT_LT((x->point - s[0]->point).norm(), kPosTol);
          EXPECT_LT(angle_between_lines(x->dir, s[0]->dir), kAngTol);
        }
        break;
      case ConstraintKind::equal_length:
        for (const Shape* x : s) EXPECT_NEAR(x->length, s[0]->length, kPosTol);
        break;
      case ConstraintKind::collinear:
        for (const Shape* x : s)
          for (const Vector3d& e : ends_of(*x)) EXPECT_LT(to_line(e, s[0]->point, s[0]->dir), kPosTol);
        break;
      case ConstraintKind::connected: {
        bool touch = false;
        for (const Vector3d& a : ends_of(*s[0]))
          for (const Vector3d& b : ends_of(*s[1])) touch |= (a - b).norm() < kPosTol;
        EXPECT_TRUE(touch);
        break;
      }
      case ConstraintKind::fixed_angle: {
        // Planes: their normals; otherwise measured at a point of a line lying on both surfaces.
        ASSERT_TRUE(g->value.has_value());
        if (s[0]->type == ShapeType::plane && s[1]->type == ShapeType::plane) {
          EXPECT_NEAR(angle_between_lines(s[0]->dir, s[1]->dir), *g->value, 0.1);
          break;
        }
        bool measured = false;
        for (const auto& l : f.lines) {
          Vector3d p;
          if (l.shape.type == ShapeType::circle) {
            p = l.shape.point + l.shape.radius * l.shape.dir.normalized().unitOrthogonal();
          } else if (l.shape.type == ShapeType::line) {
            p = l.shape.point + 0.5 * l.shape.length * l.shape.dir.normalized();
          } else {
            continue;
          }
          if (surface_distance(*s[0], p) > 1e-6 || surface_distance(*s[1], p) > 1e-6) continue;
          measured = true;
          EXPECT_NEAR(angle_between_lines(normal_at(*s[0], p), normal_at(*s[1], p)), *g->value, 0.1);
        }
        EXPECT_TRUE(measured) << "no common edge to measure at";
        break;
      }
      case ConstraintKind::equal_angle:
        ASSERT_TRUE(g->value.has_value());
        for (const auto& m : g->members) {
          const Group& fixed = group_of(f, m);
          ASSERT_EQ(fixed.constraint, ConstraintKind::fixed_angle);
          EXPECT_NEAR(*fixed.value, *g->value, 0.1);
        }
        break;
      case ConstraintKind::symmetric: {
        ASSERT_EQ(s.size(), 2u);
        ASSERT_TRUE(g->attributes.count("mirror"));
        const json m = json::parse(g->attributes.at("mirror"));
        const Vector3d c = vec3(m["point"]), n = vec3(m["normal"]).normalized();
        Shape image = *s[0];
        image.point = s[0]->point - 2 * n.dot(s[0]->point - c) * n;
        image.dir = s[0]->dir - 2 * n.dot(s[0]->dir) * n;
        EXPECT_TRUE(same_surface(image, *s[1]));
        EXPECT_FALSE(same_surface(*s[0], *s[1]));
        break;
      }
    }
  }
}

/// Every emitted constraint holds; returns how many were checked.
int expect_all_hold(const FeatureSet& f) {
  int checked = 0;
  for (const Group* g : constraints(f)) {
    expect_holds(f, g);
    ++checked;
  }
  return checked;
}

int count(const FeatureSet& f, ConstraintKind k) {
  int n = 0;
  for (const Group* g : constraints(f)) n += *g->constraint == k;
  return n;
}
bool has(const FeatureSet& f, ConstraintKind k, std::set<std::string> members) {
  for (const Group* g : constraints(f))
    if (*g->constraint == k && std::set<std::string>(g->members.begin(), g->members.end()) == members) return true;
  return false;
}
/// Is some group of kind k containing all of `members`?
bool grouped(const FeatureSet& f, ConstraintKind k, const std::vector<std::string>& members) {
  for (const Group* g : constraints(f)) {
    if (*g->constraint != k) continue;
    bool all = true;
    for (const auto& m : members) all &= std::count(g->members.begin(), g->members.end(), m) > 0;
    if (all) return true;
  }
  return false;
}

// ---- the fixture parts -------------------------------------------------------------------------

TEST(ConstraintsTest, PlateTruthImpliedAndAllHold) {
  Part p = load_part("plate");
  const int added = detect_constraints(p.f, options_for(p));
  EXPECT_EQ(added, static_cast<int>(p.f.groups.size()));
  expect_truth_implied(p);
  EXPECT_EQ(expect_all_hold(p.f), added);
  // One class per equivalence: the four small holes in one equal_radius group, exactly.
  EXPECT_TRUE(has(p.f, ConstraintKind::equal_radius,
                  {p.id["hole_0"], p.id["hole_1"], p.id["hole_2"], p.id["hole_3"]}));
  EXPECT_TRUE(has(p.f, ConstraintKind::parallel, {p.id["top"], p.id["bottom"]}));
  // Holes mirror each other about x = 0 and y = 0.
  EXPECT_TRUE(has(p.f, ConstraintKind::symmetric, {p.id["hole_0"], p.id["hole_1"]}));
  EXPECT_TRUE(has(p.f, ConstraintKind::symmetric, {p.id["hole_0"], p.id["hole_3"]}));
  EXPECT_FALSE(has(p.f, ConstraintKind::symmetric, {p.id["hole_0"], p.id["hole_2"]}));
  // Conservative: top ↔ bottom about z = 4 is the only pair on that plane (the holes are their own
  // images), and one pair does not make a symmetry plane.
  EXPECT_FALSE(has(p.f, ConstraintKind::symmetric, {p.id["top"], p.id["bottom"]}));
  // Redundancy: the box edges' parallel classes follow from the planes', and the edges meeting at
  // the corners are square because the planes are; the holes' axes form one class without a
  // coaxial statement, so their parallel group stays.
  for (const Group* g : constraints(p.f)) {
    if (*g->constraint != ConstraintKind::parallel && *g->constraint != ConstraintKind::perpendicular) continue;
    for (const auto& m : g->members) EXPECT_EQ(m[0], 'P') << g->id;
  }
  EXPECT_TRUE(grouped(p.f, ConstraintKind::parallel, {p.id["hole_0"], p.id["hole_center"]}));
  EXPECT_EQ(count(p.f, ConstraintKind::coaxial), 0);
  // Equal lengths: the 60, 40 and 8 mm edges; equal radii: the 3 mm rims together.
  EXPECT_EQ(count(p.f, ConstraintKind::equal_length), 3);
  EXPECT_TRUE(grouped(p.f, ConstraintKind::equal_radius, {p.id["rim_hole_0_top"], p.id["rim_hole_3_bottom"]}));
  // 24 corner pairs of connected edges; no fixed_angle (all edges square).
  EXPECT_EQ(count(p.f, ConstraintKind::connected), 24);
  EXPECT_EQ(count(p.f, ConstraintKind::fixed_angle), 0);
  EXPECT_EQ(count(p.f, ConstraintKind::perpendicular), 12);
}

TEST(ConstraintsTest, SearchThenAddIsDetectWithIdsAfterTheGroupsAddedMeanwhile) {
  Part p = load_part("plate");
  FeatureSet at_once = p.f;
  detect_constraints(at_once, options_for(p));
  // The search sees no groups; two groups are added before its constraints are numbered.
  const ConstraintSearch search(p.f, options_for(p));
  for (const char* id : {"G0", "G1"}) {
    Group g;
    g.id = id;
    g.kind = "component";
    p.f.groups.push_back(g);
  }
  const int added = search.add_to(p.f);
  ASSERT_EQ(added, static_cast<int>(at_once.groups.size()));
  ASSERT_EQ(p.f.groups.size(), at_once.groups.size() + 2);
  for (std::size_t k = 0; k < at_once.groups.size(); ++k) {
    const Group &a = at_once.groups[k], &b = p.f.groups[k + 2];
    EXPECT_EQ(b.id, "G" + std::to_string(k + 2));
    EXPECT_EQ(a.constraint, b.constraint);
    EXPECT_EQ(a.value, b.value);
    if (a.constraint != ConstraintKind::equal_angle) {
      EXPECT_EQ(a.members, b.members) << a.id;
    } else {  // members are fixed_angle groups: their ids moved by two as well
      ASSERT_EQ(a.members.size(), b.members.size());
      for (std::size_t i = 0; i < a.members.size(); ++i)
        EXPECT_EQ(std::stoi(b.members[i].substr(1)), std::stoi(a.members[i].substr(1)) + 2);
    }
  }
}

TEST(ConstraintsTest, ShaftTruthImpliedAndAllHold) {
  Part p = load_part("shaft");
  p.adjacent("shaft_body", "tip");  // tangent: no line between them
  detect_constraints(p.f, options_for(p));
  expect_truth_implied(p);
  expect_all_hold(p.f);
  EXPECT_TRUE(has(p.f, ConstraintKind::coaxial, {p.id["chamfer"], p.id["shaft_body"], p.id["tip"]}));
  // 45° twice → one equal_angle group whose members are the two fixed_angle groups.
  ASSERT_EQ(count(p.f, ConstraintKind::fixed_angle), 2);
  ASSERT_EQ(count(p.f, ConstraintKind::equal_angle), 1);
  for (const Group* g : constraints(p.f))
    if (*g->constraint == ConstraintKind::equal_angle) {
      EXPECT_EQ(g->members.size(), 2u);
      for (const auto& m : g->members) EXPECT_EQ(group_of(p.f, m).constraint, ConstraintKind::fixed_angle);
      EXPECT_NEAR(*g->value, 45.0, 1e-9);
    }
  // The tangent body–tip junction is not a fixed angle; coaxial already says the axes agree.
  EXPECT_FALSE(has(p.f, ConstraintKind::fixed_angle, {p.id["shaft_body"], p.id["tip"]}));
  EXPECT_EQ(count(p.f, ConstraintKind::parallel), 0);
}

TEST(ConstraintsTest, PocketTruthImpliedAndAllHold) {
  Part p = load_part("pocket");
  detect_constraints(p.f, options_for(p));
  expect_truth_implied(p);
  expect_all_hold(p.f);
  // The counterbore floor's two rims are concentric; the pocket floor's rim is not on that plane.
  EXPECT_TRUE(has(p.f, ConstraintKind::concentric,
                  {p.id["rim_counterbore_counterbore_floor"], p.id["rim_hole_counterbore_floor"]}));
  EXPECT_FALSE(grouped(p.f, ConstraintKind::concentric,
                       {p.id["rim_counterbore_pocket_floor"], p.id["rim_hole_counterbore_floor"]}));
  // No plane pair that only meets across the pocket is called perpendicular.
  EXPECT_FALSE(has(p.f, ConstraintKind::perpendicular, {p.id["bottom"], p.id["pocket_wall_xp"]}));
  // The pocket is centred: its walls mirror each other.
  EXPECT_TRUE(has(p.f, ConstraintKind::symmetric, {p.id["pocket_wall_xp"], p.id["pocket_wall_xn"]}));
  // Top and bottom are mirror planes about z = 10, but the pocket makes their faces differ.
  EXPECT_FALSE(has(p.f, ConstraintKind::symmetric, {p.id["top"], p.id["bottom"]}));
}

TEST(ConstraintsTest, BracketTruthImpliedAndAllHold) {
  Part p = load_part("bracket");
  detect_constraints(p.f, options_for(p));
  expect_truth_implied(p);  // includes the non-adjacent hole axes: base holes ⊥ wall hole
  expect_all_hold(p.f);
  EXPECT_FALSE(has(p.f, ConstraintKind::perpendicular, {p.id["bottom"], p.id["wall_front"]}));
}

TEST(ConstraintsTest, SignsOfNormalsAndAxesDoNotMatter) {
  for (const char* part : {"plate", "shaft", "pocket", "bracket"}) {
    SCOPED_TRACE(part);
    Part p = load_part(part);
    if (std::string(part) == "shaft") p.adjacent("shaft_body", "tip");
    for (auto& patch : p.f.patches)
      if (patch.shape.type != ShapeType::cone) patch.shape.dir = -patch.shape.dir;
    for (auto& l : p.f.lines)
      if (l.shape.type == ShapeType::circle) l.shape.dir = -l.shape.dir;
    detect_constraints(p.f, options_for(p));
    expect_truth_implied(p);
    expect_all_hold(p.f);
  }
}

// ---- tolerances and adjacency ------------------------------------------------------------------

Vector3d rotate_z(const Vector3d& v, double deg) { return Eigen::AngleAxisd(deg * kPi / 180, Vector3d::UnitZ()) * v; }

TEST(ConstraintsTest, PlaneTiltedFiveDegreesLosesItsParallelAndPerpendicular) {
  Part p = load_part("plate");
  Shape& side = p.shape("side_xn");
  side.dir = rotate_z(side.dir, 5.0);
  detect_constraints(p.f, options_for(p));
  expect_all_hold(p.f);
  EXPECT_FALSE(grouped(p.f, ConstraintKind::parallel, {p.id["side_xp"], p.id["side_xn"]}));
  EXPECT_FALSE(grouped(p.f, ConstraintKind::parallel, {p.id["side_xn"]}));
  EXPECT_FALSE(has(p.f, ConstraintKind::perpendicular, {p.id["side_xn"], p.id["side_yn"]}));
  EXPECT_TRUE(has(p.f, ConstraintKind::perpendicular, {p.id["side_xn"], p.id["top"]}));  // still square to z
  EXPECT_TRUE(has(p.f, ConstraintKind::fixed_angle, {p.id["side_xn"], p.id["side_yn"]}));
  EXPECT_TRUE(has(p.f, ConstraintKind::parallel, {p.id["top"], p.id["bottom"]}));
}

TEST(ConstraintsTest, WithinToleranceStillParallel) {
  Part p = load_part("plate");
  p.shape("side_xn").dir = rotate_z(p.shape("side_xn").dir, 1.5);
  detect_constraints(p.f, options_for(p));
  EXPECT_TRUE(has(p.f, ConstraintKind::parallel, {p.id["side_xp"], p.id["side_xn"]}));
  EXPECT_TRUE(has(p.f, ConstraintKind::perpendicular, {p.id["side_xn"], p.id["side_yn"]}));
}

TEST(ConstraintsTest, ChainsOfNearMissesDoNotDrift) {
  // Normals 1.5° apart in a row: neighbours pass the 2° test, but no class spans more than 2°.
  FeatureSet f;
  for (int i = 0; i < 6; ++i) {
    Patch p;
    p.id = "P" + std::to_string(i);
    p.shape = make_shape(ShapeType::plane, Vector3d(0, 0, 10.0 * i), rotate_z(Vector3d::UnitX(), 1.5 * i));
    f.patches.push_back(p);
  }
  detect_constraints(f, {});
  for (const Group* g : constraints(f)) {
    ASSERT_EQ(*g->constraint, ConstraintKind::parallel);
    for (const auto& a : g->members)
      for (const auto& b : g->members)
        EXPECT_LE(angle_between_lines(shape_of(f, a).dir, shape_of(f, b).dir), 2.0 + 1e-9);
  }
  EXPECT_GE(count(f, ConstraintKind::parallel), 2);
}

TEST(ConstraintsTest, PerpendicularOnlyBetweenNeighbours) {
  Part p = load_part("plate");
  auto& adj = p.f.adjacency;
  adj.erase(std::remove_if(adj.begin(), adj.end(),
                           [&](const auto& a) {
                             return std::set<std::string>{a.first, a.second} ==
                                    std::set<std::string>{p.id["top"], p.id["side_xp"]};
                           }),
            adj.end());
  ASSERT_FALSE(p.has_adjacency("top", "side_xp"));
  detect_constraints(p.f, options_for(p));
  EXPECT_FALSE(has(p.f, ConstraintKind::perpendicular, {p.id["top"], p.id["side_xp"]}));
  EXPECT_TRUE(has(p.f, ConstraintKind::perpendicular, {p.id["top"], p.id["side_xn"]}));
  // Parallel planes are never perpendicular.
  EXPECT_FALSE(has(p.f, ConstraintKind::perpendicular, {p.id["top"], p.id["bottom"]}));
}

TEST(ConstraintsTest, RadiusAndLengthTolerances) {
  FeatureSet f;
  auto cyl = [&](double x, double r) {
    Patch p;
    p.id = "P" + std::to_string(f.patches.size());
    p.shape = make_shape(ShapeType::cylinder, Vector3d(x, 0, 0), Vector3d::UnitZ(), r);
    f.patches.push_back(p);
  };
  cyl(0, 3.0);
  cyl(10, 3.02);  // 0.7 %: equal
  cyl(20, 3.2);   // 6 %: a different hole size
  auto seg = [&](double y, double len) {
    Line l;
    l.id = "L" + std::to_string(f.lines.size());
    l.shape = make_shape(ShapeType::line, Vector3d(0, y, 0), Vector3d::UnitX(), 0, len);
    l.vertices = {static_cast<int>(2 * f.lines.size()), static_cast<int>(2 * f.lines.size() + 1)};
    f.lines.push_back(l);
  };
  seg(0, 50.0);
  seg(5, 50.3);  // 0.6 %
  seg(10, 47.0);
  ConstraintOptions o;
  o.diagonal = 100;
  detect_constraints(f, o);
  EXPECT_TRUE(has(f, ConstraintKind::equal_radius, {"P0", "P1"}));
  EXPECT_FALSE(grouped(f, ConstraintKind::equal_radius, {"P2"}));
  EXPECT_TRUE(has(f, ConstraintKind::equal_length, {"L0", "L1"}));
  EXPECT_FALSE(grouped(f, ConstraintKind::equal_length, {"L2"}));
  // Parallel lines on distinct lines with no planes around: stated.
  EXPECT_TRUE(has(f, ConstraintKind::parallel, {"L0", "L1", "L2"}));
  EXPECT_EQ(count(f, ConstraintKind::collinear), 0);
}

TEST(ConstraintsTest, FixedAngleSkipsTangentSquareAndVaryingEdges) {
  // A plane P0 and neighbours at 1° (tangent), 30°, 89° (square) to it; a sphere cut by P0 at
  // d = R/2 (60°); a cylinder cut obliquely (the angle varies along the edge).
  FeatureSet f;
  auto patch = [&](Shape s) {
    Patch p;
    p.id = "P" + std::to_string(f.patches.size());
    p.shape = s;
    f.patches.push_back(p);
    if (f.patches.size() > 1) f.adjacency.emplace_back("P0", p.id);
  };
  auto tilted = [](double deg) {
    return Eigen::AngleAxisd(deg * kPi / 180, Vector3d::UnitX()) * Vector3d::UnitZ();
  };
  patch(make_shape(ShapeType::plane, Vector3d::Zero(), Vector3d::UnitZ()));
  patch(make_shape(ShapeType::plane, Vector3d::Zero(), tilted(1.0)));
  patch(make_shape(ShapeType::plane, Vector3d::Zero(), tilted(30.0)));
  patch(make_shape(ShapeType::plane, Vector3d::Zero(), tilted(89.0)));
  patch(make_shape(ShapeType::sphere, Vector3d(0, 0, 2.5), Vector3d::UnitZ(), 5.0));
  patch(make_shape(ShapeType::cylinder, Vector3d::Zero(), tilted(40.0), 3.0));
  ConstraintOptions o;
  o.diagonal = 100;
  detect_constraints(f, o);
  EXPECT_EQ(count(f, ConstraintKind::fixed_angle), 2);
  for (const Group* g : constraints(f))
    if (*g->constraint == ConstraintKind::fixed_angle) {
      if (g->members[1] == "P2") EXPECT_NEAR(*g->value, 30.0, 1e-9);
      else if (g->members[1] == "P4") EXPECT_NEAR(*g->value, 60.0, 1e-9);
      else ADD_FAILURE() << "unexpected fixed_angle with " << g->members[1];
    }
  EXPECT_TRUE(has(f, ConstraintKind::perpendicular, {"P0", "P3"}));
  EXPECT_TRUE(has(f, ConstraintKind::parallel, {"P0", "P1"}));
  EXPECT_EQ(count(f, ConstraintKind::equal_angle), 0);
}

TEST(ConstraintsTest, FixedAngleBelowTheMinimumIsNotStated) {
  // Neighbours of a plane at 6° (pieces of one noisy surface on a scan) and at 45° (a chamfer).
  FeatureSet f;
  for (double deg : {0.0, 6.0, 45.0}) {
    Patch p;
    p.id = "P" + std::to_string(f.patches.size());
    p.shape = make_shape(ShapeType::plane, Vector3d::Zero(),
                         Eigen::AngleAxisd(deg * kPi / 180, Vector3d::UnitX()) * Vector3d::UnitZ());
    f.patches.push_back(p);
    if (deg > 0) f.adjacency.emplace_back("P0", p.id);
  }
  FeatureSet all = f;
  ConstraintOptions o;
  o.diagonal = 100;
  detect_constraints(all, o);
  EXPECT_EQ(count(all, ConstraintKind::fixed_angle), 2);
  o.min_fixed_angle_deg = 25.0;
  detect_constraints(f, o);
  ASSERT_EQ(count(f, ConstraintKind::fixed_angle), 1);
  for (const Group* g : constraints(f))
    if (*g->constraint == ConstraintKind::fixed_angle) {
      EXPECT_EQ(g->members[1], "P2");
      EXPECT_NEAR(*g->value, 45.0, 1e-9);
    }
}

/// Appends a patch of `area` mm² and returns its id.
std::string add_patch(FeatureSet& f, ShapeType type, const Vector3d& point, const Vector3d& normal, double area) {
  Patch p;
  p.id = "P" + std::to_string(f.patches.size());
  p.area = area;
  p.shape = make_shape(type, point, normal);
  f.patches.push_back(p);
  return p.id;
}

/// Appends a line of `shape`, adjacent to the patches `touches`, and returns its id. Its chain is
/// `vertices`, or two vertices no other line has.
std::string append_line(FeatureSet& f, const Shape& shape, const std::vector<std::string>& touches,
                        std::vector<int> vertices) {
  Line l;
  l.id = "L" + std::to_string(f.lines.size());
  l.shape = shape;
  l.vertices = vertices.empty() ? std::vector<int>{static_cast<int>(2 * f.lines.size()), static_cast<int>(2 * f.lines.size() + 1)}
                                : std::move(vertices);
  for (const auto& p : touches) f.adjacency.emplace_back(p, l.id);
  f.lines.push_back(l);
  return l.id;
}

/// Appends the straight line from `from` to `to` (append_line).
std::string add_line(FeatureSet& f, const Vector3d& from, const Vector3d& to, const std::vector<std::string>& touches,
                     std::vector<int> vertices = {}) {
  return append_line(f, make_shape(ShapeType::line, from, to - from, 0, (to - from).norm()), touches, std::move(vertices));
}

/// Appends the straight line from a to b, its chain from vertex va over a vertex of its own to vb.
void add_segment(FeatureSet& f, const Vector3d& a, const Vector3d& b, int va, int vb) {
  add_line(f, a, b, {}, {va, 100 + static_cast<int>(f.lines.size()), vb});
}

TEST(ConstraintsTest, CollinearAndConnectedLines) {
  FeatureSet f;
  auto seg = [&](Vector3d a, Vector3d b, int va, int vb) { add_segment(f, a, b, va, vb); };
  seg({0, 0, 0}, {10, 0, 0}, 0, 1);
  seg({20, 0, 0}, {35, 0, 0}, 2, 3);  // collinear with L0
  seg({10, 0, 0}, {10, 10, 0}, 1, 4);  // connected to L0 at vertex 1, square to it
  seg({10, 10, 0}, {0, 20, 0}, 4, 5);  // connected to L2 at 45°
  detect_constraints(f, {});
  expect_all_hold(f);
  EXPECT_TRUE(has(f, ConstraintKind::collinear, {"L0", "L1"}));
  EXPECT_FALSE(grouped(f, ConstraintKind::parallel, {"L0", "L1"}));  // collinear says it
  EXPECT_TRUE(has(f, ConstraintKind::connected, {"L0", "L2"}));
  EXPECT_TRUE(has(f, ConstraintKind::connected, {"L2", "L3"}));
  EXPECT_FALSE(has(f, ConstraintKind::connected, {"L0", "L1"}));
  EXPECT_TRUE(has(f, ConstraintKind::perpendicular, {"L0", "L2"}));
  EXPECT_FALSE(has(f, ConstraintKind::perpendicular, {"L2", "L3"}));
}

// A scan's corner stub (one face of a patch poking past a corner: a line of a mesh edge or two)
// is no longer than the position tolerance: no length, end or direction of it is a designed one.
// On a clean tessellation its ends and direction are exact; only its length is not measurable.
TEST(ConstraintsTest, LinesNoLongerThanThePositionToleranceTakeNoPart) {
  auto corner = [](double stub, bool scan) {
    FeatureSet f;
    auto seg = [&](Vector3d a, Vector3d b, int va, int vb) { add_segment(f, a, b, va, vb); };
    const Vector3d c(0, 0, 40);
    seg({0, 0, 6}, c, 0, 1);                                            // the long edge up to the corner
    seg(c, c + stub * Vector3d(0, 0.82, 0.58).normalized(), 1, 2);      // two stubs from its end,
    seg(c, c + stub * Vector3d(-0.26, 0.9, 0.35).normalized(), 1, 3);  // of one length
    ConstraintOptions o;
    o.diagonal = 100;                      // position tolerance 0.5 mm
    o.min_patch_area = scan ? 1.0 : 0.0;  // (no patches here: only the scan rules it switches on)
    detect_constraints(f, o);
    return f;
  };
  const FeatureSet scan_stubs = corner(0.14, true);
  EXPECT_EQ(count(scan_stubs, ConstraintKind::equal_length), 0);
  EXPECT_EQ(count(scan_stubs, ConstraintKind::connected), 0);
  const FeatureSet clean_stubs = corner(0.14, false);
  EXPECT_EQ(count(clean_stubs, ConstraintKind::equal_length), 0);
  EXPECT_TRUE(has(clean_stubs, ConstraintKind::connected, {"L0", "L1"}));
  // Lines of the same shape twice the tolerance long take part.
  const FeatureSet edges = corner(1.0, true);
  expect_all_hold(edges);
  EXPECT_TRUE(has(edges, ConstraintKind::connected, {"L0", "L1"}));
  EXPECT_TRUE(has(edges, ConstraintKind::connected, {"L0", "L2"}));
  EXPECT_TRUE(has(edges, ConstraintKind::equal_length, {"L1", "L2"}));
}

/// Appends the arc of `radius` about `centre` in the plane square to `normal`, from `from` (on
/// it) through `degrees`, with the chain `vertices`, and returns its id.
std::string add_arc(FeatureSet& f, const Vector3d& centre, const Vector3d& normal, const Vector3d& from, double degrees,
                    std::vector<int> vertices) {
  Shape arc;
  arc.type = ShapeType::arc;
  arc.point = centre;
  arc.dir = normal.normalized();
  arc.radius = (from - centre).norm();
  arc.start = from;
  arc.end = centre + Eigen::AngleAxisd(degrees * M_PI / 180.0, arc.dir) * (from - centre);
  arc.angle_deg = degrees;
  return append_line(f, arc, {}, std::move(vertices));
}

// The same for an arc: a few mesh edges round a scan's rounded corner fit a circle of a tenth of
// a millimetre, whose centre and radius are that corner's zigzag (the bracket scan on a working
// mesh of a seventh: a 163° arc of radius 0.135 mm at the corner of two edges, connected to both).
TEST(ConstraintsTest, ArcsNoLongerThanThePositionToleranceTakeNoPartOnScans) {
  auto corner = [](double radius, bool scan) {
    FeatureSet f;
    const Vector3d c(0, 0, 40);
    add_line(f, {0, 0, 6}, c, {}, {0, 100, 1});                      // an edge up to the corner
    add_arc(f, c + Vector3d(radius, 0, 0), {0, 1, 0}, c, 180, {1, 101, 2});  // round it
    add_line(f, {50, 0, 40}, c + Vector3d(2 * radius, 0, 0), {}, {3, 102, 2});  // and on
    ConstraintOptions o;
    o.diagonal = 100;  // position tolerance 0.5 mm
    o.min_patch_area = scan ? 1.0 : 0.0;
    detect_constraints(f, o);
    return f;
  };
  const FeatureSet scan_stub = corner(0.135, true);  // 0.42 mm of arc
  EXPECT_EQ(count(scan_stub, ConstraintKind::connected), 0);
  const FeatureSet clean_stub = corner(0.135, false);
  EXPECT_TRUE(has(clean_stub, ConstraintKind::connected, {"L0", "L1"}));
  EXPECT_TRUE(has(clean_stub, ConstraintKind::connected, {"L1", "L2"}));
  // An arc of a 1 mm fillet (3.1 mm) is a designed curve: it takes part on a scan too.
  const FeatureSet fillet = corner(1.0, true);
  expect_all_hold(fillet);
  EXPECT_TRUE(has(fillet, ConstraintKind::connected, {"L0", "L1"}));
  EXPECT_TRUE(has(fillet, ConstraintKind::connected, {"L1", "L2"}));
}

TEST(ConstraintsTest, MovedHoleIsNotSymmetric) {
  Part p = load_part("plate");
  p.shape("hole_1").point.x() += 1.0;
  detect_constraints(p.f, options_for(p));
  expect_all_hold(p.f);
  EXPECT_FALSE(has(p.f, ConstraintKind::symmetric, {p.id["hole_0"], p.id["hole_1"]}));
  EXPECT_TRUE(has(p.f, ConstraintKind::symmetric, {p.id["hole_3"], p.id["hole_2"]}));
  EXPECT_FALSE(grouped(p.f, ConstraintKind::equal_radius, {p.id["hole_1"], p.id["hole_center"]}));
}

// ---- ids, order, bad input ---------------------------------------------------------------------

TEST(ConstraintsTest, IdsContinueNumberingInKindOrder) {
  Part p = load_part("plate");
  Group c;
  c.id = "G7";
  c.kind = "component";
  c.members = {p.id["top"]};
  p.f.groups.push_back(c);
  c.id = "G2";
  p.f.groups.push_back(c);
  const int added = detect_constraints(p.f, options_for(p));
  ASSERT_GT(added, 0);
  ASSERT_EQ(p.f.groups.size(), static_cast<std::size_t>(added + 2));
  int last_kind = -1;
  for (int i = 0; i < added; ++i) {
    const Group& g = p.f.groups[2 + i];
    EXPECT_EQ(g.id, "G" + std::to_string(8 + i));
    EXPECT_EQ(g.kind, "constraint");
    ASSERT_TRUE(g.constraint.has_value());
    EXPECT_GE(static_cast<int>(*g.constraint), last_kind);
    last_kind = static_cast<int>(*g.constraint);
  }
  // Deterministic: the same input gives the same groups.
  Part q = load_part("plate");
  q.f.groups = {p.f.groups[0], p.f.groups[1]};
  detect_constraints(q.f, options_for(q));
  ASSERT_EQ(q.f.groups.size(), p.f.groups.size());
  for (std::size_t i = 0; i < p.f.groups.size(); ++i) {
    EXPECT_EQ(q.f.groups[i].id, p.f.groups[i].id);
    EXPECT_EQ(q.f.groups[i].members, p.f.groups[i].members);
    EXPECT_EQ(q.f.groups[i].attributes, p.f.groups[i].attributes);
  }
}

TEST(ConstraintsTest, FreeformAndUnusableShapesTakeNoPart) {
  Part p = load_part("plate");
  p.shape("hole_0").type = ShapeType::freeform;          // e.g. a failed fit
  p.shape("hole_1").radius = std::nan("");                // garbage numbers
  p.shape("side_xp").dir = Vector3d::Zero();              // no normal
  p.f.adjacency.emplace_back(p.id["top"], "P999");        // unknown feature: ignored
  detect_constraints(p.f, options_for(p));
  expect_all_hold(p.f);
  for (const Group* g : constraints(p.f))
    for (const auto& m : g->members) {
      EXPECT_NE(m, p.id["hole_0"]);
      EXPECT_NE(m, p.id["hole_1"]);
      EXPECT_NE(m, p.id["side_xp"]);
    }
  EXPECT_TRUE(has(p.f, ConstraintKind::equal_radius, {p.id["hole_2"], p.id["hole_3"]}));
}

TEST(ConstraintsTest, PatchesBelowTheMinimumAreaOrFreeformAndTheirLinesTakeNoPart) {
  Part p = load_part("plate");
  for (auto& patch : p.f.patches) patch.area = 100.0;
  std::set<std::string> excluded = {p.id["hole_0"]};
  for (auto& patch : p.f.patches)
    if (patch.id == p.id["hole_0"]) patch.area = 1.0;  // a scan artefact's size
  for (const auto& [a, b] : p.f.adjacency) {
    if (a == p.id["hole_0"] && b[0] == 'L') excluded.insert(b);
    if (b == p.id["hole_0"] && a[0] == 'L') excluded.insert(a);
  }
  ASSERT_GE(excluded.size(), 3u) << "hole_0 and its two rims";
  // A freeform patch (fitting gave up) disqualifies its lines too, once a minimum area is set.
  p.shape("hole_1").type = ShapeType::freeform;
  excluded.insert(p.id["hole_1"]);
  std::size_t rims = 0;
  for (const auto& [a, b] : p.f.adjacency) {
    if (a == p.id["hole_1"] && b[0] == 'L') excluded.insert(b), ++rims;
    if (b == p.id["hole_1"] && a[0] == 'L') excluded.insert(a), ++rims;
  }
  ASSERT_GE(rims, 2u);
  ConstraintOptions o = options_for(p);
  o.min_patch_area = 10.0;
  detect_constraints(p.f, o);
  expect_all_hold(p.f);
  for (const Group* g : constraints(p.f))
    for (const auto& m : g->members) EXPECT_EQ(excluded.count(m), 0u) << m << " in " << g->id;
  EXPECT_TRUE(has(p.f, ConstraintKind::equal_radius, {p.id["hole_2"], p.id["hole_3"]}));
}

TEST(ConstraintsTest, PlanesAcrossARoundedEdgeAreNeighboursOnNoisyMeshes) {
  // A scan rounds the edge between two square planes into a strip that no shape fits: the
  // planes then touch only that strip. With a minimum area (noisy meshes) they are neighbours
  // through it; on a clean mesh (no minimum) only touching planes are.
  FeatureSet f;
  auto patch = [&](ShapeType type, const Vector3d& normal, double area) {
    Patch p;
    p.id = "P" + std::to_string(f.patches.size());
    p.area = area;
    p.shape = make_shape(type, Vector3d::Zero(), normal);
    f.patches.push_back(p);
    return p.id;
  };
  const std::string top = patch(ShapeType::plane, Vector3d::UnitZ(), 100);
  const std::string round = patch(ShapeType::freeform, Vector3d::UnitZ(), 4);
  const std::string side = patch(ShapeType::plane, Vector3d(1, 0, 0.01).normalized(), 100);  // 0.6° off square
  const std::string far = patch(ShapeType::plane, Vector3d::UnitY(), 100);                    // touches nothing
  f.adjacency = {{top, round}, {round, side}};
  ConstraintOptions o;
  o.diagonal = 100;
  FeatureSet clean = f;
  detect_constraints(clean, o);
  EXPECT_FALSE(has(clean, ConstraintKind::perpendicular, {top, side}));
  o.min_patch_area = 10.0;
  detect_constraints(f, o);
  EXPECT_TRUE(has(f, ConstraintKind::perpendicular, {top, side}));
  EXPECT_FALSE(has(f, ConstraintKind::perpendicular, {top, far}));
  EXPECT_FALSE(has(f, ConstraintKind::perpendicular, {side, far}));
}

TEST(ConstraintsTest, AScansEdgeAlongARoundedBandTakesPartAndItsLengthOnlyCornerToCorner) {
  // The top edges of a 50 × 50 box whose scan rounded them into one freeform band. A line touching
  // the band takes part when it is a whole edge: the intersection of two planes it touches, both
  // ends on planes next to both (corners).
  FeatureSet f;
  auto patch = [&](ShapeType type, const Vector3d& point, const Vector3d& normal, double area) {
    return add_patch(f, type, point, normal, area);
  };
  auto line = [&](const Vector3d& from, const Vector3d& to, std::vector<std::string> touches) {
    return add_line(f, from, to, touches);
  };
  const std::string top = patch(ShapeType::plane, Vector3d(0, 0, 20), Vector3d::UnitZ(), 2500);
  const std::string xp = patch(ShapeType::plane, Vector3d(25, 0, 10), Vector3d::UnitX(), 1000);
  const std::string xn = patch(ShapeType::plane, Vector3d(-25, 0, 10), -Vector3d::UnitX(), 1000);
  const std::string yp = patch(ShapeType::plane, Vector3d(0, 25, 10), Vector3d::UnitY(), 1000);
  const std::string yn = patch(ShapeType::plane, Vector3d(0, -25, 10), -Vector3d::UnitY(), 1000);
  const std::string band = patch(ShapeType::freeform, Vector3d::Zero(), Vector3d::UnitZ(), 300);
  for (const auto& p : {top, xp, xn, yp, yn}) f.adjacency.emplace_back(p, band);
  const std::string whole_xp = line({25, -25, 20}, {25, 25, 20}, {top, xp, band});
  const std::string whole_xn = line({-25, 25, 20}, {-25, -25, 20}, {top, xn, band});
  // A piece of the edge along yp, as long as the others but ending where no plane cuts it.
  const std::string piece_yp = line({-20, 25, 20}, {30, 25, 20}, {top, yp, band});
  // A line along the band that is no intersection: 1 mm off the edge along yn.
  const std::string off_yn = line({-25, -24, 20}, {25, -24, 20}, {top, yn, band});
  ConstraintOptions o;
  o.diagonal = 100;
  o.min_patch_area = 10.0;
  detect_constraints(f, o);
  EXPECT_TRUE(has(f, ConstraintKind::equal_length, {whole_xp, whole_xn}));
  for (const Group* g : constraints(f))
    for (const auto& m : g->members) {
      EXPECT_NE(m, off_yn) << "in " << g->id;
      EXPECT_NE(m, piece_yp) << "in " << g->id;
    }
  // Without the band all of them take part, as before: the piece's equal length is stated.
  FeatureSet unbanded = f;
  unbanded.groups.clear();
  auto& adjacency = unbanded.adjacency;
  adjacency.erase(std::remove_if(adjacency.begin(), adjacency.end(),
                                 [&](const auto& a) { return a.first == band || a.second == band; }),
                  adjacency.end());
  unbanded.patches.pop_back();
  detect_constraints(unbanded, o);
  EXPECT_TRUE(grouped(unbanded, ConstraintKind::equal_length, {whole_xp, whole_xn, piece_yp}));
}

// A scan rounds the corner where a pocket's top meets two of its walls; a 0.57 mm line runs from
// the corner diagonally down into the rounding, along none of the three planes' edges.
TEST(ConstraintsTest, ALineAcrossARoundedCornerTakesNoPartOnScans) {
  auto corner = [](bool scan) {
    FeatureSet f;
    const std::string top = add_patch(f, ShapeType::plane, Vector3d(0, 0, 20), Vector3d::UnitZ(), 1800);
    const std::string wall_y = add_patch(f, ShapeType::plane, Vector3d(0, -10, 15), -Vector3d::UnitY(), 200);
    const std::string wall_x = add_patch(f, ShapeType::plane, Vector3d(15, 0, 15), Vector3d::UnitX(), 200);
    add_line(f, {-15, -10, 20}, {15, -10, 20}, {top, wall_y}, {0, 1});  // L0, the top's edges
    add_line(f, {15, -10, 20}, {15, 10, 20}, {top, wall_x}, {1, 2});    // L1
    const Vector3d from(14.7, -10.0, 19.86);
    add_line(f, from, from + 0.57 * Vector3d(0.40, 0.37, -0.84).normalized(), {top, wall_y, wall_x}, {1, 3});
    ConstraintOptions o;
    o.diagonal = 100;  // position tolerance 0.5 mm: the diagonal is longer
    o.min_patch_area = scan ? 10.0 : 0.0;
    detect_constraints(f, o);
    return f;
  };
  const FeatureSet scan = corner(true);
  EXPECT_TRUE(has(scan, ConstraintKind::connected, {"L0", "L1"}));
  for (const Group* g : constraints(scan))
    for (const auto& m : g->members) EXPECT_NE(m, "L2") << "in " << g->id;
  const FeatureSet clean = corner(false);
  EXPECT_TRUE(has(clean, ConstraintKind::connected, {"L0", "L2"}));
}

TEST(ConstraintsTest, EmptySetGivesNothing) {
  FeatureSet f;
  EXPECT_EQ(detect_constraints(f, {}), 0);
  EXPECT_TRUE(f.groups.empty());
  Patch lone;
  lone.id = "P0";
  lone.shape = make_shape(ShapeType::plane, Vector3d::Zero(), Vector3d::UnitZ());
  f.patches.push_back(lone);
  EXPECT_EQ(detect_constraints(f, {}), 0);
}

TEST(ConstraintsTest, ThousandsOfFeaturesStayFast) {
  // 1000 holes on a grid in a plate-like set of 1500 planes: classes, not pairs.
  FeatureSet f;
  for (int i = 0; i < 1500; ++i) {
    Patch p;
    p.id = "P" + std::to_string(f.patches.size());
    p.area = 100;
    p.shape = make_shape(ShapeType::plane, Vector3d(0, 0, i), i % 3 == 0 ? Vector3d::UnitZ() : (i % 3 == 1 ? Vector3d::UnitX() : Vector3d::UnitY()));
    f.patches.push_back(p);
  }
  for (int i = 0; i < 1000; ++i) {
    Patch p;
    p.id = "P" + std::to_string(f.patches.size());
    p.area = 50;
    p.shape = make_shape(ShapeType::cylinder, Vector3d(10.0 * (i % 40), 10.0 * (i / 40), 0), Vector3d::UnitZ(), 2);
    f.patches.push_back(p);
  }
  ConstraintOptions o;
  o.diagonal = 1500;
  const auto t0 = std::chrono::steady_clock::now();
  detect_constraints(f, o);
  const double seconds = seconds_since(t0);
  EXPECT_LT(seconds, 10.0);
  EXPECT_LT(f.groups.size(), 5000u);
  EXPECT_EQ(count(f, ConstraintKind::equal_radius), 1);
}

}  // namespace
}  // namespace s2c::features
