// Features stage benchmark (issue 5; bench/README.md "Features"): ground-truth evaluation of
// s2c::features::analyze on the fixture parts, clean and with noise, on single meshes (e.g. the
// pipeline's repaired.ply from a fixture scan), its speed on a 1M-vertex mesh, and a self-check
// of the evaluation itself.
//
//   s2c-bench-features sweep [--parts DIR] [--names plate,shaft,bracket,pocket] [--sigma 0,0.1,0.2,0.3]
//                            [--div 100] [--seed 1] [--verbose]
//   s2c-bench-features mesh MESH TRUTH [--features F.json | --features-out F.json] [--line-tol MM] [--verbose]
//   s2c-bench-features speed [--mesh MESH] [--vertices 1000000] [--repeat 3] [--write SUBDIVIDED.ply]
//   s2c-bench-features selfcheck [--parts DIR]
//   s2c-bench-features fits [--repeat 100]
//   s2c-bench-features voting [--mesh MESH] [--vertices 1000000] [--repeat 10]
//   s2c-bench-features inputs [--parts DIR] [--names …] [--sigma …] [--div 100] [--seed 1] [--out DIR]
//   s2c-bench-features read MESH [--repeat 5]
//
// sweep: per part, the OpenSCAD mesh as exported ("clean CAD", σ = 0), then the mesh refined by
// longest-edge bisection to max edge = bbox diagonal / div, with isotropic Gaussian noise of σ·h
// per coordinate (h = mean edge length of the refined mesh; seed + sigma index). Metrics and
// tolerances: bench/features_eval.h. Prints a Markdown table on stdout; --verbose lists the
// missed primitives, wrong constraints and missed constraint pairs on stderr.
// speed: 1→4 midpoint subdivision of MESH (default the CGAL fandisk) until ≥ --vertices, then
// analyze() of the indexed faces (as `scan2cad features` runs it) timed, best of --repeat, with
// TBB's default thread count.
// fits: the surface fits alone (fit_cone + fit_cylinder + fit_sphere) on samples of a torus band,
// which none of them fits exactly (as on a fillet, where the solvers work longest), at 60, 250,
// 1000 and 4000 samples: ms per three fits, best of --repeat, and a checksum of the results that
// must not move when a change is meant to leave them bit for bit. Run it under `taskset -c 0`:
// on one core it varies by a few per cent where the whole analysis varies by tens.
// inputs: the sweep's inputs (sizes, edge length, 1st percentile of the smallest angle), written as
// PLY into --out when given (for peers and for looking at them).
// read: the file read `scan2cad features` starts with (read_soup: binary PLY by our reader, the
// other formats by OpenMesh's) against OpenMesh's own reading of the file into its mesh
// (IO::read_mesh with vertex normals), the peer, alternated, best and median of --repeat each.
// selfcheck: the truth of every part converted to a FeatureSet on the part's mesh must evaluate
// to 1 everywhere; copies with one plane rotated and one radius scaled must lose exactly those
// features (5°, +5 %) or nothing (1.5°, +1.5 %). Exit 1 on any failure (CTest bench_features_selfcheck).
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <map>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <Eigen/Geometry>
#include <fstream>
#include <OpenMesh/Core/IO/MeshIO.hh>
#include <nlohmann/json.hpp>
#include <tbb/task_arena.h>

#include "features_eval.h"
#include "s2c/core/clock.h"
#include "s2c/core/errors.h"
#include "s2c/core/io.h"
#include "s2c/core/memory.h"
#include "s2c/features/analyze.h"
#include "s2c/features/shape.h"

using namespace s2c;
using bench::FeatureMetrics;
using Clock = std::chrono::steady_clock;

namespace {


std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out;
  std::stringstream ss(s);
  std::string x;
  while (std::getline(ss, x, sep))
    if (!x.empty()) out.push_back(x);
  return out;
}

struct Args {
  std::vector<std::string> positional;
  std::map<std::string, std::string> options;  // --key value
  std::set<std::string> flags;                 // --verbose
  std::string get(const std::string& k, const std::string& def) const {
    const auto it = options.find(k);
    return it == options.end() ? def : it->second;
  }
};

