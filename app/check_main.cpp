// scan2cad-check: is a mesh CAD-ready? Prints one JSON object on stdout.
#include <cstdio>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "s2c/core/check.h"
#include "s2c/core/cli.h"
#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "s2c/core/io.h"
#include "s2c/core/memory.h"
#include "s2c/core/report.h"

int main(int argc, char** argv) {
  s2c::reuse_freed_memory();
  CLI::App app{
      "Check whether a mesh is CAD-ready: closed, 2-manifold, consistently outward-oriented, free of\n"
      "self-intersections, degenerate and duplicate faces. Prints one JSON object on stdout with\n"
      "closed, boundary_loops, nonmanifold_edges, nonmanifold_vertices, components, self_intersections,\n"
      "degenerate_faces, oriented, cad_ready and more; 'problems' lists what to fix (scan2cad repair).\n"
      "The mesh is checked exactly as stored (STL vertices welded by position).",
      "scan2cad-check"};
  s2c::CommonOptions common;
  std::string mesh, output;
  bool fast = false, strict = false;
  app.add_option("MESH", mesh, "Mesh to check (.ply .stl .obj .off .vtk)")->required();
  app.add_option("-o,--output", output, "Also write the JSON to FILE (atomically)");
  app.add_flag("--no-self-intersections", fast, "Skip the self-intersection test (faster)");
  app.add_flag("--strict", strict, "Exit 3 when the mesh is not CAD-ready");
  s2c::add_common_options(app, common);
  if (int rc = s2c::parse_command_line(app, argc, argv); rc >= 0) return rc;
  s2c::init_logging("scan2cad-check", common);

  bool ready = true;
  const int rc = s2c::run_guarded([&] {
    s2c::Report report("scan2cad-check");
    report.parameters() = {{"mesh", mesh}, {"self_intersections", !fast}};
    s2c::TriangleSoup soup;
    {
      s2c::Report::Step t(report, "read");
      soup = s2c::read_soup(mesh);
    }
    s2c::CheckOptions opt;
    opt.self_intersections = !fast;
    s2c::CheckResult r;
    {
      s2c::Report::Step t(report, "check");
      r = s2c::check_mesh(soup, opt);
    }
    const std::string json = s2c::to_json(r);
    if (!output.empty()) s2c::write_file_atomic(output, json + "\n");
    std::printf("%s\n", json.c_str());
    report.counts() = nlohmann::json::parse(json);
    report.write(common.report);
    ready = r.cad_ready;
  });
  if (rc == 0 && strict && !ready) return s2c::kExitFailed;
  return rc;
}
