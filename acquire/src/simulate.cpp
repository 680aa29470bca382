#include "s2c/acquire/simulate.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "s2c/core/distance.h"
#include "s2c/core/errors.h"
#include "s2c/core/progress.h"

namespace s2c {
namespace {

// Counter-based random numbers: each pixel's noise depends only on (seed, frame, pixel), so the
// output is identical whatever the thread scheduling.
std::uint64_t splitmix(std::uint64_t x) {
  x += 0x9e3779b97f4a7c15ull;
  x = (x ^ (x >> 30)) * 0xbf58476d1ce4e5b9ull;
  x = (x ^ (x >> 27)) * 0x94d049bb133111ebull;
  return x ^ (x >> 31);
}

double gaussian(std::uint64_t key) {
  const std::uint64_t a = splitmix(key), b = splitmix(a);
  const double u1 = (static_cast<double>(a >> 11) + 0.5) * (1.0 / 9007199254740992.0);
  const double u2 = static_cast<double>(b >> 11) * (1.0 / 9007199254740992.0);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

double auto_depth_unit(double max_range_mm) {
  for (double u : {0.01, 0.02, 0.05, 0.1, 0.2, 0.5, 1.0, 2.0, 5.0})
    if (max_range_mm / u < 60000) return u;
  throw InvalidInput(fmt::format("part too large for 16-bit depth: range {:.0f} mm", max_range_mm));
}

void validate(const SimulateOptions& o) {
  auto bad = [](const std::string& m) { throw InvalidInput(m); };
  if (o.views < 1 || o.views > 720) bad(fmt::format("--views {} out of range (1..720)", o.views));
  if (!(o.noise_mm >= 0) || o.noise_mm > 100) bad(fmt::format("--noise {} out of range (0..100 mm)", o.noise_mm));
  if (o.width < 8 || o.height < 8 || o.width > 8192 || o.height > 8192) bad("image size out of range (8..8192)");
  if (!(o.focal_px > 0)) bad("focal length must be positive");
  if (!(o.grazing_limit_deg > 0 && o.grazing_limit_deg <= 90)) bad("grazing limit must be in (0, 90] degrees");
  if (o.distance_mm < 0 || o.depth_unit_mm < 0 || o.profile_step_mm < 0) bad("lengths must not be negative");
}

struct Measurement {
  std::uint16_t raw = 0;
  bool grazing = false;
};

// One ray: hit, incidence-dependent noise along the ray, dropout beyond the grazing limit,
// then quantisation of the z (depth) coordinate in the sensor frame.
Measurement measure(const SurfaceQuery& surface, const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                    const Eigen::Vector3d& optical_axis, const SimulateOptions& o, double unit, std::uint64_t key) {
  const auto hit = surface.raycast(origin, dir);
  if (!hit) return {};
  const double cos_inc = std::abs(hit->normal.dot(dir));
  if (cos_inc < std::cos(o.grazing_limit_deg * M_PI / 180.0)) return {0, true};
  const double sigma = o.noise_mm / std::max(cos_inc, 1e-3);
  const double range = hit->t + sigma * gaussian(key);
  const double z = range * dir.dot(optical_axis);
  const double counts = std::round(z / unit);
  if (counts < 1 || counts > 65535) return {};
  return {static_cast<std::uint16_t>(counts), false};
}

}  // namespace

std::vector<Eigen::Isometry3d> turntable_poses(const Eigen::Vector3d& center, double distance, int views,
                                               double elevation_deg) {
  std::vector<Eigen::Isometry3d> poses;
  for (int i = 0; i < views; ++i) {
    const double az = 2.0 * M_PI * i / views;
    const double el = (i % 2 == 0 ? 1.0 : -1.0) * elevation_deg * M_PI / 180.0;
    const Eigen::Vector3d eye = center + distance * Eigen::Vector3d(std::cos(el) * std::cos(az),
                                                                    std::cos(el) * std::sin(az), std::sin(el));
    const Eigen::Vector3d z = (center - eye).normalized();
    Eigen::Vector3d x = z.cross(Eigen::Vector3d::UnitZ());
    if (x.norm() < 1e-9) x = Eigen::Vector3d::UnitX();  // looking straight up or down
    x.normalize();
    const Eigen::Vector3d y = z.cross(x);
    Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
    T.linear() << x, y, z;
    T.translation() = eye;
    poses.push_back(T);
  }
  return poses;
}

SimulateReport simulate_scan(const TriangleSoup& part, const std::filesystem::path& out_dir, const SimulateOptions& o) {
  validate(o);
  if (part.faces.empty()) throw InvalidInput("the part has no faces");
  const Bounds b = bounds(part);
  const double radius = 0.5 * b.diagonal();
  if (!(radius > 0)) throw InvalidInput("the part has zero size");
  const bool laser = o.sensor == Sensor::laser;
  const double half_fov = std::atan(0.5 * std::min(o.width, laser ? o.width : o.height) / o.focal_px);
  SimulateReport rep;
  rep.distance_mm = o.distance_mm > 0 ? o.distance_mm : radius / std::sin(0.9 * half_fov);
  if (o.distance_mm == 0 && rep.distance_mm <= radius) throw InvalidInput("the part does not fit in view; set --distance");
  rep.depth_unit_mm = o.depth_unit_mm > 0 ? o.depth_unit_mm : auto_depth_unit(rep.distance_mm + radius);
  rep.profile_step_mm = o.profile_step_mm > 0 ? o.profile_step_mm : rep.distance_mm / o.focal_px;

  StreamInfo info;
  info.sensor = o.sensor;
  info.device = laser ? "simulate:laser" : "simulate:depth";
  info.width = o.width;
  info.depth_unit_mm = rep.depth_unit_mm;
  info.camera_matrix << o.focal_px, 0, (o.width - 1) / 2.0, 0, o.focal_px, (o.height - 1) / 2.0, 0, 0, 1;
  // A laser sweep covers the bounding sphere: rows advance the profile plane along +y.
  const int laser_rows = static_cast<int>(std::ceil(2.0 * radius / rep.profile_step_mm)) + 1;
  if (laser) {
    info.height = laser_rows;
    info.camera_matrix(1, 1) = o.focal_px;
    info.camera_matrix(1, 2) = 0;
    info.profile_step_mm = rep.profile_step_mm;
  } else {
    info.height = o.height;
  }

  const SurfaceQuery surface(part);
  const auto poses = turntable_poses(b.center(), rep.distance_mm, o.views, o.elevation_deg);
  StreamWriter writer(out_dir, info);
  Progress progress("views", poses.size());
  const double fx = info.camera_matrix(0, 0), fy = info.camera_matrix(1, 1);
  const double cx = info.camera_matrix(0, 2), cy = info.camera_matrix(1, 2);
  std::vector<double> errors;

  for (std::size_t view = 0; view < poses.size(); ++view) {
    Eigen::Isometry3d T = poses[view];
    if (laser) T.translation() -= T.linear().col(1) * radius;  // row 0 starts one radius "above" the centre
    DepthImage img;
    img.width = info.width;
    img.height = info.height;
    img.data.assign(static_cast<std::size_t>(img.width) * img.height, 0);
    std::vector<char> grazing(img.data.size(), 0);
    const Eigen::Matrix3d R = T.linear();
    tbb::parallel_for(0, img.height, [&](int v) {
      for (int u = 0; u < img.width; ++u) {
        Eigen::Vector3d origin_c = Eigen::Vector3d::Zero(), dir_c;
        if (laser) {
          origin_c = Eigen::Vector3d(0, v * rep.profile_step_mm, 0);
          dir_c = Eigen::Vector3d((u - cx) / fx, 0, 1).normalized();
        } else {
          dir_c = Eigen::Vector3d((u - cx) / fx, (v - cy) / fy, 1).normalized();
        }
        const std::size_t px = static_cast<std::size_t>(v) * img.width + u;
        const std::uint64_t key = splitmix(o.seed ^ splitmix(view * 0x100000000ull + px));
        const Measurement m = measure(surface, T * origin_c, R * dir_c, R.col(2), o, rep.depth_unit_mm, key);
        img.data[px] = m.raw;
        grazing[px] = m.grazing;
      }
    });
    rep.grazing_dropouts += static_cast<std::size_t>(std::count(grazing.begin(), grazing.end(), 1));
    writer.add_frame(static_cast<double>(view), img, T);
    progress.advance();

    // Self-check: how far each back-projected measurement lies from the part.
    Stream s;
    s.info = info;
    s.frames = {{0.0, "", 0}};
    s.poses = {{0.0, T}};
    for (const auto& p : deproject(s, 0, img)) {
      const auto c = surface.closest(p, 10.0 * (o.noise_mm + rep.depth_unit_mm) + 1.0);
      errors.push_back(c ? c->distance : 10.0 * (o.noise_mm + rep.depth_unit_mm) + 1.0);
    }
  }
  writer.finish();
  rep.frames = static_cast<int>(poses.size());
  rep.measurements = errors.size();
  if (!errors.empty()) {
    double sum = 0;
    for (double e : errors) sum += e;
    rep.error_mean_mm = sum / errors.size();
    std::sort(errors.begin(), errors.end());
    rep.error_p99_mm = errors[static_cast<std::size_t>(0.99 * (errors.size() - 1))];
    rep.error_max_mm = errors.back();
  }
  return rep;
}

}  // namespace s2c
