// s2c-make-defects: writes deterministic defective variants of a clean closed mesh (a corpus for
// the tests and benchmarks of the repair stage) and DIR/defects.json describing them.
#include <cstdio>
#include <filesystem>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "defect_corpus.h"
#include "s2c/core/check.h"
#include "s2c/core/cli.h"
#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "s2c/core/io.h"
#include "s2c/core/report.h"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  CLI::App app{
      "Write defective variants of a clean closed mesh into DIR: holes.ply (two face discs removed),\n"
      "nested.ply (two holes touching at a vertex; a hole with an island touching its rim),\n"
      "flipped.ply (a patch with reversed faces), duplicates.ply (5 faces twice), gap.ply (cut along\n"
      "a plane section, one side moved off by --gap, not welded), self_intersections.ply (a patch\n"
      "pushed through the opposite wall), loose.ply (3 tiny isolated triangles), everything.ply (all\n"
      "of them), clean.ply (the refined input they start from) and defects.json (what each holds,\n"
      "with check counts). The same input and seed give the same files.",
      "s2c-make-defects"};
  s2c::CommonOptions common;
  std::string input, out_dir;
  s2c::bench::DefectOptions options;
  app.add_option("CLEAN", input, "Clean closed mesh (.stl .ply .off .obj)")->required();
  app.add_option("--out", out_dir, "Output folder (created if missing)")->required();
  app.add_option("--seed", options.seed, "Seed of every random choice")->capture_default_str();
  app.add_option("--edge", options.edge_length, "Refine to this longest edge first, mm (0 = bbox diagonal / 40)")
      ->capture_default_str();
  app.add_option("--gap", options.gap, "Width of the gap, mm")->capture_default_str()->check(CLI::PositiveNumber);
  s2c::add_common_options(app, common);
  if (int rc = s2c::parse_command_line(app, argc, argv); rc >= 0) return rc;
  s2c::init_logging("s2c-make-defects", common);

  return s2c::run_guarded([&] {
    s2c::Report report("s2c-make-defects");
    report.parameters() = {{"input", input}, {"out", out_dir}, {"seed", options.seed},
                           {"edge_mm", options.edge_length}, {"gap_mm", options.gap}};
    s2c::TriangleSoup clean;
    {
      s2c::Report::Step t(report, "read");
      clean = s2c::read_soup(input);
    }
    s2c::bench::DefectCorpus corpus;
    {
      s2c::Report::Step t(report, "make");
      try {
        corpus = s2c::bench::make_defect_corpus(clean, options);
      } catch (const s2c::InvalidInput& e) {
        throw s2c::InvalidInput(input + ": " + e.what());
      }
    }
    s2c::Report::Step t(report, "write");
    std::error_code ec;
    fs::create_directories(out_dir, ec);
    if (ec) throw s2c::IoError(out_dir + ": cannot create folder (" + ec.message() + ")");
    nlohmann::json doc = {{"format", "scan2cad.defects/1"},
                          {"input", fs::path(input).filename().string()},
                          {"input_sha256", s2c::sha256_file(input)},
                          {"seed", options.seed},
                          {"edge_mm", corpus.edge_length},
                          {"gap_mm", options.gap},
                          {"clean", {{"file", "clean.ply"},
                                     {"vertices", corpus.clean.vertices.size()},
                                     {"faces", corpus.clean.faces.size()}}},
                          {"variants", nlohmann::json::array()}};
    s2c::bench::write_soup_ply(corpus.clean, fs::path(out_dir) / "clean.ply");
    for (const auto& v : corpus.variants) {
      const std::string file = v.name + ".ply";
      s2c::bench::write_soup_ply(v.soup, fs::path(out_dir) / file);
      const auto& c = v.check;
      doc["variants"].push_back(
          {{"name", v.name},
           {"file", file},
           {"defects", v.defects},
           {"check", {{"vertices", c.vertices},
                      {"faces", c.faces},
                      {"boundary_edges", c.boundary_edges},
                      {"boundary_loops", c.boundary_loops},
                      {"nonmanifold_edges", c.nonmanifold_edges},
                      {"nonmanifold_vertices", c.nonmanifold_vertices},
                      {"orientation_conflicts", c.orientation_conflicts},
                      {"components", c.components},
                      {"self_intersections", c.self_intersections},
                      {"degenerate_faces", c.degenerate_faces},
                      {"duplicate_faces", c.duplicate_faces}}}});
      spdlog::info("{}: {} faces, {} boundary loops, {} non-manifold vertices, {} self-intersections", file,
                   c.faces, c.boundary_loops, c.nonmanifold_vertices, c.self_intersections);
    }
    s2c::write_file_atomic(fs::path(out_dir) / "defects.json", doc.dump(2) + "\n");
    report.counts() = {{"variants", corpus.variants.size()}, {"clean_faces", corpus.clean.faces.size()}};
    report.write(common.report);
  });
}
