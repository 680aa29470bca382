// s2c-bench-accuracy: how close is a reconstructed mesh to the true part, and how much of the
// true part does it cover? Samples both surfaces uniformly by area (deterministic seed) and
// measures each sample's distance to the other surface (Embree closest-point queries).
//
//   s2c-bench-accuracy RECON_MESH TRUE_MESH [--threshold 0.25] [--samples 200000] [--seed 1]
//                      [--edge-angle 30] [--edge-band 1] [--dump FILE.ply] [--cloud CLOUD.ply]
//
// Prints one JSON object on stdout. Besides the headline numbers it splits both directions by
// distance to the true part's sharp edges (dihedral angle above --edge-angle): where Poisson
// rounds edges off, the error concentrates in that band. With --cloud (the fused cloud the mesher
// saw) it also reports `cloud_coverage`: the fraction of the true part that has a data point
// within the threshold, i.e. the coverage the scan itself allows.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <numeric>
#include <thread>
#include <unordered_map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "s2c/core/cli.h"
#include "s2c/core/distance.h"
#include "s2c/core/errors.h"
#include "s2c/core/io.h"
#include "s2c/core/mesh.h"
#include "common/sampling.h"

namespace {

using Eigen::Vector3d;
using s2c::bench::Rng;
using s2c::bench::Samples;
using s2c::bench::sample_surface;
using s2c::bench::distances;

// The sharp edges of a (welded) triangle surface: dihedral angle above `angle_deg`, or an edge
// with other than two faces. Answers "is this point within `band` of a sharp edge?" via a grid.
class SharpEdges {
 public:
  SharpEdges(const s2c::TriangleSoup& soup, double angle_deg, double band) : band_(band) {
    std::unordered_map<std::uint64_t, std::vector<int>> edge_faces;
    auto key = [](int a, int b) {
      if (a > b) std::swap(a, b);
      return (static_cast<std::uint64_t>(a) << 32) | static_cast<std::uint32_t>(b);
    };
    for (std::size_t f = 0; f < soup.faces.size(); ++f)
      for (int k = 0; k < 3; ++k) edge_faces[key(soup.faces[f][k], soup.faces[f][(k + 1) % 3])].push_back(static_cast<int>(f));
    auto normal = [&](int f) {
      const auto& t = soup.faces[f];
      return (soup.vertices[t[1]] - soup.vertices[t[0]]).cross(soup.vertices[t[2]] - soup.vertices[t[0]]).normalized();
    };
    const double cos_max = std::cos(angle_deg * M_PI / 180.0);
    for (const auto& [k, fs] : edge_faces) {
      const bool sharp = fs.size() != 2 || normal(fs[0]).dot(normal(fs[1])) < cos_max;
      if (!sharp) continue;
      segments_.push_back({soup.vertices[k >> 32], soup.vertices[k & 0xffffffffu]});
    }
    for (std::size_t s = 0; s < segments_.size(); ++s) {
      const auto& [a, b] = segments_[s];
      const Eigen::Array3i lo = cell(a.cwiseMin(b)), hi = cell(a.cwiseMax(b));
      for (int x = lo.x(); x <= hi.x(); ++x)
        for (int y = lo.y(); y <= hi.y(); ++y)
          for (int z = lo.z(); z <= hi.z(); ++z) grid_[pack(x, y, z)].push_back(static_cast<int>(s));
    }
  }
  std::size_t count() const { return segments_.size(); }
  bool near(const Vector3d& p) const {
    const Eigen::Array3i c = cell(p);
    for (int dx = -1; dx <= 1; ++dx)
      for (int dy = -1; dy <= 1; ++dy)
        for (int dz = -1; dz <= 1; ++dz) {
          auto it = grid_.find(pack(c.x() + dx, c.y() + dy, c.z() + dz));
          if (it == grid_.end()) continue;
          for (int s : it->second) {
            const auto& [a, b] = segments_[s];
            const Vector3d ab = b - a;
            const double t = std::clamp((p - a).dot(ab) / std::max(ab.squaredNorm(), 1e-300), 0.0, 1.0);
            if ((a + t * ab - p).norm() <= band_) return true;
          }
        }
    return false;
  }

 private:
  Eigen::Array3i cell(const Vector3d& p) const { return (p / band_).array().floor().cast<int>(); }
  static std::uint64_t pack(int x, int y, int z) {
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(x) & 0x1fffff) << 42) |
           (static_cast<std::uint64_t>(static_cast<std::uint32_t>(y) & 0x1fffff) << 21) |
           (static_cast<std::uint64_t>(static_cast<std::uint32_t>(z) & 0x1fffff));
  }
  double band_;
  std::vector<std::pair<Vector3d, Vector3d>> segments_;
  std::unordered_map<std::uint64_t, std::vector<int>> grid_;
};

