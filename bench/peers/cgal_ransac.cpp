// s2c-bench-cgal-ransac: CGAL 5.5 Efficient RANSAC (Shape_detection::Efficient_RANSAC with Plane,
// Cylinder, Sphere and Cone; default-constructed Parameters) against s2c::features::analyze on the
// same meshes in the same run, both judged by bench/features_eval (issue 5's type-accuracy target).
//
//   s2c-bench-cgal-ransac sweep [--parts DIR] [--names plate,shaft,bracket,pocket] [--sigma 0,0.1,0.2,0.3]
//                               [--div 100] [--seed 1] [--samples 100000] [--runs 3] [--verbose]
//   s2c-bench-cgal-ransac mesh MESH TRUTH [--features F.json | --skip-ours] [--noise MM] [--samples 100000] [--runs 3]
//                              [--verbose]
//
// sweep: the inputs of `s2c-bench-features sweep` (bench::sweep_inputs, same parts, σ, div, seed).
// CGAL gets `--samples` points sampled area-uniformly from the mesh, each with the normal of its
// face (seed 1). mesh --features evaluates a given features.json as ours instead of running analyze;
// --skip-ours runs CGAL only. CGAL's defaults: probability 0.01, min_points 1 % of the points, epsilon and
// cluster_epsilon 1 % of the bbox diagonal, normal_threshold 0.9.
// RANSAC's shapes become detected surfaces over the mesh's faces: a face takes the shape nearest
// to its centroid among the shapes that own a sample within cluster_epsilon of it (RANSAC's own
// connectivity bound; the shapes are infinite), if that distance is ≤ max(3σ, epsilon) (σ: the
// input's noise); otherwise the face has no shape and counts as wrong. Primitive recall and type
// accuracy then use exactly the evaluation of our patches. CGAL's RANSAC is randomised: it runs
// --runs times with CGAL's default random generator seeded 1, 2, …; the table shows the mean
// (min–max), the Δ uses the mean. "found" is the looser measure of the issue's anchor: a truth
// primitive of which one detected shape of the right type covers at least half (no parameter
// tolerances). Prints a Markdown table.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Shape_detection/Efficient_RANSAC.h>
#include <CGAL/property_map.h>

#include "features_eval.h"
#include "s2c/core/clock.h"
#include "s2c/core/errors.h"
#include "s2c/core/io.h"
#include "s2c/features/analyze.h"

using namespace s2c;
using Clock = std::chrono::steady_clock;