Args parse_args(int argc, char** argv, int first) {
  Args a;
  for (int i = first; i < argc; ++i) {
    const std::string s = argv[i];
    if (s == "--verbose" || s == "--help")
      a.flags.insert(s);
    else if (s.rfind("--", 0) == 0 && i + 1 < argc)
      a.options[s] = argv[++i];
    else if (s.rfind("--", 0) == 0)
      throw InvalidInput("option " + s + " needs a value");
    else
      a.positional.push_back(s);
  }
  return a;
}

const char* kUsage =
    "usage: s2c-bench-features sweep [--parts DIR] [--names plate,shaft,bracket,pocket] [--sigma 0,0.1,0.2,0.3]\n"
    "                                [--div 100] [--seed 1] [--verbose]\n"
    "       s2c-bench-features mesh MESH TRUTH [--features F.json | --features-out F.json] [--line-tol MM]\n"
    "                                [--json OUT.json] [--verbose]\n"
    "       s2c-bench-features speed [--mesh MESH] [--vertices 1000000] [--repeat 3] [--write SUBDIVIDED.ply]\n"
    "       s2c-bench-features selfcheck [--parts DIR]\n"
    "       s2c-bench-features fits [--repeat 100]\n"
    "       s2c-bench-features voting [--mesh MESH] [--vertices 1000000] [--repeat 10]\n"
    "       s2c-bench-features inputs [--parts DIR] [--names …] [--sigma …] [--div 100] [--seed 1] [--out DIR]\n"
    "       s2c-bench-features read MESH [--repeat 5]\n";

