#pragma once
/// \file The views of a scan, as reconstruct reads them: points in the sensor frame plus the
/// pose the recording gave (if any). Streams, plain TUM RGB-D folders, folders of depth images
/// and point clouds all become views.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace s2c {

struct View {
  std::string name;                          ///< frame file or cloud file, for messages
  std::vector<Eigen::Vector3d> points;       ///< sensor frame, mm
  std::vector<Eigen::Vector3d> to_sensor;    ///< unit direction towards the sensor per point, or empty if unknown
  std::optional<Eigen::Isometry3d> pose;     ///< sensor-to-world from the recording
  double spacing_mm = 0;                     ///< median nearest-neighbour distance within the view
  int width = 0, height = 0;                 ///< pixel grid of organized views (0 for plain clouds)
  std::vector<int> pixel;                    ///< per point, v · width + u in that grid
};

struct InputOptions {
  /// Pinhole intrinsics fx, fy, cx, cy (pixels) for folders without stream.yaml (TUM, depth images).
  std::optional<Eigen::Vector4d> intrinsics;
  double depth_unit_mm = 0;    ///< mm per depth count for such folders (0: TUM's 0.2)
  double input_unit_mm = 1.0;  ///< scale of cloud coordinates (1000 for clouds in metres)
};

/// Reads the views of every input. One stream directory, TUM folder or depth-image folder gives
/// one view per frame; each cloud file (.ply .pcd) gives one view (NaN points dropped).
/// \throw InvalidInput naming the file, the frame or the missing option.
std::vector<View> load_views(const std::vector<std::filesystem::path>& inputs, const InputOptions& options);

/// Parses "fx,fy,cx,cy". \throw InvalidInput
Eigen::Vector4d parse_intrinsics(const std::string& text);

}  // namespace s2c