namespace {

using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using Vector = Kernel::Vector_3;
using PointWithNormal = std::pair<Point, Vector>;
using PwnVector = std::vector<PointWithNormal>;
using PointMap = CGAL::First_of_pair_property_map<PointWithNormal>;
using NormalMap = CGAL::Second_of_pair_property_map<PointWithNormal>;
using Traits = CGAL::Shape_detection::Efficient_RANSAC_traits<Kernel, PwnVector, PointMap, NormalMap>;
using Ransac = CGAL::Shape_detection::Efficient_RANSAC<Traits>;
using RPlane = CGAL::Shape_detection::Plane<Traits>;
using RCylinder = CGAL::Shape_detection::Cylinder<Traits>;
using RSphere = CGAL::Shape_detection::Sphere<Traits>;
using RCone = CGAL::Shape_detection::Cone<Traits>;

Eigen::Vector3d eig(const Point& p) { return {p.x(), p.y(), p.z()}; }
Eigen::Vector3d eig(const Vector& v) { return {v.x(), v.y(), v.z()}; }

struct RansacResult {
  std::vector<bench::DetectedSurface> surfaces;
  double seconds = 0, epsilon = 0, cluster_epsilon = 0;
  std::size_t unassigned_points = 0;
};

RansacResult run_ransac(const Mesh& mesh, std::size_t n_samples, double sigma_mm, unsigned seed) {
  const bench::OrientedSamples s = bench::sample_oriented(mesh, n_samples, 1);
  PwnVector points;
  points.reserve(s.points.size());
  for (std::size_t i = 0; i < s.points.size(); ++i)
    points.emplace_back(Point(s.points[i].x(), s.points[i].y(), s.points[i].z()),
                        Vector(s.normals[i].x(), s.normals[i].y(), s.normals[i].z()));
  Ransac ransac;
  ransac.set_input(points);
  ransac.add_shape_factory<RPlane>();
  ransac.add_shape_factory<RCylinder>();
  ransac.add_shape_factory<RSphere>();
  ransac.add_shape_factory<RCone>();
  const Ransac::Parameters defaults;  // CGAL's defaults; epsilons become 1 % of the bbox diagonal
  CGAL::get_default_random() = CGAL::Random(seed);  // CGAL seeds it from the clock otherwise
  const auto t0 = Clock::now();
  ransac.detect(defaults);
  RansacResult r;
  r.seconds = seconds_since(t0);
  // The epsilons detect() derived (same formula, from the samples' bbox).
  Eigen::Vector3d lo = s.points[0], hi = s.points[0];
  for (const auto& p : s.points) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  r.epsilon = r.cluster_epsilon = 0.01 * (hi - lo).norm();
  r.unassigned_points = ransac.number_of_unassigned_points();

  std::vector<int> owner(points.size(), -1);
  for (const auto& shape : ransac.shapes()) {
    bench::DetectedSurface d;
    d.id = "R" + std::to_string(r.surfaces.size());
    if (const auto* p = dynamic_cast<const RPlane*>(shape.get())) {
      const Eigen::Vector3d n = eig(p->plane_normal());
      d.shape.type = features::ShapeType::plane;
      d.shape.dir = n.normalized();
      d.shape.point = -p->d() * n / n.squaredNorm();
    } else if (const auto* c = dynamic_cast<const RCylinder*>(shape.get())) {
      d.shape.type = features::ShapeType::cylinder;
      d.shape.point = eig(c->axis().point());
      d.shape.dir = eig(c->axis().to_vector()).normalized();
      d.shape.radius = c->radius();
    } else if (const auto* sp = dynamic_cast<const RSphere*>(shape.get())) {
      d.shape.type = features::ShapeType::sphere;
      d.shape.point = eig(sp->center());
      d.shape.radius = sp->radius();
    } else if (const auto* co = dynamic_cast<const RCone*>(shape.get())) {
      d.shape.type = features::ShapeType::cone;
      d.shape.point = eig(co->apex());
      d.shape.dir = eig(co->axis()).normalized();
      d.shape.half_angle_deg = co->angle() * 180.0 / M_PI;
    } else {
      continue;
    }
    for (std::size_t i : shape->indices_of_assigned_points()) owner[i] = int(r.surfaces.size());
    r.surfaces.push_back(d);
  }

  // Faces → shapes (see the file comment).
  std::vector<Eigen::Vector3d> owned;
  std::vector<int> owned_shape;
  for (std::size_t i = 0; i < owner.size(); ++i)
    if (owner[i] >= 0) owned.push_back(s.points[i]), owned_shape.push_back(owner[i]);
  if (owned.empty()) return r;
  const bench::PointGrid grid(owned, r.cluster_epsilon);
  const double accept = std::max(3 * sigma_mm, r.epsilon);
  for (auto f : mesh.faces()) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (auto v : mesh.fv_range(f)) c += to_eigen(mesh.point(v)) / 3.0;
    std::set<int> near;
    for (int i : grid.within(c, r.cluster_epsilon)) near.insert(owned_shape[i]);
    int best = -1;
    double best_d = accept;
    for (int k : near) {
      const double dist = bench::shape_distance(r.surfaces[k].shape, c);
      if (dist <= best_d) best_d = dist, best = k;
    }
    if (best >= 0) r.surfaces[best].faces.push_back(f.idx());
  }
  return r;
}

struct Row {
  std::string part, input, sigma;
  std::size_t faces = 0;
  bench::PrimitiveMetrics ours, cgal;  // cgal: the first RANSAC run
  double ours_s = 0;
  // Over the RANSAC runs (seeds 1..runs): mean, min, max.
  struct Stat {
    double mean = 0, min = 1e30, max = -1e30;
    void add(double x, int n) {
      mean += x / n;
      min = std::min(min, x);
      max = std::max(max, x);
    }
  };
  Stat recall, found, type_accuracy, shapes, seconds, unassigned;
  int runs = 0;
  std::vector<bench::DetectedSurface> cgal_surfaces;  // of the first run
  bool ours_skipped = false;
};

std::string stat(const Row::Stat& s, const char* fmt, int runs) {
  char a[64], b[64], c[64];
  std::snprintf(a, sizeof a, fmt, s.mean);
  if (runs == 1) return a;
  std::snprintf(b, sizeof b, fmt, s.min);
  std::snprintf(c, sizeof c, fmt, s.max);
  return std::string(a) + " (" + b + "–" + c + ")";
}

