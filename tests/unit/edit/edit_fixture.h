#pragma once
// Fixture parts for the edit tests: the OpenSCAD mesh (or a refined copy) with its features from
// the features stage, the truth, and independent checks of the edited mesh: vertices are picked by
// the truth surfaces they lay on before the edit and refitted after it.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "features_eval.h"
#include "s2c/core/check.h"
#include "s2c/core/io.h"
#include "s2c/edit/editor.h"
#include "s2c/edit/interpreter.h"
#include "s2c/features/analyze.h"
#include "s2c/features/shape.h"
#include "test_util.h"

namespace s2c::test {

struct EditPart {
  Mesh mesh;
  features::FeatureSet features;
  bench::Truth truth;
  std::vector<Eigen::Vector3d> before;  ///< vertex positions before any edit
};

/// `refine_edge` > 0: refined by longest-edge bisection to that edge length (interior vertices).
inline EditPart load_edit_part(const std::string& name, double refine_edge = 0.0) {
  EditPart p;
  p.truth = bench::read_truth(source_dir() / "fixtures/parts" / (name + ".truth.json"));
  p.mesh = read_mesh(source_dir() / "fixtures/parts" / (name + ".stl"));
  if (refine_edge > 0.0) p.mesh = bench::refine_mesh(p.mesh, refine_edge);
  p.mesh.update_normals();
  p.features = features::analyze(p.mesh, {}).features;
  for (auto v : p.mesh.vertices()) p.before.push_back(to_eigen(p.mesh.point(v)));
  return p;
}

inline const bench::TruthFeature& truth_primitive(const EditPart& p, const std::string& id) {
  for (const auto& t : p.truth.primitives)
    if (t.id == id) return t;
  throw std::runtime_error("no truth primitive " + id);
}

/// Vertices that lay on the truth primitive before the edit (within 1e-3 mm of the surface,
/// bounded by the truth mesh's box so infinite planes do not pick up other faces).
inline std::vector<int> on_primitive(const EditPart& p, const std::string& id, double tol = 1e-3) {
  const auto& t = truth_primitive(p, id);
  std::vector<int> out;
  for (int v = 0; v < static_cast<int>(p.before.size()); ++v)
    if (bench::shape_distance(t.shape, p.before[v]) < tol) out.push_back(v);
  return out;
}

/// The shape of the given type refitted to the vertices' positions in `mesh`.
inline features::Fit refit(const Mesh& mesh, const std::vector<int>& vs, features::ShapeType type) {
  features::Samples s;
  for (int v : vs) s.points.push_back(to_eigen(mesh.point(OpenMesh::VertexHandle(v))));
  switch (type) {
    case features::ShapeType::plane: return features::fit_plane(s);
    case features::ShapeType::cylinder: return features::fit_cylinder(s);
    case features::ShapeType::sphere: return features::fit_sphere(s);
    default: return features::fit_cone(s);
  }
}

inline double displacement(const EditPart& p, const Mesh& mesh, int v) {
  return (to_eigen(mesh.point(OpenMesh::VertexHandle(v))) - p.before[v]).norm();
}

/// Runs a script on the part; returns the editor.
inline edit::Editor run_on(const EditPart& p, const std::string& script, edit::EditOptions o = {}) {
  edit::Editor ed(p.mesh, p.features, o);
  edit::run_script(edit::parse_script(script, "t.s2e"), ed);
  return ed;
}

inline CheckResult check(const Mesh& mesh) { return check_mesh(mesh_to_soup(mesh)); }

}  // namespace s2c::test