// Fraction of `pts` with a cloud point within `r` (hash grid of cell r).
double cloud_coverage(const std::vector<Vector3d>& cloud, const std::vector<Vector3d>& pts, double r) {
  auto key = [r](const Vector3d& p, int dx, int dy, int dz) {
    const Eigen::Array3i c = (p / r).array().floor().cast<int>();
    return (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.x() + dx) & 0x1fffff) << 42) |
           (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.y() + dy) & 0x1fffff) << 21) |
           (static_cast<std::uint64_t>(static_cast<std::uint32_t>(c.z() + dz) & 0x1fffff));
  };
  std::unordered_map<std::uint64_t, std::vector<int>> grid;
  for (std::size_t i = 0; i < cloud.size(); ++i) grid[key(cloud[i], 0, 0, 0)].push_back(static_cast<int>(i));
  std::size_t hit = 0;
  for (const auto& p : pts) {
    bool found = false;
    for (int dx = -1; dx <= 1 && !found; ++dx)
      for (int dy = -1; dy <= 1 && !found; ++dy)
        for (int dz = -1; dz <= 1 && !found; ++dz) {
          auto it = grid.find(key(p, dx, dy, dz));
          if (it == grid.end()) continue;
          for (int i : it->second)
            if ((cloud[i] - p).squaredNorm() <= r * r) {
              found = true;
              break;
            }
        }
    hit += found;
  }
  return pts.empty() ? 0.0 : static_cast<double>(hit) / static_cast<double>(pts.size());
}

double mean(const std::vector<double>& v) {
  return v.empty() ? 0.0 : std::accumulate(v.begin(), v.end(), 0.0) / static_cast<double>(v.size());
}
double rms(const std::vector<double>& v) {
  double s = 0;
  for (double x : v) s += x * x;
  return v.empty() ? 0.0 : std::sqrt(s / static_cast<double>(v.size()));
}
double quantile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  const std::size_t k = std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())));
  std::nth_element(v.begin(), v.begin() + static_cast<std::ptrdiff_t>(k), v.end());
  return v[k];
}
double fraction_within(const std::vector<double>& v, double t) {
  if (v.empty()) return 0.0;
  return static_cast<double>(std::count_if(v.begin(), v.end(), [t](double x) { return x <= t; })) /
         static_cast<double>(v.size());
}
double r6(double x) { return std::round(x * 1e6) / 1e6; }