void print_header(int runs) {
  std::printf(
      "| part | input | σ/h | faces | primitive recall ours | CGAL%s | found ours | CGAL | type accuracy ours | CGAL | "
      "Δ type accuracy (points) | CGAL shapes | CGAL unassigned samples | ours (s) | CGAL detect (s) |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
      runs > 1 ? (" (mean of " + std::to_string(runs) + " seeds, min–max)").c_str() : "");
}

void print_row(const Row& r) {
  const int n = r.runs;
  auto ours = [&](const char* fmt, double x) {
    char b[32];
    std::snprintf(b, sizeof b, fmt, x);
    return r.ours_skipped || std::isnan(x) ? std::string("—") : std::string(b);
  };
  std::printf("| %s | %s | %s | %zu | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |\n", r.part.c_str(),
              r.input.c_str(), r.sigma.c_str(), r.faces, ours("%.3f", r.ours.recall).c_str(),
              stat(r.recall, "%.3f", n).c_str(),
              ours("%.3f", r.ours.truth ? double(r.ours.found) / r.ours.truth : 0.0).c_str(),
              stat(r.found, "%.3f", n).c_str(), ours("%.3f", r.ours.type_accuracy).c_str(),
              stat(r.type_accuracy, "%.3f", n).c_str(),
              ours("%+.1f", 100 * (r.ours.type_accuracy - r.type_accuracy.mean)).c_str(),
              stat(r.shapes, "%.1f", n).c_str(), stat(r.unassigned, "%.1f %%", n).c_str(), ours("%.2f", r.ours_s).c_str(),
              stat(r.seconds, "%.2f", n).c_str());
  std::fflush(stdout);
}

void details(const Row& r, bool verbose) {
  if (!verbose) return;
  std::fprintf(stderr, "## %s %s σ/h %s (CGAL: first run)\n", r.part.c_str(), r.input.c_str(), r.sigma.c_str());
  for (const auto& x : r.ours.missed) std::fprintf(stderr, "  ours missed %s\n", x.c_str());
  for (const auto& x : r.cgal.missed) std::fprintf(stderr, "  CGAL missed %s\n", x.c_str());
  for (const auto& [t, d] : r.cgal.matches) std::fprintf(stderr, "  CGAL %s = %s\n", t.c_str(), d.c_str());
  for (const auto& d : r.cgal_surfaces) {
    const auto& s = d.shape;
    std::fprintf(stderr, "  %s %s point (%.3f %.3f %.3f) dir (%.4f %.4f %.4f) r %.4f half angle %.3f: %zu faces\n",
                 d.id.c_str(), s.type == features::ShapeType::plane      ? "plane"
                               : s.type == features::ShapeType::cylinder ? "cylinder"
                               : s.type == features::ShapeType::sphere   ? "sphere"
                                                                         : "cone",
                 s.point.x(), s.point.y(), s.point.z(), s.dir.x(), s.dir.y(), s.dir.z(), s.radius, s.half_angle_deg,
                 d.faces.size());
  }
}

Row compare(const Mesh& mesh, const bench::Truth& truth, const features::FeatureSet* given, double sigma_mm,
            std::size_t samples, double line_tol, int runs, bool skip_ours = false) {
  Row row;
  row.faces = mesh.n_faces();
  row.runs = runs;
  bench::Tolerances tol;
  tol.line_tol_mm = line_tol;
  features::FeatureSet fs;
  if (given) {
    fs = *given;
    row.ours_s = std::nan("");
  } else if (skip_ours) {
    row.ours_s = std::nan("");
    row.ours_skipped = true;
  } else {
    const auto t0 = Clock::now();
    fs = features::analyze(mesh, features::FeatureOptions{}).features;
    row.ours_s = seconds_since(t0);
  }
  if (!skip_ours) row.ours = bench::evaluate(mesh, fs, truth, tol).primitives;
  const std::vector<int> labels = bench::label_faces(mesh, truth, tol);
  for (int k = 0; k < runs; ++k) {
    const RansacResult rr = run_ransac(mesh, samples, sigma_mm, unsigned(k + 1));
    const bench::PrimitiveMetrics m = bench::evaluate_surfaces(mesh, rr.surfaces, truth, labels, tol);
    if (k == 0) row.cgal = m, row.cgal_surfaces = rr.surfaces;
    row.recall.add(m.recall, runs);
    row.found.add(double(m.found) / m.truth, runs);
    row.type_accuracy.add(m.type_accuracy, runs);
    row.shapes.add(double(rr.surfaces.size()), runs);
    row.seconds.add(rr.seconds, runs);
    row.unassigned.add(100.0 * double(rr.unassigned_points) / double(samples), runs);
  }
  return row;
}

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string x;
  while (std::getline(ss, x, ','))
    if (!x.empty()) out.push_back(x);
  return out;
}

