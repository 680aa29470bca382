// The interpreter of the edit language: evaluates expressions and selections and calls the Editor.
#include "s2c/edit/interpreter.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include <fmt/format.h>

#include "constraint_rules.h"
#include "s2c/core/errors.h"
#include "shape_map.h"

namespace s2c::edit {

using Eigen::Vector3d;
using features::Shape;
using features::ShapeType;

namespace {

constexpr double kDefaultDirectionTolDeg = 5.0;
constexpr double kDefaultRelativeTol = 0.01;

struct Value {
  bool is_vector = false;
  double x = 0.0;
  Vector3d v = Vector3d::Zero();
};

using Selection = std::vector<FeatureRef>;

class Interpreter {
 public:
  Interpreter(const Script& s, Editor& ed, const ScriptOptions& o) : script_(s), ed_(ed), opt_(o) {}

  ScriptResult run() {
    check_overrides();
    ScriptResult result;
    for (const Statement& st : script_.statements) {
      StatementReport rep;
      rep.line = st.at.line;
      rep.text = st.text;
      try {
        execute(st, rep, result);
      } catch (const ScriptError&) {
        throw;
      } catch (const ProcessingError& e) {
        throw ProcessingError(fmt::format("{}:{}: `{}`: {}", script_.source, st.at.line, st.text, e.what()));
      } catch (const InvalidInput& e) {
        throw ScriptError(script_.source, st.name.empty() ? st.at : st.name_at, fmt::format("`{}`: {}", st.text, e.what()));
      }
      result.statements.push_back(std::move(rep));
    }
    return result;
  }

 private:
  void say(const std::string& s) const {
    if (opt_.say) opt_.say(s);
  }
  [[noreturn]] void fail(Location at, const std::string& what) const { throw ScriptError(script_.source, at, what); }

  void check_overrides() const {
    std::set<std::string> params;
    for (const Statement& st : script_.statements)
      if (st.kind == Statement::Kind::param) params.insert(st.name);
    for (const auto& [name, text] : opt_.overrides)
      if (!params.count(name))
        throw InvalidInput(fmt::format("--set {}={}: {} has no 'param {}' (its parameters: {})", name, text,
                                       script_.source, name, params.empty() ? "none" : fmt::format("{}", fmt::join(params, ", "))));
  }

  // ---- values -----------------------------------------------------------------------------------
  Value eval(const ExprPtr& e) const {
    switch (e->kind) {
      case Expr::Kind::number: return {false, e->number, {}};
      case Expr::Kind::vector: {
        Value v;
        v.is_vector = true;
        for (int a = 0; a < 3; ++a) v.v[a] = number(e->args[a], "a vector component");
        return v;
      }
      case Expr::Kind::name: {
        if (auto it = values_.find(e->name); it != values_.end()) return it->second;
        if (selections_.count(e->name) || ed_.find(e->name))
          fail(e->at, fmt::format("'{}' is a selection, not a value: use {}.radius, {}.area, …", e->name, e->name, e->name));
        fail(e->at, fmt::format("unknown name '{}': define it with 'param {} = …' or 'let {} = …'", e->name, e->name, e->name));
      }
      case Expr::Kind::property: return property_value(e);
      case Expr::Kind::negate: {
        Value v = eval(e->args[0]);
        v.x = -v.x;
        v.v = -v.v;
        return v;
      }
      case Expr::Kind::binary: {
        const Value a = eval(e->args[0]), b = eval(e->args[1]);
        Value r;
        switch (e->op) {
          case '+':
          case '-':
            if (a.is_vector != b.is_vector) fail(e->at, fmt::format("cannot {} a number and a vector", e->op == '+' ? "add" : "subtract"));
            r.is_vector = a.is_vector;
            r.x = e->op == '+' ? a.x + b.x : a.x - b.x;
            r.v = e->op == '+' ? Vector3d(a.v + b.v) : Vector3d(a.v - b.v);
            return r;
          case '*':
            if (a.is_vector && b.is_vector) fail(e->at, "cannot multiply two vectors");
            r.is_vector = a.is_vector || b.is_vector;
            r.x = a.x * b.x;
            r.v = a.is_vector ? Vector3d(a.v * b.x) : Vector3d(b.v * a.x);
            return r;
          case '/':
            if (b.is_vector) fail(e->at, "cannot divide by a vector");
            if (b.x == 0.0) fail(e->at, "division by zero");
            r.is_vector = a.is_vector;
            r.x = a.x / b.x;
            r.v = a.v / b.x;
            return r;
        }
      }
    }
    fail(e->at, "malformed expression");
  }
  double number(const ExprPtr& e, const char* what) const {
    const Value v = eval(e);
    if (v.is_vector) fail(e->at, fmt::format("{} must be a number, not a vector", what));
    if (!std::isfinite(v.x)) fail(e->at, fmt::format("{} is not finite", what));
    return v.x;
  }
  Vector3d vector(const ExprPtr& e, const char* what) const {
    const Value v = eval(e);
    if (!v.is_vector) fail(e->at, fmt::format("{} must be a vector [x, y, z], not a number", what));
    if (!v.v.allFinite()) fail(e->at, fmt::format("{} is not finite", what));
    return v.v;
  }

