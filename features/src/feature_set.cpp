// features.json ("scan2cad.features/1"): writing and strict reading. Reading names the file and
// the offending element, because edit refuses to work from a features file it cannot trust.
#include "s2c/features/feature_set.h"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <functional>
#include <iterator>
#include <set>
#include <string_view>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <tbb/parallel_pipeline.h>

#include "s2c/core/errors.h"
#include "s2c/core/files.h"

namespace s2c::features {
namespace {

using nlohmann::json;
constexpr const char* kFormat = "scan2cad.features/1";

constexpr const char* kConstraintNames[] = {"equal_length", "connected",     "collinear",   "parallel",
                                            "concentric",   "coaxial",       "perpendicular", "fixed_angle",
                                            "equal_angle",  "symmetric",     "equal_radius"};

/// True for a value printed in one piece: not an object, not an array.
bool scalar(const json& j) { return !j.is_object() && !j.is_array(); }

/// Appends face indices as print() appends an array of integers, straight to digits (a
/// million-face part's patches hold two million of them; they are not in the JSON tree).
void print_indices(const std::vector<int>& indices, std::string& out) {
  // Into room made for the longest numbers, then cut to what was printed: appending two
  // separators and the digits one call at a time cost three times the printing.
  constexpr std::size_t kMaxChars = 13;  // ", " and an int's up to eleven characters
  const std::size_t start = out.size();
  out.resize(start + 2 + kMaxChars * indices.size());
  char* at = out.data() + start;
  char* const end = out.data() + out.size();
  *at++ = '[';
  for (std::size_t k = 0; k < indices.size(); ++k) {
    if (k > 0) *at++ = ',', *at++ = ' ';
    at = std::to_chars(at, end, indices[k]).ptr;
  }
  *at++ = ']';
  out.resize(static_cast<std::size_t>(at - out.data()));
}

/// Appends `j` as dump(1) does, except that an array of scalars goes on one line: a million-face
/// part's patches list two million face indices, which one per line made a 25 MB file (17 MB so).
/// `faces`, when given, is printed as the value of the key "faces" of the object `j` (a patch's:
/// not copied into the JSON tree first).
void print(const json& j, int depth, std::string& out, const std::vector<int>* faces = nullptr) {
  auto newline = [&](int d) {
    out += '\n';
    out.append(static_cast<std::size_t>(d), ' ');
  };
  if (j.is_object() && !j.empty()) {
    out += '{';
    const char* sep = "";
    for (const auto& [key, value] : j.items()) {
      out += sep;
      newline(depth + 1);
      out += json(key).dump();
      out += ": ";
      if (faces && key == "faces")
        print_indices(*faces, out);
      else
        print(value, depth + 1, out);
      sep = ",";
    }
    newline(depth);
    out += '}';
  } else if (j.is_array() && !j.empty()) {
    // The elements as the vector they are: json's own iterators cost more than the printing.
    const auto& items = j.get_ref<const json::array_t&>();
    const bool flat = std::all_of(items.begin(), items.end(), scalar);
    out += '[';
    for (std::size_t k = 0; k < items.size(); ++k) {
      if (k > 0) out += flat ? ", " : ",";
      if (!flat) newline(depth + 1);
      print(items[k], depth + 1, out);
    }
    if (!flat) newline(depth);
    out += ']';
  } else {
    out += j.dump();
  }
}

json vec(const Eigen::Vector3d& v) { return json::array({v.x(), v.y(), v.z()}); }

json shape_json(const Shape& s) {
  json j = {{"type", shape_name(s.type)}};
  switch (s.type) {
    case ShapeType::plane: j["normal"] = vec(s.dir); j["point"] = vec(s.point); break;
    case ShapeType::cylinder:
      j["axis_point"] = vec(s.point); j["axis_dir"] = vec(s.dir); j["radius"] = s.radius; break;
    case ShapeType::sphere: j["center"] = vec(s.point); j["radius"] = s.radius; break;
    case ShapeType::cone:
      j["apex"] = vec(s.point); j["axis_dir"] = vec(s.dir); j["half_angle_deg"] = s.half_angle_deg; break;
    case ShapeType::line: j["point"] = vec(s.point); j["direction"] = vec(s.dir); j["length"] = s.length; break;
    case ShapeType::arc:
      j["start"] = vec(s.start); j["end"] = vec(s.end); j["angle_deg"] = s.angle_deg;
      [[fallthrough]];
    case ShapeType::circle: j["center"] = vec(s.point); j["normal"] = vec(s.dir); j["radius"] = s.radius; break;
    case ShapeType::freeform: break;
  }
  return j;
}

json attributes_json(const Attributes& a) {
  json j = json::object();
  for (const auto& [k, v] : a) j[k] = json::parse(v);
  return j;
}

/// Reads with a path for messages: "features.json: patches[3].shape.radius: expected a number".
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const std::string& where, const std::string& what) const {
    throw InvalidInput(fmt::format("{}: {}: {}", source_, where, what));
  }
  const json& key(const json& obj, const char* k, const std::string& where) const {
    if (!obj.is_object()) fail(where, "expected an object");
    auto it = obj.find(k);
    if (it == obj.end()) fail(where, fmt::format("missing key \"{}\"", k));
    return *it;
  }
  double number(const json& obj, const char* k, const std::string& where) const {
    const json& v = key(obj, k, where);
    if (!v.is_number() || !std::isfinite(v.get<double>())) fail(where + "." + k, "expected a finite number");
    return v.get<double>();
  }
  std::string string(const json& obj, const char* k, const std::string& where) const {
    const json& v = key(obj, k, where);
    if (!v.is_string()) fail(where + "." + k, "expected a string");
    return v.get<std::string>();
  }
  Eigen::Vector3d vector(const json& obj, const char* k, const std::string& where, bool unit = false) const {
    const json& v = key(obj, k, where);
    if (!v.is_array() || v.size() != 3) fail(where + "." + k, "expected [x, y, z]");
    Eigen::Vector3d p;
    for (int i = 0; i < 3; ++i) {
      if (!v[i].is_number() || !std::isfinite(v[i].get<double>())) fail(where + "." + k, "expected finite numbers");
      p[i] = v[i].get<double>();
    }
    if (unit) {
      if (p.norm() < 1e-9) fail(where + "." + k, "zero-length direction");
      p.normalize();
    }
    return p;
  }
  std::vector<int> indices(const json& obj, const char* k, const std::string& where, int limit) const {
    const json& v = key(obj, k, where);
    if (!v.is_array()) fail(where + "." + k, "expected an array of indices");
    std::vector<int> out;
    out.reserve(v.size());
    for (std::size_t i = 0; i < v.size(); ++i) {
      if (!v[i].is_number_integer()) fail(fmt::format("{}.{}[{}]", where, k, i), "expected an integer");
      const auto x = v[i].get<long long>();
      if (x < 0 || x >= limit)
        fail(fmt::format("{}.{}[{}]", where, k, i), fmt::format("index {} outside the mesh (0..{})", x, limit - 1));
      out.push_back(static_cast<int>(x));
    }
    return out;
  }

