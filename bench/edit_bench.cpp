// s2c-bench-edit: the edit stage's benchmark (issue 6) and its independent verification.
//
//   refit EDITED ORIGINAL TRUTH.json   the truth primitives refitted on an edited mesh: the vertices
//                                       that lay on each primitive in ORIGINAL (by the truth labels
//                                       of their faces) are refitted at their EDITED positions.
//   speed [--part plate] [--vertices 50000] [--steps 20]
//                                       a parametric edit on the part refined to N vertices:
//                                       full propagation (first edit, fresh factorisation), then
//                                       interactive steps (same region, factorisation reused), the
//                                       same with ARAP over the whole mesh, and the accuracy
//                                       (refitted radius, constraint residual, displacement beyond
//                                       the region).
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <set>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "features_eval.h"
#include "s2c/core/cli.h"
#include "s2c/core/clock.h"
#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "s2c/core/io.h"
#include "s2c/edit/editor.h"
#include "s2c/features/analyze.h"
#include "s2c/features/shape.h"

namespace {

using namespace s2c;
using Eigen::Vector3d;
using features::ShapeType;
using json = nlohmann::json;

// Per truth primitive: the vertices of faces labelled with it (the truth labels of `mesh`) that lie
// within `pick_mm` of its surface. On a CAD tessellation every vertex sits on a border, so a rim
// vertex counts for both the hole and the plane it bounds.
std::vector<std::vector<int>> primitive_vertices(const Mesh& mesh, const bench::Truth& truth, double pick_mm) {
  bench::Tolerances tol;
  tol.label_max_mm = pick_mm;
  const std::vector<int> labels = bench::label_faces(mesh, truth, tol);
  std::vector<std::set<int>> sets(truth.primitives.size());
  for (auto f : mesh.faces()) {
    const int l = labels[f.idx()];
    if (l < 0) continue;
    for (auto v : mesh.fv_range(f))
      if (bench::shape_distance(truth.primitives[l].shape, to_eigen(mesh.point(v))) <= pick_mm) sets[l].insert(v.idx());
  }
  std::vector<std::vector<int>> out;
  for (const auto& s : sets) out.emplace_back(s.begin(), s.end());
  return out;
}

features::Fit refit(const Mesh& mesh, const std::vector<int>& vs, ShapeType type) {
  features::Samples s;
  for (int v : vs) s.points.push_back(to_eigen(mesh.point(OpenMesh::VertexHandle(v))));
  switch (type) {
    case ShapeType::plane: return features::fit_plane(s);
    case ShapeType::cylinder: return features::fit_cylinder(s);
    case ShapeType::sphere: return features::fit_sphere(s);
    case ShapeType::cone: return features::fit_cone(s);
    default: return {};
  }
}

json shape_json(const features::Fit& f, std::size_t n) {
  json j = {{"type", features::shape_name(f.shape.type)}, {"ok", f.ok}, {"rms", f.rms}, {"vertices", n},
            {"point", {f.shape.point.x(), f.shape.point.y(), f.shape.point.z()}},
            {"dir", {f.shape.dir.x(), f.shape.dir.y(), f.shape.dir.z()}}};
  if (f.shape.type == ShapeType::cylinder || f.shape.type == ShapeType::sphere) j["radius"] = f.shape.radius;
  if (f.shape.type == ShapeType::cone) j["half_angle_deg"] = f.shape.half_angle_deg;
  return j;
}

int cmd_refit(const std::string& edited, const std::string& original, const std::string& truth_path, double pick,
              const std::string& out) {
  const Mesh a = read_mesh(original), b = read_mesh(edited);
  if (a.n_vertices() != b.n_vertices() || a.n_faces() != b.n_faces())
    throw InvalidInput(fmt::format("{} and {} do not have the same vertices and faces: the edit keeps the topology",
                                   edited, original));
  const bench::Truth truth = bench::read_truth(truth_path);
  const auto groups = primitive_vertices(a, truth, pick);
  json j = json::object();
  for (std::size_t i = 0; i < truth.primitives.size(); ++i) {
    const auto& t = truth.primitives[i];
    if (groups[i].size() < 10) continue;
    j[t.id] = shape_json(refit(b, groups[i], t.shape.type), groups[i].size());
    j[t.id]["before"] = shape_json(refit(a, groups[i], t.shape.type), groups[i].size());
  }
  const std::string text = j.dump(1);
  if (out.empty()) std::printf("%s\n", text.c_str());
  else write_file_atomic(out, text + "\n");
  return 0;
}

// ---- speed ------------------------------------------------------------------------------------

Mesh refined_part(const Mesh& part, int vertices) {
  double area = 0.0;
  for (auto f : part.faces()) area += part.calc_face_area(f);
  double h = std::sqrt(area / (0.866 * vertices)) * 1.3;
  Mesh m;
  for (int attempt = 0; attempt < 4; ++attempt) {
    m = bench::refine_mesh(part, h);
    const double ratio = static_cast<double>(m.n_vertices()) / vertices;
    if (std::abs(ratio - 1.0) < 0.15) break;
    h *= std::sqrt(ratio);
  }
  m.update_normals();
  return m;
}

double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[std::min(v.size() - 1, static_cast<std::size_t>(std::ceil(q * v.size())) - (q > 0 ? 1 : 0))];
}

