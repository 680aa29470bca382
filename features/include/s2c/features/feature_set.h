#pragma once
/// \file The hyper-mesh of features.json ("scan2cad.features/1", DESIGN.md): feature patches
/// (face sets with a surface shape), feature lines (vertex chains with a curve shape), groups
/// (constraints and components, which may contain groups) and the adjacency between features.
#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "s2c/features/shape.h"

namespace s2c::features {

/// User key-value attributes; each value is kept as its JSON text so any JSON value round-trips.
using Attributes = std::map<std::string, std::string>;

struct Patch {
  std::string id;          ///< "P0", "P1", …
  std::vector<int> faces;  ///< face indices into the mesh
  double area = 0.0;       ///< mm²
  double rms = 0.0;        ///< RMS distance of the patch's vertices to its shape, mm
  Shape shape;             ///< plane | cylinder | sphere | cone | freeform
  Attributes attributes;
};

struct Line {
  std::string id;             ///< "L0", …
  std::vector<int> vertices;  ///< mesh vertex indices in order along the curve
  bool closed = false;        ///< last vertex connects back to the first
  double rms = 0.0;
  Shape shape;                ///< line | circle | arc | freeform (polyline)
  Attributes attributes;
};

/// The constraint kinds of DESIGN.md (the paper's ten plus equal_radius).
enum class ConstraintKind {
  equal_length, connected, collinear, parallel, concentric, coaxial, perpendicular, fixed_angle,
  equal_angle, symmetric, equal_radius
};
const char* constraint_name(ConstraintKind kind);
/// \throw InvalidInput for an unknown name.
ConstraintKind constraint_kind(const std::string& name);

struct Group {
  std::string id;                    ///< "G0", …
  std::string kind;                  ///< "constraint" | "component" (or a user kind)
  std::optional<ConstraintKind> constraint;  ///< set when kind == "constraint"
  std::vector<std::string> members;  ///< ids of patches, lines or groups
  std::optional<double> value;       ///< fixed_angle / equal_angle (degrees), symmetric, …
  Attributes attributes;
};

struct FeatureSet {
  int mesh_vertices = 0, mesh_faces = 0;
  std::string mesh_sha256;  ///< of the mesh file the features were computed on
  std::vector<Patch> patches;
  std::vector<Line> lines;
  std::vector<Group> groups;
  std::vector<std::pair<std::string, std::string>> adjacency;  ///< unordered pairs of feature ids
};

/// Serialises to the JSON text of features.json.
std::string to_json_text(const FeatureSet& features);
/// Parses features.json text. `source` names the file in error messages.
/// \throw InvalidInput naming the file and the offending key / element.
FeatureSet from_json_text(const std::string& text, const std::string& source);

/// Writes atomically. \throw IoError
void write_features(const FeatureSet& features, const std::filesystem::path& path);
/// \throw InvalidInput (malformed), IoError (unreadable)
FeatureSet read_features(const std::filesystem::path& path);

}  // namespace s2c::features