  Shape shape(const json& obj, const std::string& where) const {
    const json& j = key(obj, "shape", where);
    const std::string w = where + ".shape";
    Shape s;
    try {
      s.type = shape_type(string(j, "type", w));
    } catch (const InvalidInput& e) {
      fail(w + ".type", e.what());
    }
    auto positive = [&](const char* k) {
      const double r = number(j, k, w);
      if (r <= 0) fail(w + "." + k, "must be positive");
      return r;
    };
    switch (s.type) {
      case ShapeType::plane: s.dir = vector(j, "normal", w, true); s.point = vector(j, "point", w); break;
      case ShapeType::cylinder:
        s.point = vector(j, "axis_point", w); s.dir = vector(j, "axis_dir", w, true); s.radius = positive("radius"); break;
      case ShapeType::sphere: s.point = vector(j, "center", w); s.radius = positive("radius"); break;
      case ShapeType::cone:
        s.point = vector(j, "apex", w); s.dir = vector(j, "axis_dir", w, true);
        s.half_angle_deg = positive("half_angle_deg");
        if (s.half_angle_deg >= 90) fail(w + ".half_angle_deg", "must be below 90");
        break;
      case ShapeType::line:
        s.point = vector(j, "point", w); s.dir = vector(j, "direction", w, true); s.length = number(j, "length", w);
        break;
      case ShapeType::arc:
        s.start = vector(j, "start", w); s.end = vector(j, "end", w); s.angle_deg = number(j, "angle_deg", w);
        [[fallthrough]];
      case ShapeType::circle:
        s.point = vector(j, "center", w); s.dir = vector(j, "normal", w, true); s.radius = positive("radius"); break;
      case ShapeType::freeform: break;
    }
    return s;
  }

  Attributes attributes(const json& obj, const std::string& where) const {
    Attributes a;
    auto it = obj.find("attributes");
    if (it == obj.end()) return a;
    if (!it->is_object()) fail(where + ".attributes", "expected an object");
    for (const auto& [k, v] : it->items()) a[k] = v.dump();
    return a;
  }

 private:
  std::string source_;
};

}  // namespace

const char* constraint_name(ConstraintKind kind) { return kConstraintNames[static_cast<int>(kind)]; }