const char* kUsage =
    "usage: s2c-bench-cgal-ransac sweep [--parts DIR] [--names plate,shaft,bracket,pocket] [--sigma 0,0.1,0.2,0.3]\n"
    "                                   [--div 100] [--seed 1] [--samples 100000] [--runs 3] [--verbose]\n"
    "       s2c-bench-cgal-ransac mesh MESH TRUTH [--features F.json] [--noise MM] [--samples 100000] [--runs 3]\n"
    "                                  [--skip-ours] [--verbose]\n";

}  // namespace

int main(int argc, char** argv) {
  std::vector<std::string> pos;
  std::map<std::string, std::string> opt;
  bool verbose = false, skip = false;
  for (int i = 1; i < argc; ++i) {
    const std::string s = argv[i];
    if (s == "--help") {
      std::printf("%s", kUsage);
      return 0;
    }
    if (s == "--verbose")
      verbose = true;
    else if (s == "--skip-ours")
      skip = true;
    else if (s.rfind("--", 0) == 0 && i + 1 < argc)
      opt[s] = argv[++i];
    else
      pos.push_back(s);
  }
  auto get = [&](const std::string& k, const std::string& def) { return opt.count(k) ? opt[k] : def; };
  if (pos.empty()) {
    std::fprintf(stderr, "%s", kUsage);
    return 2;
  }
  try {
    const std::size_t samples = std::stoull(get("--samples", "100000"));
    const int runs = std::stoi(get("--runs", "3"));
    if (pos[0] == "sweep" && pos.size() == 1) {
      const std::string dir = get("--parts", std::string(S2C_SOURCE_DIR) + "/fixtures/parts");
      std::vector<double> sigmas;
      for (const auto& x : split(get("--sigma", "0,0.1,0.2,0.3"))) sigmas.push_back(std::stod(x));
      const double div = std::stod(get("--div", "100"));
      const auto seed = std::stoull(get("--seed", "1"));
      print_header(runs);
      for (const auto& name : split(get("--names", "plate,shaft,bracket,pocket"))) {
        const bench::Truth truth = bench::read_truth(dir + "/" + name + ".truth.json");
        for (const auto& in : bench::sweep_inputs(dir + "/" + name + ".stl", sigmas, div, seed)) {
          Row row = compare(in.mesh, truth, nullptr, in.sigma_mm, samples, in.line_tol_mm, runs);
          row.part = name;
          row.input = bench::input_label(in);
          char buf[32];
          std::snprintf(buf, sizeof buf, "%.1f", in.sigma_rel);
          row.sigma = buf;
          print_row(row);
          details(row, verbose);
        }
      }
      return 0;
    }
    if (pos[0] == "mesh" && pos.size() == 3) {
      Mesh mesh = read_mesh(pos[1]);
      mesh.update_normals();
      const bench::Truth truth = bench::read_truth(pos[2]);
      features::FeatureSet given;
      if (opt.count("--features")) {
        given = features::read_features(opt["--features"]);
        if (given.mesh_faces != int(mesh.n_faces()) || given.mesh_vertices != int(mesh.n_vertices()))
          throw InvalidInput(opt["--features"] + ": computed on another mesh than " + pos[1] + " (vertex/face counts differ)");
      }
      Row row = compare(mesh, truth, opt.count("--features") ? &given : nullptr, std::stod(get("--noise", "0")), samples,
                        0.5, runs, skip);
      row.part = truth.part;
      row.input = pos[1];
      row.sigma = "—";
      print_header(runs);
      print_row(row);
      details(row, verbose);
      return 0;
    }
    std::fprintf(stderr, "%s", kUsage);
    return 2;
  } catch (const InvalidInput& e) {
    std::fprintf(stderr, "s2c-bench-cgal-ransac: %s\n", e.what());
    return 2;
  } catch (const IoError& e) {
    std::fprintf(stderr, "s2c-bench-cgal-ransac: %s\n", e.what());
    return 4;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "s2c-bench-cgal-ransac: %s\n", e.what());
    return 3;
  }
}
