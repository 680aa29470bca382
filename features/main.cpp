// scan2cad-features: a mesh → features.json (patches, lines, groups, constraints: the hyper-mesh).
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>
#include <tbb/task_group.h>

#include "s2c/core/cli.h"
#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "s2c/core/io.h"
#include "s2c/core/memory.h"
#include "s2c/core/report.h"
#include "s2c/features/analyze.h"

namespace {

constexpr std::size_t kHeapPerFace = 150;

}  // namespace

int main(int argc, char** argv) {
  s2c::reuse_freed_memory();
  CLI::App app{
      "Find the features of a mesh and write them as features.json (format scan2cad.features/1):\n"
      "patches (planes, cylinders, spheres, cones, freeform) with fitted parameters, feature lines\n"
      "(straight lines, circles, arcs, polylines) where patches meet at a crease, their adjacency,\n"
      "one group per connected component, and the constraints between features (parallel,\n"
      "perpendicular, coaxial, concentric, equal radius/length, fixed and equal angles, ...).\n"
      "Tensor voting classifies every vertex as face, crease or corner. Thresholds default from the\n"
      "mesh: the noise is measured, the voting radius and fit tolerance follow from it and from the\n"
      "edge length; --report lists the values used and the counts.\n"
      "Examples: scan2cad features repaired.ply -o features.json --segments-out segments.ply\n"
      "          scan2cad features part.stl -o f.json --min-angle 30 --report features-report.json",
      "scan2cad-features"};
  s2c::CommonOptions common;
  s2c::features::FeatureOptions o;
  std::string input, output, segments;
  bool no_constraints = false;
  app.add_option("MESH", input, "Mesh to analyse (.ply .stl .obj .off .vtk), ideally CAD-ready (scan2cad repair)")
      ->required();
  app.add_option("-o,--output", output, "features.json to write")->required();
  app.add_option("--segments-out", segments, "Also write the mesh with a colour and a segment id per face (.ply)");
  app.add_option("--min-angle", o.min_crease_deg,
                 "Smallest crease angle to detect, degrees (angle between the face normals across the edge); on "
                 "noisy meshes also the smallest angle stated as a fixed_angle constraint")
      ->check(CLI::Range(1.0, 120.0))->capture_default_str();
  app.add_option("--radius", o.radius, "Tensor voting radius, mm (default: 1 median edge length; on noisy meshes 2, or 3 when the noise is at "
                 "least 4% of the edge)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--noise", o.noise, "Noise sigma of the surface, mm (default: measured from the mesh)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--fit-tolerance", o.fit_tolerance,
                 "Accept a plane/cylinder/sphere/cone when the RMS distance is at most this, mm "
                 "(default: max(3 noise, 2e-4 diagonal), on noisy meshes at least 0.1 median edge and "
                 "3 x the waviness, the surface's bumps a few edges wide; --report lists both)")
      ->check(CLI::NonNegativeNumber);
  app.add_option("--working-vertices", o.working_vertices,
                 "A noisy mesh (not a clean CAD tessellation) with more than three times this many vertices is "
                 "analysed on a coarser copy, and the patches are mapped back onto it: of about this many vertices "
                 "when the noise is 4% of the edge or more (a dense scan), of a seventh of its vertices when smoother (an "
                 "undecimated Poisson surface); a million vertices in 1.2-2.6 s instead of 8-19; features narrower "
                 "than two of the copy's cells are lost (0: always the whole mesh; --report lists the copy under "
                 "working_mesh)")
      ->check(CLI::NonNegativeNumber)->capture_default_str();
  app.add_option("--angle-tolerance", o.constraint.angle_tol_deg, "Constraint angle tolerance, degrees")
      ->check(CLI::Range(0.0, 10.0))->capture_default_str();
  app.add_flag("--no-constraints", no_constraints, "Skip the constraint analysis");
  s2c::add_common_options(app, common);
  if (int rc = s2c::parse_command_line(app, argc, argv); rc >= 0) return rc;
  s2c::init_logging("scan2cad-features", common);

  return s2c::run_guarded([&] {
    s2c::refuse_same_file(input, output);
    if (!segments.empty()) {
      if (s2c::mesh_format(segments) != s2c::MeshFormat::ply)
        throw s2c::InvalidInput(segments + ": --segments-out writes PLY (per-face colours): use a .ply name");
      s2c::refuse_same_file(input, segments);
    }
    o.constraints = !no_constraints;
    s2c::Report report("scan2cad-features");
    report.parameters() = {{"input", input},          {"output", output},
                           {"min_angle_deg", o.min_crease_deg}, {"radius_mm", o.radius},
                           {"noise_mm", o.noise},     {"fit_tolerance_mm", o.fit_tolerance},
                           {"working_vertices", o.working_vertices},
                           {"angle_tolerance_deg", o.constraint.angle_tol_deg}, {"constraints", o.constraints}};
    // The analysis takes over the indexed faces as they are read; a half-edge mesh is only built
    // for the segments PLY (read_mesh's, so its vertices are those the analysis numbered).
    s2c::TriangleSoup soup;
    std::string hash;
    {
      s2c::Report::Step t(report, "read");
      // The analysis takes about 150 bytes of heap per face (a million vertices: 300 MB) that it
      // would fault in page by page; the idle core does it while this one parses the file.
      s2c::HeapWarmer warm(kHeapPerFace * s2c::estimated_faces(input));
      soup = s2c::read_soup(input);
    }
    // The file's hash (0.04 s for a million-vertex PLY) as a task beside the analysis rather
    // than on the way to it. (A thread of its own during the read waited for the memory map
    // lock behind the heap warmer: bench/README, "2 MB pages and 100 MB less".)
    tbb::task_group hashing;
    hashing.run([&] { hash = s2c::sha256_file(input); });
    s2c::Mesh mesh;
    if (!segments.empty()) s2c::soup_to_mesh(soup, mesh);
    s2c::features::Analysis analysis;
    {
      s2c::Report::Step t(report, "analyse");
      analysis = s2c::features::analyze(std::move(soup), o, &report.counts());
      hashing.wait();
    }
    analysis.features.mesh_sha256 = hash;
    {
      s2c::Report::Step t(report, "write");
      s2c::features::write_features(analysis.features, output);
      if (!segments.empty()) s2c::features::write_segments_ply(mesh, analysis, segments);
    }
    report.write(common.report);
  });
}
