// scan2cad-edit: run an edit script (.s2e) on a mesh and its features.json.
#include <cstdio>
#include <map>
#include <memory>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "s2c/core/check.h"
#include "s2c/core/cli.h"
#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "s2c/core/io.h"
#include "s2c/core/memory.h"
#include "s2c/core/report.h"
#include "s2c/edit/editor.h"
#include "s2c/edit/interpreter.h"
#include "s2c/features/feature_set.h"

namespace {

// Every output is first written beside its target and renamed only when all are ready, so a
// failing script (or a failing write) leaves nothing behind.
struct Outputs {
  std::vector<std::unique_ptr<s2c::AtomicFile>> files;
  s2c::AtomicFile& add(const std::filesystem::path& p) {
    files.push_back(std::make_unique<s2c::AtomicFile>(p));
    return *files.back();
  }
  void commit() {
    for (auto& f : files) f->commit();
  }
};

}  // namespace

int main(int argc, char** argv) {
  s2c::reuse_freed_memory();
  CLI::App app{
      "Edit a mesh through its features with a script (.s2e): select features by type and parameters,\n"
      "set radii, move, rotate or scale features, add or remove constraints, lock features, assert\n"
      "results and export. Each edit places the edited feature exactly on its new shape; features\n"
      "constrained to it follow (greedy propagation); neighbouring patches deform as rigidly as\n"
      "possible (ARAP), and everything further away stays exactly where it was. The language is in\n"
      "docs/edit.md. A script runs completely or writes nothing.\n"
      "Exit codes: 0 ok, 2 bad usage/input or a script error (file:line:column), 3 a failed assert\n"
      "or an edit that cannot be satisfied (a conflict between constraints, a folded triangle), 4 I/O.\n"
      "Examples: scan2cad edit repaired.ply --features features.json --script widen.s2e -o edited.ply\n"
      "          scan2cad edit part.ply --features f.json --script s.s2e --dry-run --set hole_r=4",
      "scan2cad-edit"};
  s2c::CommonOptions common;
  std::string input, features_path, script_path, output, features_out;
  std::vector<std::string> sets;
  bool dry_run = false, no_propagate = false, allow_unready = false;
  s2c::edit::EditOptions eo;
  app.add_option("MESH", input, "The mesh the features were computed on (.ply .stl .obj .off)")->required();
  app.add_option("--features", features_path, "features.json of MESH (scan2cad features); its sha256 must match MESH")
      ->required();
  app.add_option("--script", script_path, "Edit script (.s2e), see docs/edit.md")->required();
  app.add_option("-o,--output", output, "Edited mesh to write (format by extension)");
  app.add_option("--features-out", features_out, "Also write the features of the edited mesh (updated shapes and constraints)");
  app.add_option("--set", sets, "Override a script parameter: --set NAME=VALUE (repeatable; VALUE is an expression)");
  app.add_flag("--dry-run", dry_run, "Print what each statement selects and changes; write nothing");
  app.add_flag("--no-propagate", no_propagate, "Do not propagate edits through constraints (constraints that break are reported)");
  app.add_option("--angle-tolerance", eo.angle_tolerance_deg, "A constraint holds within this angle, degrees")
      ->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--length-tolerance", eo.length_tolerance, "A constraint holds within this distance, mm")
      ->check(CLI::PositiveNumber)->capture_default_str();
  app.add_option("--arap-iterations", eo.arap_iterations, "ARAP local/global iterations at most")
      ->check(CLI::Range(1, 1000))->capture_default_str();
  app.add_flag("--allow-not-cad-ready", allow_unready,
               "Write the result even when the edit makes a CAD-ready mesh self-intersect");
  s2c::add_common_options(app, common);
  if (int rc = s2c::parse_command_line(app, argc, argv); rc >= 0) return rc;
  s2c::init_logging("scan2cad-edit", common);

  return s2c::run_guarded([&] {
    if (output.empty() && !dry_run) throw s2c::InvalidInput("-o/--output is required (or use --dry-run)");
    for (const auto& p : {output, features_out})
      if (!p.empty()) {
        s2c::refuse_same_file(input, p);
        s2c::refuse_same_file(features_path, p);
        s2c::refuse_same_file(script_path, p);
      }
    s2c::edit::ScriptOptions so;
    for (const auto& s : sets) {
      const auto eq = s.find('=');
      if (eq == std::string::npos || eq == 0)
        throw s2c::InvalidInput(fmt::format("--set {}: expected NAME=VALUE, e.g. --set hole_r=4", s));
      so.overrides[s.substr(0, eq)] = s.substr(eq + 1);
    }
    eo.propagate = !no_propagate;
    s2c::Report report("scan2cad-edit");
    report.parameters() = {{"input", input},   {"features", features_path}, {"script", script_path},
                           {"output", output}, {"dry_run", dry_run},        {"propagate", eo.propagate},
                           {"set", sets},      {"angle_tolerance_deg", eo.angle_tolerance_deg},
                           {"length_tolerance_mm", eo.length_tolerance}};

    s2c::edit::Script script;
    s2c::Mesh mesh;
    s2c::features::FeatureSet fs;
    {
      s2c::Report::Step t(report, "read");
      script = s2c::edit::parse_script(s2c::read_file(script_path), script_path);
      s2c::read_mesh(input, mesh);
      fs = s2c::features::read_features(features_path);
      const std::string hash = s2c::sha256_file(input);
      if (fs.mesh_sha256 != hash)
        throw s2c::InvalidInput(fmt::format(
            "{}: computed for a different mesh (its sha256 '{}', {} has {}…): run scan2cad features {} -o {} first",
            features_path, fs.mesh_sha256.substr(0, 12), input, hash.substr(0, 12), input, features_path));
    }
    const s2c::CheckResult before = s2c::check_mesh(s2c::mesh_to_soup(mesh));

    s2c::edit::Editor editor(std::move(mesh), std::move(fs), eo);
    so.say = [&](const std::string& line) {
      if (dry_run) std::printf("%s\n", line.c_str());
      else spdlog::debug("{}", line);
    };
    s2c::edit::ScriptResult result;
    {
      s2c::Report::Step t(report, "edit");
      result = s2c::edit::run_script(script, editor, so);
    }

    s2c::CheckResult after;
    {
      s2c::Report::Step t(report, "check");
      after = s2c::check_mesh(s2c::mesh_to_soup(editor.mesh()));
    }
    if (after.self_intersections > before.self_intersections || after.degenerate_faces > before.degenerate_faces) {
      const std::string what = fmt::format(
          "{}: the edited mesh has {} self-intersecting face pairs and {} degenerate faces (before: {} and {}); "
          "the edits are too large for the mesh around them",
          script_path, after.self_intersections, after.degenerate_faces, before.self_intersections, before.degenerate_faces);
      if (!allow_unready) throw s2c::ProcessingError(what + " (--allow-not-cad-ready writes it anyway)");
      spdlog::warn("{}", what);
    }

    auto& c = report.counts();
    c["statements"] = script.statements.size();
    c["asserts_passed"] = result.asserts;
    c["cad_ready"] = after.cad_ready;
    c["self_intersections"] = after.self_intersections;
    nlohmann::json steps = nlohmann::json::array();
    int broken = 0;
    for (const auto& s : result.statements) {
      nlohmann::json j = {{"line", s.line}, {"text", s.text}, {"selected", s.selected}};
      if (!s.edit.edited.empty() || !s.edit.propagated.empty()) {
        j["propagation"] = s.edit.propagation;
        j["handle_vertices"] = s.edit.handle_vertices;
        j["free_vertices"] = s.edit.free_vertices;
        j["free_patches"] = s.edit.free.size();
        j["extra_rings"] = s.edit.extra_rings;
        j["carried_patches"] = s.edit.carried.size();
        j["arap_iterations"] = s.edit.arap_iterations;
        j["factorization_reused"] = s.edit.factorization_reused;
        j["max_displacement_mm"] = s.edit.max_displacement;
        j["seconds"] = s.edit.seconds;
      }
      j["broken_constraints"] = s.edit.broken;
      broken += static_cast<int>(s.edit.broken.size());
      for (const auto& b : s.edit.broken) spdlog::warn("line {}: {}", s.line, b);
      steps.push_back(std::move(j));
    }
    report.json()["statements"] = std::move(steps);
    c["broken_constraints"] = broken;

    if (dry_run) {
      std::printf("dry run: %zu statements, %d asserts passed, result %s; nothing written\n", script.statements.size(),
                  result.asserts, after.cad_ready ? "CAD-ready" : "NOT CAD-ready");
      report.write(common.report);
      return;
    }
    Outputs out;
    {
      s2c::Report::Step t(report, "write");
      if (!output.empty()) {
        auto& f = out.add(output);
        s2c::write_mesh(editor.mesh(), f.temp_path());
        if (!features_out.empty()) {
          s2c::features::FeatureSet fo = editor.features();
          fo.mesh_sha256 = s2c::sha256_file(f.temp_path());
          auto& ff = out.add(features_out);
          s2c::features::write_features(fo, ff.temp_path());
        }
      }
      std::vector<std::filesystem::path> written;
      for (const auto& o : {output, features_out})
        if (!o.empty()) written.emplace_back(o);
      for (const auto& [path, m] : result.exports) {
        // Inputs are never overwritten, and no two outputs share a file.
        for (const auto& in : {input, features_path, script_path}) s2c::refuse_same_file(in, path);
        for (const auto& w : written)
          if (std::filesystem::absolute(w).lexically_normal() == std::filesystem::absolute(path).lexically_normal())
            throw s2c::InvalidInput(fmt::format("{}: export \"{}\" is also another output of this run", script_path, path.string()));
        written.push_back(path);
        if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
        auto& f = out.add(path);
        s2c::write_mesh(m, f.temp_path());
      }
      out.commit();
    }
    spdlog::info("{} statements, {} asserts passed, {} constraint(s) broken; {} is {}CAD-ready", script.statements.size(),
                 result.asserts, broken, output, after.cad_ready ? "" : "NOT ");
    report.write(common.report);
  });
}