// ----------------------------------------------------------------------------- table
void print_header() {
  std::printf(
      "| part | input | σ/h | faces | primitive recall | type accuracy | line P | line R | line F1 | circle radius err "
      "mean / max (matched) | constraint P | constraint R | analyze (s) |\n"
      "|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
}

void print_row(const std::string& part, const std::string& input, const std::string& sigma, std::size_t faces,
               const FeatureMetrics& m, double seconds) {
  const auto& p = m.primitives;
  const auto& l = m.lines;
  const auto& c = m.constraints;
  char circle[96];
  if (l.truth_circles == 0)
    std::snprintf(circle, sizeof circle, "—");
  else if (l.matched_circles == 0)
    std::snprintf(circle, sizeof circle, "— (0/%d)", l.truth_circles);
  else
    std::snprintf(circle, sizeof circle, "%.2f %% / %.2f %% (%d/%d)", 100 * l.circle_err_mean, 100 * l.circle_err_max,
                  l.matched_circles, l.truth_circles);
  std::printf("| %s | %s | %s | %zu | %.3f (%d/%d) | %.3f | %.3f | %.3f | %.3f | %s | %.3f (%d/%d) | %.3f (%d/%d) | %.2f |\n",
              part.c_str(), input.c_str(), sigma.c_str(), faces, p.recall, p.matched, p.truth, p.type_accuracy,
              l.precision, l.recall, l.f1, circle, c.precision, c.correct, c.checked, c.recall, c.recalled_pairs,
              c.truth_pairs, seconds);
  std::fflush(stdout);
}

void print_details(const std::string& what, const FeatureMetrics& m) {
  std::fprintf(stderr, "## %s: %d patches, labelled share %.3f\n", what.c_str(), m.primitives.detected,
               m.primitives.labelled_share);
  for (const auto& x : m.primitives.missed) std::fprintf(stderr, "  missed primitive %s\n", x.c_str());
  auto list = [](const char* label, const std::vector<std::string>& v) {
    const std::size_t shown = std::min<std::size_t>(v.size(), 40);
    for (std::size_t i = 0; i < shown; ++i) std::fprintf(stderr, "  %s %s\n", label, v[i].c_str());
    if (shown < v.size()) std::fprintf(stderr, "  … and %zu more %s\n", v.size() - shown, label);
  };
  list("wrong", m.constraints.wrong);
  list("missed pair", m.constraints.missed);
  std::fprintf(stderr, "  lines: detected %.1f mm, truth %.1f mm\n", m.lines.detected_length, m.lines.truth_length);
}

struct Run {
  features::FeatureSet features;
  double seconds = 0;
};

Run run_analyze(const Mesh& mesh) {
  Run r;
  const auto t0 = Clock::now();
  features::Analysis a = features::analyze(mesh, features::FeatureOptions{});
  r.seconds = seconds_since(t0);
  r.features = std::move(a.features);
  return r;
}

std::string default_parts() { return std::string(S2C_SOURCE_DIR) + "/fixtures/parts"; }

std::vector<double> parse_list(const std::string& s) {
  std::vector<double> v;
  for (const auto& x : split(s, ',')) v.push_back(std::stod(x));
  return v;
}

// ----------------------------------------------------------------------------- sweep
/// The options sweep and inputs share: which parts, noise levels, refinement and seed.
struct SweepOptions {
  std::string dir;
  std::vector<std::string> names;
  std::vector<double> sigmas;
  double div;
  unsigned long long seed;

  explicit SweepOptions(const Args& a)
      : dir(a.get("--parts", default_parts())),
        names(split(a.get("--names", "plate,shaft,bracket,pocket"), ',')),
        sigmas(parse_list(a.get("--sigma", "0,0.1,0.2,0.3"))),
        div(std::stod(a.get("--div", "100"))),
        seed(std::stoull(a.get("--seed", "1"))) {}
  std::vector<bench::SweepInput> inputs(const std::string& name) const {
    return bench::sweep_inputs(dir + "/" + name + ".stl", sigmas, div, seed);
  }
};

int cmd_sweep(const Args& a) {
  const SweepOptions o(a);
  print_header();
  for (const auto& name : o.names) {
    const bench::Truth truth = bench::read_truth(o.dir + "/" + name + ".truth.json");
    for (auto& in : o.inputs(name)) {
      const Run r = run_analyze(in.mesh);
      bench::Tolerances tol;
      tol.line_tol_mm = in.line_tol_mm;
      const FeatureMetrics m = bench::evaluate(in.mesh, r.features, truth, tol);
      const std::string input = bench::input_label(in);
      char sigma[32];
      std::snprintf(sigma, sizeof sigma, "%.1f", in.sigma_rel);
      print_row(name, input, sigma, in.mesh.n_faces(), m, r.seconds);
      if (a.flags.count("--verbose")) print_details(name + " " + input + " σ/h " + sigma, m);
    }
  }
  return 0;
}

// ----------------------------------------------------------------------------- inputs
int cmd_inputs(const Args& a) {
  const SweepOptions o(a);
  const std::string out = a.get("--out", "");
  std::printf("| part | input | σ/h | h (mm) | σ (mm) | vertices | faces | min angle p1 (°) | file |\n|---|---|---|---|---|---|---|---|---|\n");
  for (const auto& name : o.names)
    for (auto& in : o.inputs(name)) {
      std::vector<double> angles;
      for (auto f : in.mesh.faces()) {
        std::vector<Eigen::Vector3d> p;
        for (auto v : in.mesh.fv_range(f)) p.push_back(to_eigen(in.mesh.point(v)));
        double mn = 180;
        for (int k = 0; k < 3; ++k) {
          const Eigen::Vector3d u = p[(k + 1) % 3] - p[k], w = p[(k + 2) % 3] - p[k];
          mn = std::min(mn, std::atan2(u.cross(w).norm(), u.dot(w)) * 180 / M_PI);
        }
        angles.push_back(mn);
      }
      std::sort(angles.begin(), angles.end());
      std::string file = "—";
      if (!out.empty()) {
        char buf[256];
        std::snprintf(buf, sizeof buf, "%s/%s_%s_s%.2f.ply", out.c_str(), name.c_str(),
                      in.input == "OpenSCAD" ? "cad" : "refined", in.sigma_rel);
        file = buf;
        write_mesh(in.mesh, file);
      }
      std::printf("| %s | %s | %.1f | %.4f | %.4f | %zu | %zu | %.2f | %s |\n", name.c_str(), in.input.c_str(),
                  in.sigma_rel, in.h, in.sigma_mm, in.mesh.n_vertices(), in.mesh.n_faces(),
                  angles.empty() ? 0.0 : angles[angles.size() / 100], file.c_str());
    }
  return 0;
}

// ----------------------------------------------------------------------------- mesh
int cmd_mesh(const Args& a) {
  if (a.positional.size() != 2) throw InvalidInput(std::string("mesh needs MESH and TRUTH\n") + kUsage);
  Mesh mesh = read_mesh(a.positional[0]);
  mesh.update_normals();
  const bench::Truth truth = bench::read_truth(a.positional[1]);
  Run r;
  if (a.options.count("--features")) {
    r.features = features::read_features(a.get("--features", ""));
    if (r.features.mesh_faces != int(mesh.n_faces()) || r.features.mesh_vertices != int(mesh.n_vertices()))
      throw InvalidInput(a.get("--features", "") + ": computed on a mesh of " + std::to_string(r.features.mesh_vertices) +
                         " vertices / " + std::to_string(r.features.mesh_faces) + " faces, " + a.positional[0] +
                         " has " + std::to_string(mesh.n_vertices()) + " / " + std::to_string(mesh.n_faces()));
    r.seconds = std::nan("");
  } else {
    r = run_analyze(mesh);
    if (a.options.count("--features-out")) {
      r.features.mesh_sha256.clear();  // not computed here; the file is for s2c-bench-cgal-ransac --features
      features::write_features(r.features, a.get("--features-out", ""));
    }
  }
  bench::Tolerances tol;
  tol.line_tol_mm = std::stod(a.get("--line-tol", "0.5"));
  const FeatureMetrics m = bench::evaluate(mesh, r.features, truth, tol);
  print_header();
  print_row(truth.part, a.positional[0], "—", mesh.n_faces(), m, r.seconds);
  if (a.flags.count("--verbose")) print_details(a.positional[0], m);
  if (a.options.count("--json")) {
    // For scripts (the e2e test): the headline numbers of the row above.
    const nlohmann::json j = {{"part", truth.part},
                              {"faces", mesh.n_faces()},
                              {"primitive_recall", m.primitives.recall},
                              {"type_accuracy", m.primitives.type_accuracy},
                              {"line_precision", m.lines.precision},
                              {"line_recall", m.lines.recall},
                              {"line_f1", m.lines.f1},
                              {"circle_radius_err_max", m.lines.circle_err_max},
                              {"constraint_precision", m.constraints.precision},
                              {"constraint_recall", m.constraints.recall},
                              {"missed_primitives", m.primitives.missed}};
    std::ofstream(a.get("--json", "")) << j.dump(2) << "\n";
  }
  return 0;
}

// ----------------------------------------------------------------------------- speed
TriangleSoup subdivide(const TriangleSoup& in) {
  TriangleSoup out;
  out.vertices = in.vertices;
  std::unordered_map<std::uint64_t, int> mid;
  mid.reserve(in.faces.size() * 2);
  auto midpoint = [&](int a, int b) {
    const auto k = undirected_edge_key(a, b);
    const auto it = mid.find(k);
    if (it != mid.end()) return it->second;
    out.vertices.push_back(0.5 * (in.vertices[a] + in.vertices[b]));
    return mid[k] = int(out.vertices.size()) - 1;
  };
  out.faces.reserve(in.faces.size() * 4);
  for (const auto& f : in.faces) {
    const int ab = midpoint(f[0], f[1]), bc = midpoint(f[1], f[2]), ca = midpoint(f[2], f[0]);
    out.faces.push_back({f[0], ab, ca});
    out.faces.push_back({f[1], bc, ab});
    out.faces.push_back({f[2], ca, bc});
    out.faces.push_back({ab, bc, ca});
  }
  return out;
}

/// --mesh (default the CGAL fandisk) subdivided 1→4 until it has --vertices (default 1 M) into
/// `soup`; returns the number of subdivisions.
int subdivided_soup(const Args& a, const std::string& path, TriangleSoup& soup) {
  const std::size_t target = std::stoull(a.get("--vertices", "1000000"));
  soup = read_soup(path);
  int levels = 0;
  while (soup.vertices.size() < target) {
    soup = subdivide(soup);
    ++levels;
  }
  return levels;
}

/// The same as a half-edge mesh.
int subdivided_mesh(const Args& a, const std::string& path, Mesh& mesh) {
  TriangleSoup soup;
  const int levels = subdivided_soup(a, path, soup);
  soup_to_mesh(soup, mesh);
  mesh.update_normals();
  return levels;
}

std::string speed_mesh_path(const Args& a) {
  return a.get("--mesh", std::string(S2C_SHARED_DIR) + "/data/real/cad/cgal_fandisk.off");
}

int cmd_speed(const Args& a) {
  const std::string path = speed_mesh_path(a);
  const int repeat = std::stoi(a.get("--repeat", "3"));
  TriangleSoup soup;
  const int levels = subdivided_soup(a, path, soup);
  if (const std::string out = a.get("--write", ""); !out.empty()) {  // for timing `scan2cad features` on it
    Mesh mesh;
    soup_to_mesh(soup, mesh);
    write_mesh(mesh, out);
  }
  double best = 1e30, first = 0.0;
  nlohmann::json best_report;
  std::size_t patches = 0, lines = 0, groups = 0;
  for (int i = 0; i < repeat; ++i) {
    nlohmann::json report;
    // The analysis `scan2cad features` runs: from the indexed faces as read, which it takes over.
    TriangleSoup faces = soup;
    const auto t0 = Clock::now();
    const features::Analysis an = features::analyze(std::move(faces), features::FeatureOptions{}, &report);
    const double s = seconds_since(t0);
    std::fprintf(stderr, "run %d: %.3f s\n", i + 1, s);
    if (i == 0) first = s;  // the run a fresh process makes: its memory touched for the first time
    if (s < best) {
      best = s;
      best_report = report;
      patches = an.features.patches.size();
      lines = an.features.lines.size();
      groups = an.features.groups.size();
    }
  }
  std::printf(
      "| mesh | subdivisions | vertices | faces | threads | analyze best of %d (s) | first run (s) | patches | lines | "
      "groups |\n",
      repeat);
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  std::printf("| %s | %d | %zu | %zu | %d | %.3f | %.3f | %zu | %zu | %zu |\n",
              std::filesystem::path(path).filename().string().c_str(), levels, soup.vertices.size(), soup.faces.size(),
              tbb::this_task_arena::max_concurrency(), best, first, patches, lines, groups);
  std::fprintf(stderr, "report of the best run: %s\n", best_report.dump().c_str());
  return 0;
}

int cmd_read(const Args& a) {
  if (a.positional.empty()) throw InvalidInput("read: which mesh? (s2c-bench-features read MESH)");
  const std::string path = a.positional[0];
  const int repeat = std::max(1, std::stoi(a.get("--repeat", "5")));
  std::vector<double> ours, peer;
  std::size_t vertices = 0, faces = 0, peer_faces = 0;
  for (int i = 0; i < repeat; ++i) {
    auto t0 = Clock::now();
    {
      const TriangleSoup soup = read_soup(path);
      ours.push_back(seconds_since(t0));
      vertices = soup.vertices.size();
      faces = soup.faces.size();
    }
    t0 = Clock::now();
    {
      Mesh mesh;
      mesh.request_vertex_normals();
      OpenMesh::IO::Options opt = OpenMesh::IO::Options::VertexNormal;
      if (!OpenMesh::IO::read_mesh(mesh, path, opt)) throw InvalidInput(path + ": OpenMesh could not read it");
      peer.push_back(seconds_since(t0));
      peer_faces = mesh.n_faces();
    }
  }
  auto best = [](std::vector<double> v) { return *std::min_element(v.begin(), v.end()); };
  auto median = [](std::vector<double> v) {
    std::nth_element(v.begin(), v.begin() + v.size() / 2, v.end());
    return v[v.size() / 2];
  };
  std::printf("| mesh | bytes | vertices | faces | read_soup best / median (s) | OpenMesh read_mesh best / median (s) | "
              "OpenMesh / ours (median) |\n|---|---|---|---|---|---|---|\n");
  std::printf("| %s | %ju | %zu | %zu (OpenMesh %zu) | %.3f / %.3f | %.3f / %.3f | %.1f |\n",
              std::filesystem::path(path).filename().string().c_str(), std::filesystem::file_size(path), vertices,
              faces, peer_faces, best(ours), median(ours), best(peer), median(peer), median(peer) / median(ours));
  return 0;
}

/// The tensor voting alone on the speed command's mesh (vote_tensors: the mesh's arrays, then the
/// vote at the clean default radius of one median edge), best of --repeat, with the class counts.
int cmd_voting(const Args& a) {
  const std::string path = speed_mesh_path(a);
  const int repeat = std::max(1, std::stoi(a.get("--repeat", "10")));
  Mesh mesh;
  subdivided_mesh(a, path, mesh);
  std::vector<double> lengths;
  for (const auto e : mesh.edges()) lengths.push_back(mesh.calc_edge_length(e));
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
  const double edge = lengths[lengths.size() / 2];  // the clean default radius: one median edge
  double best = 1e30;
  std::array<std::size_t, 3> classes{};
  for (int i = 0; i < repeat; ++i) {
    const auto t0 = Clock::now();
    const auto tensors = features::vote_tensors(mesh, edge, features::FeatureOptions{}.min_crease_deg, 0.0);
    best = std::min(best, seconds_since(t0));
    if (i == 0)
      for (const auto& t : tensors) ++classes[static_cast<int>(t.cls)];
  }
  std::printf("| mesh | vertices | arrays + vote, best of %d (s) | face | crease | corner |\n|---|---|---|---|---|---|\n",
              repeat);
  std::printf("| %s | %zu | %.3f | %zu | %zu | %zu |\n", std::filesystem::path(path).filename().string().c_str(),
              mesh.n_vertices(), best, classes[static_cast<int>(features::VertexClass::face)],
              classes[static_cast<int>(features::VertexClass::crease)],
              classes[static_cast<int>(features::VertexClass::corner)]);
  return 0;
}

// ----------------------------------------------------------------------------- fits
/// n samples of the torus (R, r) over u ∈ [0, 0.8], v ∈ [0.2, 0.9] (radians), with its normals.
features::Samples torus_band(int n, double R, double r, unsigned seed) {
  features::Samples s;
  std::mt19937 g(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int i = 0; i < n; ++i) {
    const double u = 0.8 * unit(g), v = 0.2 + 0.7 * unit(g);
    const Eigen::Vector3d normal(std::cos(v) * std::cos(u), std::cos(v) * std::sin(u), std::sin(v));
    s.points.push_back(Eigen::Vector3d(R * std::cos(u), R * std::sin(u), 0.0) + r * normal);
    s.normals.push_back(normal);
    s.weights.push_back(1.0);
  }
  return s;
}

int cmd_fits(const Args& a) {
  const int repeat = std::max(1, std::stoi(a.get("--repeat", "100")));
  std::printf("| samples | cone + cylinder + sphere, best of %d (ms) |\n|---|---|\n", repeat);
  double checksum = 0.0;
  for (int n : {60, 250, 1000, 4000}) {
    const features::Samples s = torus_band(n, 10.0, 2.0, static_cast<unsigned>(n));
    double best = 1e30;
    for (int k = 0; k < repeat; ++k) {
      const auto t0 = Clock::now();
      const features::Fit c = features::fit_cone(s), y = features::fit_cylinder(s), p = features::fit_sphere(s);
      best = std::min(best, seconds_since(t0));
      if (k == 0)
        checksum += c.rms + y.rms + p.rms + c.shape.point.sum() + c.shape.dir.sum() + y.shape.point.sum() +
                    y.shape.dir.sum() + y.shape.radius + p.shape.point.sum() + p.shape.radius;
    }
    std::printf("| %d | %.3f |\n", n, best * 1e3);
  }
  std::printf("\nchecksum %.17g\n", checksum);
  return 0;
}

// ----------------------------------------------------------------------------- selfcheck
int failures = 0;

void expect(bool ok, const std::string& what) {
  if (!ok) {
    ++failures;
    std::fprintf(stderr, "selfcheck FAILED: %s\n", what.c_str());
  }
}

bool near(double a, double b) { return std::abs(a - b) < 1e-9; }

bool mentions(const std::string& pair, const std::string& id) {
  return pair.find("(" + id + ",") != std::string::npos || pair.find("," + id + ")") != std::string::npos;
}

// A member of two truth constraints of the same equivalence kind links their classes; dropping
// it would split a class, so the self-check perturbs only features that are no such hub.
bool is_hub(const bench::Truth& t, const std::string& id) {
  std::map<features::ConstraintKind, int> n;
  for (const auto& c : t.constraints)
    if (std::count(c.members.begin(), c.members.end(), id)) ++n[c.kind];
  for (const auto& [k, count] : n)
    if (count > 1 && k != features::ConstraintKind::perpendicular && k != features::ConstraintKind::fixed_angle &&
        k != features::ConstraintKind::connected)
      return true;
  return false;
}

int cmd_selfcheck(const Args& a) {
  const std::string dir = a.get("--parts", default_parts());
  for (const std::string name : {"plate", "shaft", "bracket", "pocket"}) {
    const bench::Truth truth = bench::read_truth(dir + "/" + name + ".truth.json");
    expect(!truth.mesh.empty(), name + ": truth mesh read");
    Mesh mesh;
    const features::FeatureSet exact = bench::truth_as_features(truth, mesh);
    const bench::Tolerances tol;
    const FeatureMetrics m = bench::evaluate(mesh, exact, truth, tol);
    print_details(name + " exact", m);
    expect(near(m.primitives.recall, 1), name + ": primitive recall 1");
    expect(near(m.primitives.type_accuracy, 1) && near(m.primitives.labelled_share, 1), name + ": type accuracy 1");
    expect(near(m.lines.precision, 1) && near(m.lines.recall, 1) && near(m.lines.f1, 1), name + ": line P/R/F1 1");
    int circles = 0;
    for (const auto& l : truth.lines) circles += l.shape.type == features::ShapeType::circle;
    expect(m.lines.matched_circles == circles && m.lines.circle_err_max < 1e-12, name + ": circles exact");
    expect(near(m.constraints.precision, 1) && m.constraints.checked == int(truth.constraints.size()),
           name + ": constraint precision 1");
    expect(near(m.constraints.recall, 1) && m.constraints.truth_pairs > 0, name + ": constraint recall 1");

    // Extra detected constraints, mapped but judged on the truth shapes: true though not listed
    // in the truth (connected across a truth edge), and false ones.
    {
      features::FeatureSet f = exact;
      auto add = [&](features::ConstraintKind kind, int x, int y) {
        features::Group g;
        g.id = "X" + std::to_string(f.groups.size());
        g.kind = "constraint";
        g.constraint = kind;
        g.members = {"P" + std::to_string(x), "P" + std::to_string(y)};
        f.groups.push_back(g);
      };
      const auto edge = truth.primitive_edges.begin()->first;
      add(features::ConstraintKind::connected, edge.first, edge.second);
      int falses = 0;
      for (const auto& c : truth.constraints)
        if (c.kind == features::ConstraintKind::parallel && c.members.size() == 2) {
          int first = -1, second = -1;
          for (int i = 0; i < int(truth.primitives.size()); ++i) {
            if (truth.primitives[i].id == c.members[0]) first = i;
            if (truth.primitives[i].id == c.members[1]) second = i;
          }
          if (first >= 0 && second >= 0) add(features::ConstraintKind::perpendicular, first, second), ++falses;
          break;
        }
      add(features::ConstraintKind::equal_radius, 0, int(truth.primitives.size()) - 1), ++falses;  // plane first
      const FeatureMetrics q = bench::evaluate(mesh, f, truth, tol);
      const int n = int(truth.constraints.size());
      expect(q.constraints.checked == n + 1 + falses && q.constraints.correct == n + 1 && q.constraints.unmapped == 0,
             name + ": one true and " + std::to_string(falses) + " false extra constraints judged right");
    }

    // The perturbed features: the last plane and the first cylinder/sphere that are no hubs.
    int plane = -1, round = -1;
    for (int i = 0; i < int(truth.primitives.size()); ++i) {
      const auto& p = truth.primitives[i];
      if (is_hub(truth, p.id)) continue;
      if (p.shape.type == features::ShapeType::plane) plane = i;
      if (round < 0 && (p.shape.type == features::ShapeType::cylinder || p.shape.type == features::ShapeType::sphere))
        round = i;
    }
    expect(plane >= 0 && round >= 0, name + ": a plane and a round feature to perturb");
    if (plane < 0 || round < 0) continue;
    const std::string pid = truth.primitives[plane].id, rid = truth.primitives[round].id;
    for (const bool beyond : {true, false}) {
      features::FeatureSet f = exact;
      const Eigen::Vector3d n = f.patches[plane].shape.dir;
      const Eigen::Vector3d axis = n.cross(std::abs(n.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY());
      const double deg = beyond ? 5.0 : 1.5, scale = beyond ? 1.05 : 1.015;
      f.patches[plane].shape.dir = Eigen::AngleAxisd(deg * M_PI / 180, axis.normalized()) * n;
      f.patches[round].shape.radius *= scale;
      const FeatureMetrics q = bench::evaluate(mesh, f, truth, tol);
      const std::string what = name + (beyond ? ": beyond tolerance (" : ": within tolerance (") + pid + " rotated, " +
                               rid + " radius scaled)";
      print_details(what, q);
      expect(near(q.primitives.type_accuracy, 1) && near(q.lines.f1, 1), what + ": types and lines unchanged");
      if (!beyond) {
        expect(near(q.primitives.recall, 1) && near(q.constraints.precision, 1) && near(q.constraints.recall, 1),
               what + ": nothing lost");
        continue;
      }
      expect(q.primitives.matched == q.primitives.truth - 2, what + ": recall loses exactly two");
      std::set<std::string> missed(q.primitives.missed.begin(), q.primitives.missed.end());
      expect(missed == std::set<std::string>{pid, rid}, what + ": the two missed are the perturbed ones");
      int with = 0;
      for (const auto& c : truth.constraints)
        with += std::count(c.members.begin(), c.members.end(), pid) + std::count(c.members.begin(), c.members.end(), rid) > 0;
      expect(q.constraints.checked - q.constraints.correct == with && q.constraints.unmapped == with,
             what + ": exactly the constraints on them are wrong (" + std::to_string(with) + ")");
      std::set<std::string> expected_missed;
      for (const auto& pair : m.constraints.recalled)
        if (mentions(pair, pid) || mentions(pair, rid)) expected_missed.insert(pair);
      const std::set<std::string> got(q.constraints.missed.begin(), q.constraints.missed.end());
      expect(!expected_missed.empty() && got == expected_missed,
             what + ": exactly the constraint pairs on them are missed (" + std::to_string(expected_missed.size()) + ")");
    }
    std::printf("selfcheck %s: %zu primitives, %zu lines, %zu constraints (%d implied pairs)\n", name.c_str(),
                truth.primitives.size(), truth.lines.size(), truth.constraints.size(), m.constraints.truth_pairs);
  }
  std::printf("selfcheck: %s\n", failures ? "FAILED" : "ok");
  return failures ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  // As scan2cad-features does: the timings are those of the stage.
  s2c::reuse_freed_memory();
  if (argc < 2 || std::string(argv[1]) == "--help") {
    std::printf("%s", kUsage);
    return argc < 2 ? 2 : 0;
  }
  try {
    const std::string cmd = argv[1];
    const Args a = parse_args(argc, argv, 2);
    if (a.flags.count("--help")) {
      std::printf("%s", kUsage);
      return 0;
    }
    if (cmd == "sweep") return cmd_sweep(a);
    if (cmd == "mesh") return cmd_mesh(a);
    if (cmd == "inputs") return cmd_inputs(a);
    if (cmd == "speed") return cmd_speed(a);
    if (cmd == "selfcheck") return cmd_selfcheck(a);
    if (cmd == "fits") return cmd_fits(a);
    if (cmd == "voting") return cmd_voting(a);
    if (cmd == "read") return cmd_read(a);
    std::fprintf(stderr, "s2c-bench-features: unknown command %s\n%s", cmd.c_str(), kUsage);
    return 2;
  } catch (const InvalidInput& e) {
    std::fprintf(stderr, "s2c-bench-features: %s\n", e.what());
    return 2;
  } catch (const IoError& e) {
    std::fprintf(stderr, "s2c-bench-features: %s\n", e.what());
    return 4;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "s2c-bench-features: %s\n", e.what());
    return 3;
  }
}
