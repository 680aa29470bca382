// s2c-bench-alpha-wrap: CGAL 5.5's 3D alpha wrapping (CGAL::alpha_wrap_3) of a triangle soup, the
// anchor of issue 4's volumetric repair: any soup in, a closed 2-manifold wrap out, offset outward.
//
//   s2c-bench-alpha-wrap IN OUT [--alpha-div 200] [--offset-div 2000]
//
// alpha = bbox diagonal / alpha-div, offset = bbox diagonal / offset-div (the anchor values).
// The input is given to CGAL as the soup read from the file (no welding or cleaning: the wrap needs
// none). Prints one JSON object: the parameters, the wrap's size and `seconds` (alpha_wrap_3 alone:
// not the read, the conversion into CGAL types or the write). OUT: .ply .off .stl .obj (CGAL writes it).
#include <array>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>
#include <CGAL/Polygon_mesh_processing/IO/polygon_mesh_io.h>

#include "s2c/core/clock.h"
#include "s2c/core/errors.h"
#include "s2c/core/io.h"

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Wrap = CGAL::Surface_mesh<Point>;

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> args(argv + 1, argv + argc);
  std::vector<std::string> files;
  double alpha_div = 200, offset_div = 2000;
  for (std::size_t i = 0; i < args.size(); ++i) {
    if (args[i] == "--alpha-div" && i + 1 < args.size()) alpha_div = std::stod(args[++i]);
    else if (args[i] == "--offset-div" && i + 1 < args.size()) offset_div = std::stod(args[++i]);
    else if (args[i] == "--help") {
      std::printf("usage: s2c-bench-alpha-wrap IN OUT [--alpha-div 200] [--offset-div 2000]\n");
      return 0;
    } else files.push_back(args[i]);
  }
  if (files.size() != 2 || alpha_div <= 0 || offset_div <= 0) {
    std::fprintf(stderr, "usage: s2c-bench-alpha-wrap IN OUT [--alpha-div 200] [--offset-div 2000]\n");
    return 2;
  }
  try {
    const s2c::TriangleSoup in = s2c::read_soup(files[0]);
    const s2c::Bounds b = s2c::bounds(in);
    const double diag = (b.max - b.min).norm();
    const double alpha = diag / alpha_div, offset = diag / offset_div;

    std::vector<Point> points;
    points.reserve(in.vertices.size());
    for (const auto& v : in.vertices) points.emplace_back(v.x(), v.y(), v.z());
    std::vector<std::array<std::size_t, 3>> faces;
    faces.reserve(in.faces.size());
    for (const auto& f : in.faces)
      faces.push_back({static_cast<std::size_t>(f[0]), static_cast<std::size_t>(f[1]), static_cast<std::size_t>(f[2])});

    Wrap wrap;
    const auto t0 = std::chrono::steady_clock::now();
    CGAL::alpha_wrap_3(points, faces, alpha, offset, wrap);
    const double seconds = s2c::seconds_since(t0);

    if (wrap.number_of_faces() == 0) throw s2c::ProcessingError("alpha_wrap_3 returned an empty wrap");
    // CGAL's writer (by extension; binary PLY/STL): the wrap is already a clean Surface_mesh.
    if (!CGAL::IO::write_polygon_mesh(files[1], wrap, CGAL::parameters::stream_precision(17).use_binary_mode(true)))
      throw s2c::IoError(files[1] + ": cannot write the wrap");
    std::printf("{\"input\": \"%s\", \"output\": \"%s\", \"diag_mm\": %.6f, \"alpha_mm\": %.6f, \"offset_mm\": %.6f, "
                "\"input_faces\": %zu, \"faces\": %zu, \"seconds\": %.4f}\n",
                files[0].c_str(), files[1].c_str(), diag, alpha, offset, in.faces.size(), static_cast<std::size_t>(wrap.number_of_faces()), seconds);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "s2c-bench-alpha-wrap: %s\n", e.what());
    return 3;
  }
  return 0;
}
