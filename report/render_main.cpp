// scan2cad-render: one shaded picture of a mesh or a cloud (Embree on the CPU), as a PNG.
#include <cctype>
#include <cstdio>
#include <tuple>

#include <nlohmann/json.hpp>

#include "s2c/core/cli.h"
#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "s2c/core/io.h"
#include "s2c/core/report.h"
#include "s2c/features/feature_set.h"
#include "s2c/report/layers.h"

namespace {

/// "800x600" → (800, 600). \throw InvalidInput
std::pair<int, int> parse_size(const std::string& text) {
  int w = 0, h = 0;
  char tail;
  if (std::sscanf(text.c_str(), "%dx%d%c", &w, &h, &tail) != 2 || w < 8 || h < 8 || w > 8192 || h > 8192)
    throw s2c::InvalidInput("--size " + text + ": expected WIDTHxHEIGHT, each 8..8192 pixels (e.g. 1280x960)");
  return {w, h};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Render a mesh or a point cloud to a PNG: ray traced on the CPU with Embree, shaded, with dark\n"
      "outlines; the inside of an open surface (seen through a hole) is tinted dark red.\n"
      "With --features, patches are coloured by type and feature lines drawn; with --reference, the\n"
      "mesh is coloured by its signed deviation from the true part (blue inside → green → red outside).\n"
      "Examples: scan2cad render repaired.ply -o repaired.png\n"
      "          scan2cad render cloud.ply -o cloud.png --view top --size 1280x960\n"
      "          scan2cad render repaired.ply --features features.json -o features.png\n"
      "          scan2cad render repaired.ply --reference part.stl --range 0.1 -o deviation.png",
      "scan2cad-render"};
  s2c::CommonOptions common;
  std::string input, output, view = "iso", size = "1024x768", features_path, reference;
  double range = 0, point_radius = 0;
  bool no_outlines = false;
  app.add_option("INPUT", input, "Mesh (.ply .stl .obj .off .vtk) or point cloud (.ply without faces)")->required();
  app.add_option("-o,--output", output, "PNG to write")->required();
  app.add_option("--view", view, "Viewpoint: " + s2c::report::view_names())->capture_default_str();
  app.add_option("--size", size, "Image size WIDTHxHEIGHT, pixels")->capture_default_str();
  app.add_option("--features", features_path, "features.json of this mesh: colour patches by type, draw feature lines");
  app.add_option("--reference", reference, "True part (same coordinates): colour by signed deviation");
  app.add_option("--range", range, "Deviation colour range ±mm (default: from the data)")->check(CLI::PositiveNumber);
  app.add_option("--point-radius", point_radius, "Point radius, mm (default: 0.9 × the point spacing)")
      ->check(CLI::PositiveNumber);
  app.add_flag("--no-outlines", no_outlines, "No dark silhouettes and depth steps");
  s2c::add_common_options(app, common);
  if (int rc = s2c::parse_command_line(app, argc, argv); rc >= 0) return rc;
  s2c::init_logging("scan2cad-render", common);

  return s2c::run_guarded([&] {
    namespace r = s2c::report;
    {
      std::string ext = std::filesystem::path(output).extension().string();
      for (auto& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
      if (ext != ".png") throw s2c::InvalidInput(output + ": the picture is written as PNG: use a .png name");
    }
    s2c::refuse_same_file(input, output);
    if (!features_path.empty() && !reference.empty())
      throw s2c::InvalidInput("--features and --reference colour the mesh differently: give one of them");
    r::RenderOptions o;
    std::tie(o.width, o.height) = parse_size(size);
    o.outlines = !no_outlines;
    const r::View v = r::view_named(view);

    s2c::Report report("scan2cad-render");
    report.parameters() = {{"input", input}, {"output", output}, {"view", view}, {"size", size},
                           {"features", features_path}, {"reference", reference}};
    s2c::TriangleSoup soup;
    {
      s2c::Report::Step t(report, "read");
      soup = s2c::read_soup(input, true);
      if (soup.vertices.empty()) throw s2c::InvalidInput(input + ": no vertices to render");
    }
    r::Scene scene;
    {
      s2c::Report::Step t(report, "prepare");
      if (soup.faces.empty()) {
        if (!features_path.empty() || !reference.empty() || range > 0)
          throw s2c::InvalidInput(input + ": a point cloud (no faces): --features, --reference and --range colour meshes");
        r::PointLayer points = r::cloud_layer(soup);
        points.radius = point_radius;
        scene.add(std::move(points));
      } else if (point_radius > 0) {
        throw s2c::InvalidInput(input + ": a mesh: --point-radius is for point clouds");
      } else if (!features_path.empty()) {
        r::add_features(scene, soup, s2c::features::read_features(features_path));
      } else if (!reference.empty()) {
        const r::Deviation d = r::signed_deviation(soup, s2c::read_soup(reference));
        const double shown = range > 0 ? range : r::default_range(d.stats);
        report.counts()["deviation"] = {{"rms_mm", d.stats.rms}, {"mean_mm", d.stats.mean}, {"max_abs_mm", d.stats.max_abs},
                                        {"range_mm", shown}};
        scene.add(r::deviation_layer(soup, d, shown));
      } else {
        scene.add(r::MeshLayer{soup, {}, {}, r::kMeshGrey});
      }
    }
    {
      s2c::Report::Step t(report, "render");
      r::write_png(scene.render(v, o), output);
    }
    report.counts()["vertices"] = soup.vertices.size();
    report.counts()["faces"] = soup.faces.size();
    report.write(common.report);
  });
}