ConstraintKind constraint_kind(const std::string& name) {
  for (int i = 0; i < static_cast<int>(std::size(kConstraintNames)); ++i)
    if (name == kConstraintNames[i]) return static_cast<ConstraintKind>(i);
  throw InvalidInput(fmt::format("unknown constraint kind \"{}\"", name));
}

namespace {

/// The JSON text of `f` in pieces, in order, to `sink`. The patches, most of the text (their
/// faces), are printed side by side while the sink takes the ones before them: writing to a file
/// goes on while the rest is printed.
void emit_json_text(const FeatureSet& f, const std::function<void(std::string_view)>& sink) {
  json doc = {{"format", kFormat},
              {"mesh", {{"vertices", f.mesh_vertices}, {"faces", f.mesh_faces}, {"sha256", f.mesh_sha256}}}};
  json lines = json::array(), groups = json::array(), adjacency = json::array();
  for (const auto& l : f.lines)
    lines.push_back({{"id", l.id}, {"vertices", l.vertices}, {"closed", l.closed}, {"rms", l.rms},
                     {"shape", shape_json(l.shape)}, {"attributes", attributes_json(l.attributes)}});
  for (const auto& g : f.groups) {
    json j = {{"id", g.id}, {"kind", g.kind}, {"members", g.members}};
    if (g.constraint) j["constraint"] = constraint_name(*g.constraint);
    if (g.value) j["value"] = *g.value;
    j["attributes"] = attributes_json(g.attributes);
    groups.push_back(std::move(j));
  }
  for (const auto& [a, b] : f.adjacency) adjacency.push_back({a, b});
  doc["lines"] = std::move(lines);
  doc["groups"] = std::move(groups);
  doc["adjacency"] = std::move(adjacency);
  std::string head;
  print(doc, 0, head);
  // "patches" sorts after every other key of the document: the object is reopened for it.
  head.resize(head.size() - 2);  // "\n}"
  head += ",\n \"patches\": [";
  sink(head);
  // A patch's faces stay where they are: print() takes them from the patch.
  std::size_t next = 0;
  const std::size_t count = f.patches.size();
  tbb::parallel_pipeline(
      8, tbb::make_filter<void, std::size_t>(tbb::filter_mode::serial_in_order,
                                             [&](tbb::flow_control& fc) {
                                               if (next == count) fc.stop();
                                               return next++;
                                             }) &
             tbb::make_filter<std::size_t, std::string>(
                 tbb::filter_mode::parallel,
                 [&](std::size_t k) {
                   const Patch& p = f.patches[k];
                   const json j = {{"id", p.id},     {"faces", json::array()},      {"area", p.area},
                                   {"rms", p.rms},   {"shape", shape_json(p.shape)}, {"attributes", attributes_json(p.attributes)}};
                   std::string part = k > 0 ? ",\n  " : "\n  ";
                   part.reserve(14 * p.faces.size() + 4096);  // (print_indices makes room for 13 a face)
                   print(j, 2, part, &p.faces);
                   return part;
                 }) &
             tbb::make_filter<std::string, void>(tbb::filter_mode::serial_in_order,
                                                 [&](const std::string& part) { sink(part); }));
  sink(count == 0 ? "]\n}\n" : "\n ]\n}\n");
}

}  // namespace

std::string to_json_text(const FeatureSet& f) {
  std::string text;
  emit_json_text(f, [&](std::string_view piece) { text += piece; });
  return text;
}

