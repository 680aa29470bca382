// scan2cad-reconstruct: a recorded scan or a point cloud → fused cloud and mesh.
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "s2c/core/cli.h"
#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "s2c/core/io.h"
#include "s2c/core/report.h"
#include "s2c/reconstruct/reconstruct.h"

int main(int argc, char** argv) {
  CLI::App app{
      "Fuse a recorded scan into one cloud with normals oriented towards the sensor, and mesh it.\n"
      "INPUT is a stream directory (docs/formats.md), a TUM RGB-D folder or a folder of depth images\n"
      "(with --intrinsics), or one or more point clouds (.ply .pcd), each taken as one view.\n"
      "Views are registered: recorded poses are refined (generalized ICP against the neighbouring\n"
      "views), views without poses are aligned globally (FPFH + RANSAC) first.\n"
      "Every length defaults from the measured point spacing. Surface the scanner never saw is\n"
      "trimmed away and stays open for repair.\n"
      "Meshers: poisson (default, PCL) or imls (2-4x faster, features find more on its meshes; for scans\n"
      "whose noise is small against the point spacing, not noisy RGB-D frames).\n"
      "Examples: scan2cad reconstruct fixtures/scans/plate -o mesh.ply --cloud-out cloud.ply\n"
      "          scan2cad reconstruct fixtures/scans/plate -o mesh.ply --method imls\n"
      "          scan2cad reconstruct bun000.ply bun045.ply bun090.ply --input-unit-mm 1000 -o bunny.ply\n"
      "          scan2cad reconstruct tum_folder --intrinsics 517.3,516.5,318.6,255.3 -o room.ply",
      "scan2cad-reconstruct"};
  s2c::CommonOptions common;
  s2c::ReconstructOptions o;
  std::vector<std::string> inputs;
  std::string output, cloud_out, method = "poisson", registration = "auto", intrinsics;
  app.add_option("INPUT", inputs, "Stream directory, TUM/depth-image folder, or point clouds (.ply .pcd)")->required();
  app.add_option("-o,--output", output, "Mesh to write (.ply .stl .obj .off)")->required();
  app.add_option("--cloud-out", cloud_out, "Also write the fused cloud with normals (.ply)");
  app.add_option("--method", method,
                 "poisson (one surface, trimmed to the data), gp3 (greedy projection of the fused cloud), "
                 "organized (each frame on its pixel grid, concatenated), imls (implicit moving least squares of the "
                 "fused cloud on a sparse grid, Marching Cubes: the fastest)")
      ->check(CLI::IsMember({"poisson", "gp3", "organized", "imls"}))->capture_default_str();
  double mls = -1;
  app.add_option("--mls", mls, "Smooth the fused cloud by moving least squares with this radius, mm "
                 "(0 = 3 × spacing; default off)")->type_name("MM");
  app.add_option("--voxel", o.voxel_mm, "Fusion voxel size, mm (default: measured point spacing; imls: 1.5 × spacing, also its grid)");
  app.add_option("--depth", o.poisson_depth, "Poisson octree depth (default: from spacing and size)");
  app.add_option("--trim", o.trim_mm, "Drop surface farther than this from the data, mm (default: 3 × spacing)");
  app.add_option("--support", o.imls_support_mm, "imls: support radius of a point, mm (default: 2.5 × voxel; 10 × the measured noise when that "
                 "exceeds 0.45 voxel, as on RGB-D frames)");
  app.add_option("--simplify", o.simplify_mm,
                 "poisson, imls: decimate the mesh, moving the surface by at most this, mm (default: voxel / 10; "
                 "0 = off: the fastest, 2.2-2.5x the faces)")->type_name("MM");
  app.add_option("--outliers", o.outlier_sigma,
                 "Statistical outlier removal threshold in standard deviations (0 = off)")->capture_default_str();
  app.add_option("--register", registration,
                 "auto (refine recorded poses, else global), refine, global (ignore poses), off")
      ->check(CLI::IsMember({"auto", "refine", "global", "off"}))->capture_default_str();
  app.add_option("--intrinsics", intrinsics, "fx,fy,cx,cy in pixels, for folders without stream.yaml");
  app.add_option("--depth-unit-mm", o.input.depth_unit_mm, "mm per depth count for such folders (default 0.2, TUM)");
  app.add_option("--input-unit-mm", o.input.input_unit_mm, "Scale of cloud coordinates: 1000 for metres")
      ->capture_default_str();
  s2c::add_common_options(app, common);
  if (int rc = s2c::parse_command_line(app, argc, argv); rc >= 0) return rc;
  s2c::init_logging("scan2cad-reconstruct", common);

  return s2c::run_guarded([&] {
    s2c::mesh_format(output);  // reject a bad extension before any work
    std::vector<std::filesystem::path> in(inputs.begin(), inputs.end());
    for (const auto& p : in) {
      if (!cloud_out.empty()) s2c::refuse_same_file(p, cloud_out);
      s2c::refuse_same_file(p, output);
    }
    if (!intrinsics.empty()) o.input.intrinsics = s2c::parse_intrinsics(intrinsics);
    if (!(o.input.input_unit_mm > 0)) throw s2c::InvalidInput("--input-unit-mm must be positive");
    o.registration.mode = registration == "refine" ? s2c::RegistrationMode::refine
                          : registration == "global" ? s2c::RegistrationMode::global
                          : registration == "off"    ? s2c::RegistrationMode::off
                                                     : s2c::RegistrationMode::automatic;
    o.method = method == "gp3" ? s2c::MeshMethod::gp3
               : method == "organized" ? s2c::MeshMethod::organized
               : method == "imls"      ? s2c::MeshMethod::imls
                                       : s2c::MeshMethod::poisson;
    s2c::Report report("scan2cad-reconstruct");
    s2c::ReconstructReport r;
    if (app.count("--mls")) o.mls_radius_mm = mls > 0 ? mls : -1;  // -1: from the spacing
    s2c::Reconstruction result = s2c::reconstruct(in, o, r);
    report.add_time("load", r.load_s);
    report.add_time("register", r.register_s);
    report.add_time("fuse", r.fuse_s);
    report.add_time("mesh", r.mesh_s);
    {
      s2c::Report::Step t(report, "write");
      if (!cloud_out.empty()) s2c::write_cloud(result.cloud, cloud_out);
      s2c::write_mesh(std::move(result.mesh), output);
    }
    nlohmann::json views = nlohmann::json::array();
    for (const auto& v : r.views)
      views.push_back({{"name", v.name}, {"rms_mm", v.rms_mm}, {"overlap", v.overlap},
                       {"corrected_mm", v.corrected_mm}, {"corrected_deg", v.corrected_deg},
                       {"rejected", v.rejected}, {"note", v.reason}});
    report.json()["views"] = views;
    report.parameters() = {{"input", inputs}, {"output", output}, {"method", method}, {"register", registration},
                           {"voxel_mm", r.voxel_mm},
                           {"poisson_depth", r.poisson_depth}, {"poisson_block_depth", r.poisson_block_depth}, {"trim_mm", r.trim_mm},
                           {"normal_neighbours", o.normal_neighbours}, {"outlier_sigma", o.outlier_sigma}, {"mls_radius_mm", r.mls_radius_mm},
                           {"imls_support_mm", r.imls_support_mm}, {"simplify_mm", r.simplify_mm}};
    report.counts() = {{"frames", r.frames}, {"points_in", r.points_in}, {"points_fused", r.points_fused},
                       {"outliers_removed", r.outliers_removed}, {"spacing_mm", r.spacing_mm}, {"imls_noise_mm", r.imls_noise_mm},
                       {"faces_before_trim", r.faces_before_trim}, {"faces", r.faces}, {"vertices", r.vertices}};
    report.write(common.report);
    spdlog::info("{} points ({} fused, spacing {:.3f} mm) → {} faces → {}", r.points_in, r.points_fused, r.spacing_mm,
                 r.faces, output);
  });
}