  // NAME.PROP in an expression: the property of the selection's features, which must agree.
  Value property_value(const ExprPtr& e) const {
    const Selection sel = selection(e->name, e->at);
    if (e->property == "count") return {false, static_cast<double>(sel.size()), {}};
    if (sel.empty()) fail(e->at, fmt::format("'{}' selects no feature, so it has no {}", e->name, e->property));
    Value first;
    for (std::size_t k = 0; k < sel.size(); ++k) {
      const auto v = feature_property(sel[k], e->property, e->at);
      if (!v) fail(e->at, fmt::format("{} ({}) has no {}", ed_.id(sel[k]), features::shape_name(ed_.shape(sel[k]).type), e->property));
      if (k == 0) first = *v;
      else if ((first.is_vector ? (first.v - v->v).norm() : std::abs(first.x - v->x)) > 1e-9 * std::max(1.0, std::abs(first.x)))
        fail(e->at, fmt::format("'{}' holds {} features whose {} differ: pick one (largest, highest, nearest …)", e->name,
                                sel.size(), e->property));
    }
    return first;
  }
  std::optional<Value> feature_property(FeatureRef f, const std::string& prop, Location at) const {
    const Shape& s = ed_.shape(f);
    if (prop == "radius") {
      if (radius_of(s) <= 0.0) return std::nullopt;
      return Value{false, radius_of(s), {}};
    }
    if (prop == "half_angle") {
      if (s.type != ShapeType::cone) return std::nullopt;
      return Value{false, s.half_angle_deg, {}};
    }
    if (prop == "area") {
      if (f.kind != FeatureRef::Kind::patch) return std::nullopt;
      return Value{false, ed_.area(f), {}};
    }
    if (prop == "length") {
      if (f.kind != FeatureRef::Kind::line) return std::nullopt;
      return Value{false, s.type == ShapeType::line ? s.length : ed_.length(f), {}};
    }
    if (prop == "center") return Value{true, 0.0, ed_.centroid(f)};
    if (prop == "normal" || prop == "axis") {
      const Vector3d d = direction_of(s);
      if (d.squaredNorm() == 0.0) return std::nullopt;
      if (prop == "normal" && s.type != ShapeType::plane && s.type != ShapeType::circle && s.type != ShapeType::arc) return std::nullopt;
      if (prop == "axis" && s.type != ShapeType::cylinder && s.type != ShapeType::cone && s.type != ShapeType::line) return std::nullopt;
      return Value{true, 0.0, d};
    }
    if (prop == "count") return std::nullopt;
    fail(at, fmt::format("unknown property '{}': expected radius, half_angle, area, length, count, center, normal or axis", prop));
  }

  // ---- selections -------------------------------------------------------------------------------
  Selection selection(const std::string& name, Location at) const {
    if (auto it = selections_.find(name); it != selections_.end()) return it->second;
    if (auto f = ed_.find(name)) return {*f};
    if (values_.count(name)) fail(at, fmt::format("'{}' is a value, not a selection of features", name));
    fail(at, fmt::format("unknown name '{}': define it with 'let {} = select …' or use a feature id from features.json (P0, L3, …)",
                         name, name));
  }
  Selection nonempty(const std::string& name, Location at) const {
    Selection s = selection(name, at);
    if (s.empty())
      fail(at, fmt::format("'{}' selects no feature: nothing to edit (run with --dry-run to see what each select finds)", name));
    return s;
  }

  static bool type_matches(const std::string& type, FeatureRef f, const Shape& s) {
    if (type == "feature") return true;
    if (type == "patch") return f.kind == FeatureRef::Kind::patch;
    if (type == "curve") return f.kind == FeatureRef::Kind::line;
    return features::shape_name(s.type) == type;
  }