struct Run {
  double first_s = 0.0;               // full propagation, fresh factorisation
  std::vector<double> steps_s;        // interactive steps
  edit::EditReport first, last;
  std::vector<double> displacement;   // per vertex, after the last step
  std::set<int> region_vertices;      // vertices of modified and free patches (any step)
};

template <class Edit>
Run run_edits(const Mesh& mesh, const features::FeatureSet& fs, const edit::EditOptions& o, int steps, Edit&& edit) {
  Run r;
  edit::Editor ed(mesh, fs, o);
  auto note_region = [&](const edit::EditReport& rep) {
    for (const auto* list : {&rep.edited, &rep.propagated, &rep.free})
      for (auto f : *list)
        for (int v : ed.vertices(f)) r.region_vertices.insert(v);
  };
  auto t0 = std::chrono::steady_clock::now();
  r.first = edit(ed, 0);
  r.first_s = seconds_since(t0);
  note_region(r.first);
  for (int k = 1; k <= steps; ++k) {
    t0 = std::chrono::steady_clock::now();
    r.last = edit(ed, k);
    r.steps_s.push_back(seconds_since(t0));
    note_region(r.last);
  }
  r.displacement = ed.displacement();
  return r;
}

json times_json(const edit::EditReport& r) {
  const auto& t = r.time;
  return {{"propagation_ms", t.propagation * 1e3}, {"region_ms", t.region * 1e3},
          {"factorization_ms", t.factorization * 1e3}, {"solve_ms", t.solve * 1e3}, {"snap_ms", t.snap * 1e3},
          {"check_ms", t.check * 1e3}, {"commit_ms", t.commit * 1e3}};
}

json run_json(const Run& r) {
  return {{"first_ms", r.first_s * 1e3},
          {"first_breakdown", times_json(r.first)},
          {"last_breakdown", times_json(r.last)},
          {"step_p50_ms", percentile(r.steps_s, 0.5) * 1e3},
          {"step_p95_ms", percentile(r.steps_s, 0.95) * 1e3},
          {"steps", r.steps_s.size()},
          {"free_vertices", r.first.free_vertices},
          {"free_patches", r.first.free.size()},
          {"handle_vertices", r.first.handle_vertices},
          {"propagated", r.first.propagated.size()},
          {"arap_iterations_first", r.first.arap_iterations},
          {"arap_iterations_last", r.last.arap_iterations},
          {"factorization_reused_last", r.last.factorization_reused}};
}

