// scan2cad-reconstruct: a recorded scan or a point cloud → fused cloud and mesh.
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "s2c/core/cli.h"
#include "s2c/core/files.h"
#include "s2c/core/io.h"
#include "s2c/core/report.h"
#include "s2c/reconstruct/reconstruct.h"

int main(int argc, char** argv) {
  CLI::App app{
      "Fuse a recorded scan (stream directory) or a point cloud (.ply .pcd) into one cloud with\n"
      "normals oriented towards the sensor, and mesh it. Every length defaults from the measured\n"
      "point spacing. Surface the scanner never saw is trimmed away and stays open for repair.\n"
      "Example: scan2cad reconstruct fixtures/scans/plate -o mesh.ply --cloud-out cloud.ply",
      "scan2cad-reconstruct"};
  s2c::CommonOptions common;
  s2c::ReconstructOptions o;
  std::string input, output, cloud_out, method = "poisson";
  app.add_option("INPUT", input, "Stream directory or point cloud (.ply .pcd)")->required();
  app.add_option("-o,--output", output, "Mesh to write (.ply .stl .obj .off)")->required();
  app.add_option("--cloud-out", cloud_out, "Also write the fused cloud with normals (.ply)");
  app.add_option("--method", method, "poisson (watertight where seen) or gp3 (greedy projection)")
      ->check(CLI::IsMember({"poisson", "gp3"}))->capture_default_str();
  app.add_option("--voxel", o.voxel_mm, "Fusion voxel size, mm (default: measured point spacing)");
  app.add_option("--depth", o.poisson_depth, "Poisson octree depth (default: from spacing and size)");
  app.add_option("--trim", o.trim_mm, "Drop surface farther than this from the data, mm (default: 3 × spacing)");
  s2c::add_common_options(app, common);
  if (int rc = s2c::parse_command_line(app, argc, argv); rc >= 0) return rc;
  s2c::init_logging("scan2cad-reconstruct", common);

  return s2c::run_guarded([&] {
    s2c::mesh_format(output);  // reject a bad extension before any work
    if (!cloud_out.empty()) s2c::refuse_same_file(input, cloud_out);
    s2c::refuse_same_file(input, output);
    o.method = method == "gp3" ? s2c::MeshMethod::gp3 : s2c::MeshMethod::poisson;
    s2c::Report report("scan2cad-reconstruct");
    s2c::ReconstructReport r;
    s2c::OrientedCloud cloud;
    {
      s2c::Report::Step t(report, "fuse");
      cloud = s2c::fuse_input(input, o, r);
    }
    s2c::Mesh mesh;
    {
      s2c::Report::Step t(report, "mesh");
      mesh = s2c::mesh_cloud(cloud, o, r);
    }
    {
      s2c::Report::Step t(report, "write");
      if (!cloud_out.empty()) s2c::write_cloud(cloud, cloud_out);
      s2c::write_mesh(mesh, output);
    }
    report.parameters() = {{"input", input}, {"output", output}, {"method", method}, {"voxel_mm", r.voxel_mm},
                           {"poisson_depth", r.poisson_depth}, {"trim_mm", r.trim_mm},
                           {"normal_neighbours", o.normal_neighbours}};
    report.counts() = {{"frames", r.frames}, {"points_in", r.points_in}, {"points_fused", r.points_fused},
                       {"outliers_removed", r.outliers_removed}, {"spacing_mm", r.spacing_mm},
                       {"faces_before_trim", r.faces_before_trim}, {"faces", r.faces}, {"vertices", r.vertices}};
    report.write(common.report);
    spdlog::info("{} points ({} fused, spacing {:.3f} mm) → {} faces → {}", r.points_in, r.points_fused, r.spacing_mm,
                 r.faces, output);
  });
}