// Samples farther than the threshold, as an ASCII PLY with their distance and direction
// (side 0: on the reconstruction, far from the true part; side 1: on the true part, uncovered).
void dump(const std::string& path, const std::vector<Vector3d>& a, const std::vector<double>& da,
          const std::vector<Vector3d>& b, const std::vector<double>& db, double threshold) {
  std::size_t n = 0;
  for (double d : da) n += d > threshold;
  for (double d : db) n += d > threshold;
  std::ofstream f(path);
  if (!f) throw s2c::IoError(fmt::format("{}: cannot write", path));
  f << "ply\nformat ascii 1.0\ncomment samples farther than " << threshold
    << " mm; side 0 = reconstruction→true, 1 = true→reconstruction\nelement vertex " << n
    << "\nproperty float x\nproperty float y\nproperty float z\nproperty float distance\nproperty uchar side\nend_header\n";
  auto put = [&](const std::vector<Vector3d>& p, const std::vector<double>& d, int side) {
    for (std::size_t i = 0; i < p.size(); ++i)
      if (d[i] > threshold) f << fmt::format("{:.5f} {:.5f} {:.5f} {:.5f} {}\n", p[i].x(), p[i].y(), p[i].z(), d[i], side);
  };
  put(a, da, 0);
  put(b, db, 1);
  if (!f.flush()) throw s2c::IoError(fmt::format("{}: write failed", path));
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Accuracy of a reconstructed mesh against the true part: samples both surfaces uniformly by\n"
      "area and prints one JSON object (distances in mm) on stdout.\n"
      "Example: s2c-bench-accuracy /tmp/plate.ply fixtures/parts/plate.stl",
      "s2c-bench-accuracy"};
  std::string recon_path, true_path, dump_path, cloud_path;
  double threshold = 0.25, edge_angle = 30, edge_band = 1.0;
  std::size_t samples = 200000;
  std::uint64_t seed = 1;
  app.add_option("RECON_MESH", recon_path, "Reconstructed mesh")->required();
  app.add_option("TRUE_MESH", true_path, "The true part")->required();
  app.add_option("--threshold", threshold, "Coverage distance, mm")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--samples", samples, "Samples per surface")->capture_default_str()->check(CLI::Range(100, 100000000));
  app.add_option("--seed", seed, "Sampling seed")->capture_default_str();
  app.add_option("--edge-angle", edge_angle, "Dihedral angle (deg) above which a true edge is sharp")->capture_default_str();
  app.add_option("--edge-band", edge_band, "Width (mm) of the band around sharp edges")->capture_default_str()->check(CLI::PositiveNumber);
  app.add_option("--cloud", cloud_path, "Fused cloud (.ply): also report the coverage the data itself allows");
  app.add_option("--dump", dump_path, "Write samples farther than the threshold to this ASCII PLY");
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }

  return s2c::run_guarded([&] {
    const s2c::TriangleSoup recon = s2c::read_soup(recon_path);
    const s2c::TriangleSoup truth = s2c::read_soup(true_path);
    const s2c::SurfaceQuery recon_q(recon), true_q(truth);
    const Samples on_recon = sample_surface(recon, samples, seed);
    const Samples on_true = sample_surface(truth, samples, seed + 1);
    std::vector<Vector3d> foot;  // closest true-surface point of each reconstruction sample
    const std::vector<double> d_rt = distances(true_q, on_recon.points, &foot);
    const std::vector<double> d_tr = distances(recon_q, on_true.points);

    // Split both directions by distance to the true part's sharp edges.
    const SharpEdges edges(truth, edge_angle, edge_band);
    std::vector<double> rt_near, rt_far, tr_near, tr_far;
    for (std::size_t i = 0; i < d_rt.size(); ++i) (edges.near(foot[i]) ? rt_near : rt_far).push_back(d_rt[i]);
    for (std::size_t i = 0; i < d_tr.size(); ++i) (edges.near(on_true.points[i]) ? tr_near : tr_far).push_back(d_tr[i]);
    std::size_t uncovered = 0, uncovered_near = 0;
    for (double d : d_tr) uncovered += d > threshold;
    for (double d : tr_near) uncovered_near += d > threshold;

    const double mean_rt = mean(d_rt), mean_tr = mean(d_tr);
    const double max_rt = *std::max_element(d_rt.begin(), d_rt.end());
    const double max_tr = *std::max_element(d_tr.begin(), d_tr.end());
    nlohmann::ordered_json j;
    j["recon"] = recon_path;
    j["true"] = true_path;
    j["samples"] = samples;
    j["seed"] = seed;
    j["threshold_mm"] = threshold;
    j["mean_recon_to_true_mm"] = r6(mean_rt);
    j["rms_recon_to_true_mm"] = r6(rms(d_rt));
    j["p95_recon_to_true_mm"] = r6(quantile(d_rt, 0.95));
    j["max_recon_to_true_mm"] = r6(max_rt);
    j["mean_true_to_recon_mm"] = r6(mean_tr);
    j["p95_true_to_recon_mm"] = r6(quantile(d_tr, 0.95));
    j["max_true_to_recon_mm"] = r6(max_tr);
    j["coverage"] = r6(fraction_within(d_tr, threshold));
    j["precision"] = r6(fraction_within(d_rt, threshold));
    j["chamfer_mm"] = r6(0.5 * (mean_rt + mean_tr));
    j["hausdorff_mm"] = r6(std::max(max_rt, max_tr));
    j["recon_faces"] = recon.faces.size();
    j["true_faces"] = truth.faces.size();
    j["recon_area_mm2"] = r6(on_recon.area);
    j["true_area_mm2"] = r6(on_true.area);
    j["sharp_edges"] = {{"angle_deg", edge_angle},
                        {"band_mm", edge_band},
                        {"segments", edges.count()},
                        {"recon_samples_near", rt_near.size()},
                        {"mean_recon_to_true_near_mm", r6(mean(rt_near))},
                        {"mean_recon_to_true_far_mm", r6(mean(rt_far))},
                        {"p95_recon_to_true_near_mm", r6(quantile(rt_near, 0.95))},
                        {"p95_recon_to_true_far_mm", r6(quantile(rt_far, 0.95))},
                        {"true_samples_near", tr_near.size()},
                        {"coverage_near", r6(fraction_within(tr_near, threshold))},
                        {"coverage_far", r6(fraction_within(tr_far, threshold))},
                        {"uncovered_share_near", r6(uncovered ? static_cast<double>(uncovered_near) / static_cast<double>(uncovered) : 0.0)}};
    if (!cloud_path.empty()) {
      const s2c::TriangleSoup cloud = s2c::read_soup(cloud_path, /*allow_empty=*/true);
      j["cloud_points"] = cloud.vertices.size();
      j["cloud_coverage"] = r6(cloud_coverage(cloud.vertices, on_true.points, threshold));
    }
    std::printf("%s\n", j.dump().c_str());
    if (!dump_path.empty()) dump(dump_path, on_recon.points, d_rt, on_true.points, d_tr, threshold);
  });
}