int cmd_speed(const std::string& part, const std::vector<int>& sizes, int steps, const std::string& out, bool peer,
              double influence) {
  const auto parts = std::filesystem::path(S2C_SOURCE_DIR) / "fixtures/parts";
  const bench::Truth truth = bench::read_truth(parts / (part + ".truth.json"));
  if (part != "plate") throw InvalidInput("speed: the scenario is written for the plate (its corner holes)");
  const Mesh base = read_mesh(parts / (part + ".stl"));
  json results = json::array();
  std::printf("| vertices | edit | restricted: first (full propagation) | step p50 | step p95 | free vertices | whole-mesh ARAP: first | step p95 | free vertices | ratio first | ratio p95 | radius error | equal_radius residual | moved outside region |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
  for (int n : sizes) {
    const auto t0 = std::chrono::steady_clock::now();
    const Mesh mesh = refined_part(base, n);
    const double refine_s = seconds_since(t0);
    const auto t1 = std::chrono::steady_clock::now();
    features::FeatureSet fs = features::analyze(mesh, {}).features;
    const double analyse_s = seconds_since(t1);
    // The corner hole at (22, 12): widen it in small steps (equal_radius takes the other three).
    std::string hole_id;
    {
      const edit::Editor probe(mesh, fs);
      const auto found = probe.select([&](edit::FeatureRef f) {
        const auto& s = probe.shape(f);
        return s.type == ShapeType::cylinder && std::abs(s.radius - 3.0) < 0.3 &&
               (probe.centroid(f) - Vector3d(22, 12, 4)).norm() < 1.0;
      });
      if (found.size() != 1) throw ProcessingError("speed: the features do not hold the corner hole at (22, 12)");
      hole_id = probe.id(found[0]);
    }
    auto hole = [&](const edit::Editor& ed) { return std::vector<edit::FeatureRef>{*ed.find(hole_id)}; };
    auto widen = [&](edit::Editor& ed, int k) { return ed.set_radius(hole(ed), 3.2 + 0.01 * k); };
    const double final_radius = 3.2 + 0.01 * steps;
    edit::EditOptions local, whole;
    local.influence = influence;
    whole.whole_mesh = true;
    const Run a = run_edits(mesh, fs, local, steps, widen);
    Run b;
    std::string whole_error;
    try {
      if (peer) b = run_edits(mesh, fs, whole, steps, widen);
    } catch (const ProcessingError& e) {
      whole_error = e.what();  // the peer failing is a result too
      std::fprintf(stderr, "whole-mesh ARAP failed on %zu vertices: %s\n", mesh.n_vertices(), e.what());
    }

    // Accuracy of the restricted edit, measured by refitting the truth holes on the result.
    edit::Editor check(mesh, fs, local);
    for (int k = 0; k <= steps; ++k) widen(check, k);
    const auto groups = primitive_vertices(mesh, truth, 0.05);
    double radius_err = 0.0, r_min = 1e9, r_max = 0.0;
    for (std::size_t i = 0; i < truth.primitives.size(); ++i) {
      const auto& id = truth.primitives[i].id;
      if (id.rfind("hole_", 0) != 0 || id == "hole_center") continue;
      const auto f = refit(check.mesh(), groups[i], ShapeType::cylinder);
      radius_err = std::max(radius_err, std::abs(f.shape.radius - final_radius));
      r_min = std::min(r_min, f.shape.radius);
      r_max = std::max(r_max, f.shape.radius);
    }
    int outside = 0;
    for (int v = 0; v < static_cast<int>(a.displacement.size()); ++v)
      if (a.displacement[v] != 0.0 && !a.region_vertices.count(v)) ++outside;
    const double ratio_first = peer ? b.first_s / a.first_s : 0.0;
    const double ratio_p95 = peer ? percentile(b.steps_s, 0.95) / std::max(percentile(a.steps_s, 0.95), 1e-12) : 0.0;
    std::printf("| %zu | widen a corner hole r 3 → %.2f in %d steps | %.1f ms | %.1f ms | %.1f ms | %d | %.1f ms | %.1f ms | %d | %.1f× | %.1f× | %.2g mm | %.2g mm | %d |\n",
                mesh.n_vertices(), final_radius, steps, a.first_s * 1e3, percentile(a.steps_s, 0.5) * 1e3,
                percentile(a.steps_s, 0.95) * 1e3, a.first.free_vertices, b.first_s * 1e3,
                percentile(b.steps_s, 0.95) * 1e3, b.first.free_vertices, ratio_first, ratio_p95, radius_err,
                r_max - r_min, outside);
    std::fflush(stdout);
    results.push_back({{"vertices", mesh.n_vertices()},
                       {"faces", mesh.n_faces()},
                       {"refine_s", refine_s},
                       {"features_s", analyse_s},
                       {"restricted", run_json(a)},
                       {"whole_mesh", whole_error.empty() ? run_json(b) : json{{"error", whole_error}}},
                       {"ratio_first", ratio_first},
                       {"ratio_step_p95", ratio_p95},
                       {"radius_error_mm", radius_err},
                       {"equal_radius_residual_mm", r_max - r_min},
                       {"moved_outside_region", outside}});
  }
  if (!out.empty()) write_file_atomic(out, results.dump(1) + "\n");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Benchmark and verification of the edit stage (issue 6); see bench/README.md", "s2c-bench-edit"};
  app.require_subcommand(1);
  std::string edited, original, truth, out, part = "plate";
  double pick = 0.1;
  std::vector<int> sizes{50000};
  int steps = 20;
  auto* r = app.add_subcommand("refit", "Refit the truth primitives on an edited mesh (same topology as ORIGINAL)");
  r->add_option("EDITED", edited)->required();
  r->add_option("ORIGINAL", original)->required();
  r->add_option("TRUTH", truth, "NAME.truth.json")->required();
  r->add_option("--pick", pick, "Faces within this of a truth primitive are labelled with it, mm")->capture_default_str();
  r->add_option("--json", out, "Write the JSON here instead of stdout");
  auto* s = app.add_subcommand("speed", "Time a parametric edit on the refined part; compare with whole-mesh ARAP");
  s->add_option("--part", part)->capture_default_str();
  s->add_option("--vertices", sizes, "Vertex counts of the refined meshes")->delimiter(',');
  s->add_option("--steps", steps, "Interactive steps after the first edit")->capture_default_str();
  s->add_option("--json", out, "Also write the results as JSON");
  bool no_peer = false;
  double influence = edit::EditOptions{}.influence;
  s->add_flag("--no-whole-mesh", no_peer, "Skip the whole-mesh ARAP comparison");
  s->add_option("--influence", influence, "EditOptions::influence of the restricted edit")->capture_default_str();
  CLI11_PARSE(app, argc, argv);
  s2c::CommonOptions common;
  s2c::init_logging("s2c-bench-edit", common);
  int rc = 0;
  const int guarded = s2c::run_guarded([&] {
    rc = *r ? cmd_refit(edited, original, truth, pick, out) : cmd_speed(part, sizes, steps, out, !no_peer, influence);
  });
  return guarded != 0 ? guarded : rc;
}