  bool test(const Condition& c, FeatureRef f, const Selection* whole) const {
    switch (c.kind) {
      case Condition::Kind::all_of:
        return std::all_of(c.children.begin(), c.children.end(), [&](const ConditionPtr& k) { return test(*k, f, whole); });
      case Condition::Kind::any_of:
        return std::any_of(c.children.begin(), c.children.end(), [&](const ConditionPtr& k) { return test(*k, f, whole); });
      case Condition::Kind::negate: return !test(*c.children[0], f, whole);
      case Condition::Kind::adjacent: {
        const Selection other = selection(c.name, c.at);
        const auto nb = ed_.neighbours(f);
        return std::any_of(other.begin(), other.end(), [&](FeatureRef o) {
          return o != f && std::find(nb.begin(), nb.end(), o) != nb.end();
        });
      }
      case Condition::Kind::near_point: {
        const Vector3d p = vector(c.value, "the point");
        return (ed_.centroid(f) - p).norm() <= number(c.tolerance, "the tolerance");
      }
      case Condition::Kind::direction:
      case Condition::Kind::parallel_axis: {
        const auto d = feature_property(f, c.property, c.at);
        if (!d) return false;
        const Vector3d want = vector(c.value, "the direction");
        if (want.norm() == 0.0) fail(c.value->at, "the direction is the zero vector");
        const double tol = c.tolerance ? number(c.tolerance, "the angle tolerance") : kDefaultDirectionTolDeg;
        const double cosang = d->v.normalized().dot(want.normalized());
        const double ang = c.kind == Condition::Kind::parallel_axis ? line_angle_deg(d->v, want)
                                                                     : std::acos(std::clamp(cosang, -1.0, 1.0)) * 180.0 / M_PI;
        return ang <= tol;
      }
      case Condition::Kind::compare:
      case Condition::Kind::approx: {
        double have;
        if (c.property == "count") {
          if (!whole) fail(c.at, "count is a property of a selection: use it in assert NAME.count …");
          have = static_cast<double>(whole->size());
        } else {
          const auto v = feature_property(f, c.property, c.at);
          if (!v) return false;
          have = v->x;
        }
        const double want = number(c.value, "the value compared with");
        if (c.kind == Condition::Kind::approx) {
          const double tol = c.tolerance ? number(c.tolerance, "the tolerance") : kDefaultRelativeTol * std::abs(want);
          return std::abs(have - want) <= tol;
        }
        if (c.op == "<") return have < want;
        if (c.op == "<=") return have <= want;
        if (c.op == ">") return have > want;
        if (c.op == ">=") return have >= want;
        return std::abs(have - want) <= 1e-9 * std::max(1.0, std::abs(want));
      }
    }
    return false;
  }

  Selection select(const Selector& s) const {
    Selection out;
    for (FeatureRef f : ed_.all())
      if (type_matches(s.type, f, ed_.shape(f)) && (!s.where || test(*s.where, f, nullptr))) out.push_back(f);
    if (s.picker == Picker::none || out.empty()) return out;
    auto key = [&](FeatureRef f) -> double {
      switch (s.picker) {
        case Picker::highest:
        case Picker::lowest: {
          Vector3d d = Vector3d::UnitZ();
          if (s.picker_arg) {
            d = vector(s.picker_arg, "the direction");
            if (d.norm() == 0.0) fail(s.picker_arg->at, "the direction is the zero vector");
            d.normalize();
          }
          const double h = ed_.centroid(f).dot(d);
          return s.picker == Picker::highest ? h : -h;
        }
        case Picker::largest:
        case Picker::smallest: {
          const double size = f.kind == FeatureRef::Kind::patch ? ed_.area(f) : ed_.length(f);
          return s.picker == Picker::largest ? size : -size;
        }
        case Picker::nearest: return -(ed_.centroid(f) - vector(s.picker_arg, "the point")).norm();
        default: return 0.0;
      }
    };
    FeatureRef best = out[0];
    double best_key = key(best);
    for (FeatureRef f : out)
      if (const double k = key(f); k > best_key + 1e-12) {
        best = f;
        best_key = k;
      }
    return {best};
  }

