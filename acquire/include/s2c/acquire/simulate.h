#pragma once
/// \file A virtual scanner: renders depth frames (or laser profiles) of a part with Embree ray
/// casting and a sensor noise model, and writes them as a stream directory (DESIGN.md).
#include <cstdint>
#include <filesystem>
#include <vector>

#include "s2c/core/mesh.h"
#include "s2c/core/stream.h"

namespace s2c {

struct SimulateOptions {
  Sensor sensor = Sensor::depth;
  int views = 12;                  ///< turntable positions (laser: sweeps); elevations alternate above/below
  double elevation_deg = 30;       ///< |elevation| of the views above and below the part's equator
  double noise_mm = 0.05;          ///< σ of range noise at normal incidence; grows as 1/cos(incidence)
  double grazing_limit_deg = 75;   ///< no measurement beyond this incidence angle (dropout)
  std::uint64_t seed = 1;          ///< same seed → byte-identical stream
  int width = 640, height = 480;   ///< depth image size; laser: points per profile = width
  double focal_px = 525;           ///< fx = fy (pixels)
  double distance_mm = 0;          ///< sensor to part centre; 0 = fit the part's bounding sphere in view
  double depth_unit_mm = 0;        ///< 0 = finest of 0.01/0.02/0.05/0.1/0.2/0.5/1 that covers the range
  double profile_step_mm = 0;      ///< laser travel per profile; 0 = the lateral point spacing
};

struct SimulateReport {
  int frames = 0;
  std::size_t measurements = 0;       ///< valid pixels / profile points over all frames
  std::size_t grazing_dropouts = 0;   ///< hits rejected beyond the grazing limit
  double distance_mm = 0, depth_unit_mm = 0, profile_step_mm = 0;
  /// Distance of every back-projected measurement to the part (mm): how faithful the stream is.
  double error_mean_mm = 0, error_p99_mm = 0, error_max_mm = 0;
};

/// Camera-to-world poses of the views (OpenCV camera: +z forward, +x right, +y down),
/// looking at `center` from `distance` (mm).
std::vector<Eigen::Isometry3d> turntable_poses(const Eigen::Vector3d& center, double distance, int views,
                                               double elevation_deg);

/// Scans `part` and writes the stream to `out_dir` (atomically).
/// \throw InvalidInput for an empty part or bad options.
SimulateReport simulate_scan(const TriangleSoup& part, const std::filesystem::path& out_dir,
                             const SimulateOptions& options = {});

}  // namespace s2c