FeatureSet from_json_text(const std::string& text, const std::string& source) {
  const Reader r(source);
  json doc;
  try {
    doc = json::parse(text);
  } catch (const json::parse_error& e) {
    throw InvalidInput(fmt::format("{}: not valid JSON (byte {}): {}", source, e.byte, e.what()));
  } catch (const json::exception& e) {  // e.g. a number too large for a double (found by fuzzing)
    throw InvalidInput(fmt::format("{}: not valid JSON: {}", source, e.what()));
  }
  if (!doc.is_object()) r.fail("document", "expected a JSON object");
  if (r.string(doc, "format", "document") != kFormat)
    r.fail("format", fmt::format("expected \"{}\", got \"{}\"", kFormat, doc["format"].get<std::string>()));
  FeatureSet f;
  const json& mesh = r.key(doc, "mesh", "document");
  const double nv = r.number(mesh, "vertices", "mesh"), nf = r.number(mesh, "faces", "mesh");
  if (nv < 0 || nf < 0 || nv > 2e9 || nf > 2e9) r.fail("mesh", "vertex/face counts out of range");
  f.mesh_vertices = static_cast<int>(nv);
  f.mesh_faces = static_cast<int>(nf);
  f.mesh_sha256 = r.string(mesh, "sha256", "mesh");

  std::set<std::string> ids;
  auto take_id = [&](const json& obj, const std::string& where) {
    std::string id = r.string(obj, "id", where);
    if (id.empty()) r.fail(where + ".id", "empty id");
    if (!ids.insert(id).second) r.fail(where + ".id", fmt::format("duplicate id \"{}\"", id));
    return id;
  };
  auto array = [&](const char* k) -> const json& {
    const json& a = r.key(doc, k, "document");
    if (!a.is_array()) r.fail(k, "expected an array");
    return a;
  };
  const json& patches = array("patches");
  for (std::size_t i = 0; i < patches.size(); ++i) {
    const std::string w = fmt::format("patches[{}]", i);
    Patch p;
    p.id = take_id(patches[i], w);
    p.faces = r.indices(patches[i], "faces", w, f.mesh_faces);
    p.area = r.number(patches[i], "area", w);
    p.rms = r.number(patches[i], "rms", w);
    p.shape = r.shape(patches[i], w);
    if (!is_surface(p.shape.type) && p.shape.type != ShapeType::freeform)
      r.fail(w + ".shape.type", "a patch needs a surface shape (plane, cylinder, sphere, cone, freeform)");
    p.attributes = r.attributes(patches[i], w);
    f.patches.push_back(std::move(p));
  }
  const json& lines = array("lines");
  for (std::size_t i = 0; i < lines.size(); ++i) {
    const std::string w = fmt::format("lines[{}]", i);
    Line l;
    l.id = take_id(lines[i], w);
    l.vertices = r.indices(lines[i], "vertices", w, f.mesh_vertices);
    const json& closed = r.key(lines[i], "closed", w);
    if (!closed.is_boolean()) r.fail(w + ".closed", "expected true or false");
    l.closed = closed.get<bool>();
    l.rms = r.number(lines[i], "rms", w);
    l.shape = r.shape(lines[i], w);
    if (is_surface(l.shape.type)) r.fail(w + ".shape.type", "a line needs a curve shape (line, circle, arc, freeform)");
    l.attributes = r.attributes(lines[i], w);
    f.lines.push_back(std::move(l));
  }
  const json& groups = array("groups");
  for (std::size_t i = 0; i < groups.size(); ++i) {
    const std::string w = fmt::format("groups[{}]", i);
    Group g;
    g.id = take_id(groups[i], w);
    g.kind = r.string(groups[i], "kind", w);
    if (groups[i].contains("constraint")) {
      try {
        g.constraint = constraint_kind(r.string(groups[i], "constraint", w));
      } catch (const InvalidInput& e) {
        r.fail(w + ".constraint", e.what());
      }
    } else if (g.kind == "constraint") {
      r.fail(w, "a constraint group needs a \"constraint\" kind");
    }
    const json& members = r.key(groups[i], "members", w);
    if (!members.is_array()) r.fail(w + ".members", "expected an array of feature ids");
    for (const auto& m : members) {
      if (!m.is_string()) r.fail(w + ".members", "expected feature ids (strings)");
      g.members.push_back(m.get<std::string>());
    }
    if (groups[i].contains("value")) g.value = r.number(groups[i], "value", w);
    g.attributes = r.attributes(groups[i], w);
    f.groups.push_back(std::move(g));
  }
  // Members and adjacency must name features that exist (groups may name later groups).
  for (std::size_t i = 0; i < f.groups.size(); ++i)
    for (const auto& m : f.groups[i].members)
      if (!ids.count(m)) r.fail(fmt::format("groups[{}].members", i), fmt::format("unknown feature id \"{}\"", m));
  const json& adjacency = array("adjacency");
  for (std::size_t i = 0; i < adjacency.size(); ++i) {
    const json& a = adjacency[i];
    const std::string w = fmt::format("adjacency[{}]", i);
    if (!a.is_array() || a.size() != 2 || !a[0].is_string() || !a[1].is_string())
      r.fail(w, "expected a pair of feature ids");
    for (int k = 0; k < 2; ++k)
      if (!ids.count(a[k].get<std::string>())) r.fail(w, fmt::format("unknown feature id \"{}\"", a[k].get<std::string>()));
    f.adjacency.emplace_back(a[0].get<std::string>(), a[1].get<std::string>());
  }
  return f;
}

void write_features(const FeatureSet& features, const std::filesystem::path& path) {
  AtomicStream out(path);
  emit_json_text(features, [&](std::string_view piece) { out.write(piece); });
  out.commit();
}

FeatureSet read_features(const std::filesystem::path& path) {
  return from_json_text(read_file(path), path.string());
}

}  // namespace s2c::features