  std::string describe(FeatureRef f) const {
    const Shape& s = ed_.shape(f);
    switch (s.type) {
      case ShapeType::plane:
        return fmt::format("{} plane normal [{:.3g}, {:.3g}, {:.3g}] area {:.4g}", ed_.id(f), s.dir.x(), s.dir.y(), s.dir.z(), ed_.area(f));
      case ShapeType::cylinder:
        return fmt::format("{} cylinder r {:.4g} axis [{:.3g}, {:.3g}, {:.3g}]", ed_.id(f), s.radius, s.dir.x(), s.dir.y(), s.dir.z());
      case ShapeType::sphere: return fmt::format("{} sphere r {:.4g}", ed_.id(f), s.radius);
      case ShapeType::cone: return fmt::format("{} cone half angle {:.4g}°", ed_.id(f), s.half_angle_deg);
      case ShapeType::line: return fmt::format("{} line length {:.4g}", ed_.id(f), s.length);
      case ShapeType::circle:
      case ShapeType::arc: return fmt::format("{} {} r {:.4g}", ed_.id(f), features::shape_name(s.type), s.radius);
      default: return fmt::format("{} freeform", ed_.id(f));
    }
  }
  std::vector<std::string> ids(const Selection& s) const {
    std::vector<std::string> out;
    for (FeatureRef f : s) out.push_back(ed_.id(f));
    return out;
  }
  void say_edit(const EditReport& r) const {
    for (const auto& p : r.propagation) say("  propagates: " + p);
    if (!r.carried.empty()) {
      std::vector<std::string> names;
      for (FeatureRef f : r.carried) names.push_back(ed_.id(f));
      say(fmt::format("  carries {} crumb patch(es) lying on the edited surfaces: {}", names.size(), fmt::join(names, ", ")));
    }
    say(fmt::format("  moves {} vertices on the edited features, solves {} on {} neighbouring patches (ARAP, {} iterations{}), "
                    "largest displacement {:.4g} mm, {:.3g} ms",
                    r.handle_vertices, r.free_vertices, r.free.size(), r.arap_iterations,
                    r.factorization_reused ? ", factorisation reused" : "", r.max_displacement, r.seconds * 1e3));
    for (const auto& b : r.broken) say("  warning: " + b);
  }

  // The features of every member, each once, in order.
  Selection members(const Statement& st) const {
    Selection out;
    for (std::size_t k = 0; k < st.members.size(); ++k)
      for (FeatureRef f : nonempty(st.members[k], st.member_at[k]))
        if (std::find(out.begin(), out.end(), f) == out.end()) out.push_back(f);
    return out;
  }

  void execute(const Statement& st, StatementReport& rep, ScriptResult& result) {
    say(fmt::format("line {}: {}", st.at.line, st.text));
    switch (st.kind) {
      case Statement::Kind::param: {
        Value v;
        if (auto it = opt_.overrides.find(st.name); it != opt_.overrides.end()) {
          v = eval(parse_expression(it->second, fmt::format("--set {}={}", st.name, it->second)));
          say(fmt::format("  {} = {} (from --set)", st.name, it->second));
        } else {
          v = eval(st.value);
        }
        values_[st.name] = v;
        return;
      }
      case Statement::Kind::let_value:
        values_[st.name] = eval(st.value);
        selections_.erase(st.name);
        return;
      case Statement::Kind::let_select: {
        const Selection s = select(st.selector);
        selections_[st.name] = s;
        values_.erase(st.name);
        rep.selected = ids(s);
        if (s.empty()) say("  selects nothing");
        for (FeatureRef f : s) say("  selects " + describe(f));
        return;
      }
      case Statement::Kind::set: {
        const Selection s = nonempty(st.name, st.name_at);
        rep.selected = ids(s);
        const double v = number(st.value, st.property.c_str());
        rep.edit = st.property == "radius" ? ed_.set_radius(s, v) : ed_.set_half_angle(s, v);
        break;
      }
      case Statement::Kind::move: {
        const Selection s = nonempty(st.name, st.name_at);
        rep.selected = ids(s);
        rep.edit = ed_.move(s, vector(st.value, "the displacement"));
        break;
      }
      case Statement::Kind::move_vertex: {
        const double index = number(st.axis, "the vertex index");
        const int nv = static_cast<int>(ed_.mesh().n_vertices());
        if (index != std::floor(index) || index < 0 || index >= nv)
          fail(st.axis->at, fmt::format("vertex {} does not exist: the mesh has vertices 0 to {}", index, nv - 1));
        const int v = static_cast<int>(index);
        const Vector3d by = vector(st.value, "the displacement");
        rep.selected = {fmt::format("vertex {}", v)};
        rep.edit = ed_.move_vertices({v}, {to_eigen(ed_.mesh().point(OpenMesh::VertexHandle(v))) + by});
        say_edit(rep.edit);
        return;
      }
      case Statement::Kind::rotate: {
        const Selection s = nonempty(st.name, st.name_at);
        rep.selected = ids(s);
        const Vector3d axis = vector(st.axis, "the axis");
        if (axis.norm() == 0.0) fail(st.axis->at, "the rotation axis is the zero vector");
        std::optional<Vector3d> pivot;
        if (st.pivot) pivot = vector(st.pivot, "the pivot point");
        rep.edit = ed_.rotate(s, axis, number(st.value, "the angle"), pivot);
        break;
      }
      case Statement::Kind::scale: {
        const Selection s = nonempty(st.name, st.name_at);
        rep.selected = ids(s);
        std::optional<Vector3d> pivot;
        if (st.pivot) pivot = vector(st.pivot, "the pivot point");
        rep.edit = ed_.scale(s, number(st.value, "the factor"), pivot);
        break;
      }
      case Statement::Kind::constrain: {
        const Selection s = members(st);
        rep.selected = ids(s);
        std::optional<double> value;
        if (st.value) value = number(st.value, "the constraint value");
        rep.edit = ed_.constrain(features::constraint_kind(st.constraint), s, value);
        break;
      }
      case Statement::Kind::unconstrain: {
        Selection s;
        std::optional<features::ConstraintKind> kind;
        if (!st.constraint.empty()) {
          s = members(st);
          kind = features::constraint_kind(st.constraint);
        } else {
          s = nonempty(st.name, st.name_at);
        }
        rep.selected = ids(s);
        const int n = ed_.unconstrain(kind, s);
        say(fmt::format("  removed from {} constraint group(s)", n));
        if (n == 0) say("  warning: no constraint matched");
        return;
      }
      case Statement::Kind::lock: {
        const Selection s = nonempty(st.name, st.name_at);
        rep.selected = ids(s);
        for (FeatureRef f : s) ed_.lock(f);
        say(fmt::format("  locks {}", fmt::join(rep.selected, ", ")));
        return;
      }
      case Statement::Kind::check: {
        check(st, rep);
        ++result.asserts;
        say("  holds");
        return;
      }
      case Statement::Kind::export_mesh:
        result.exports.emplace_back(st.path, ed_.mesh());
        say(fmt::format("  will write {} when the script has finished", st.path));
        return;
    }
    for (const auto& id : rep.selected) say("  edits " + describe(*ed_.find(id)));
    say_edit(rep.edit);
  }

  void check(const Statement& st, StatementReport& rep) const {
    if (!st.constraint.empty()) {
      const Selection s = members(st);
      rep.selected = ids(s);
      const auto kind = features::constraint_kind(st.constraint);
      const auto& o = ed_.options();
      std::optional<double> value;
      if (st.value) value = number(st.value, "the constraint value");
      for (std::size_t k = 1; k < s.size(); ++k) {
        const auto r = pair_residual({kind, value, {}}, ed_.shape(s[0]), ed_.shape(s[k]));
        if (!r.checked)
          fail(st.at, fmt::format("{} cannot be measured between {} and {}", st.constraint, ed_.id(s[0]), ed_.id(s[k])));
        if (!holds(r, o.angle_tolerance_deg, o.length_tolerance))
          throw ProcessingError(fmt::format("assert failed: {}({}, {}) is off by {:.4g}° and {:.4g} mm (tolerance {}°, {} mm)",
                                            st.constraint, ed_.id(s[0]), ed_.id(s[k]), r.angle_deg, r.length,
                                            o.angle_tolerance_deg, o.length_tolerance));
      }
      return;
    }
    const Selection s = selection(st.name, st.name_at);
    rep.selected = ids(s);
    if (st.property == "count") {
      if (!test(*st.condition, FeatureRef{}, &s))
        throw ProcessingError(fmt::format("assert failed: {} holds {} feature(s)", st.name, s.size()));
      return;
    }
    if (s.empty()) throw ProcessingError(fmt::format("assert failed: '{}' selects no feature", st.name));
    for (FeatureRef f : s) {
      if (test(*st.condition, f, &s)) continue;
      const auto v = feature_property(f, st.property, st.at);
      std::string have = !v ? fmt::format("{} has no {}", ed_.id(f), st.property)
                            : v->is_vector ? fmt::format("{}.{} = [{:.4g}, {:.4g}, {:.4g}]", ed_.id(f), st.property, v->v.x(), v->v.y(), v->v.z())
                                           : fmt::format("{}.{} = {:.6g}", ed_.id(f), st.property, v->x);
      throw ProcessingError(fmt::format("assert failed: {}", have));
    }
  }

  const Script& script_;
  Editor& ed_;
  const ScriptOptions& opt_;
  std::map<std::string, Value> values_;
  std::map<std::string, Selection> selections_;
};

}  // namespace

ScriptResult run_script(const Script& script, Editor& editor, const ScriptOptions& options) {
  return Interpreter(script, editor, options).run();
}

}  // namespace s2c::edit
