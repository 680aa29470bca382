#pragma once
/// \file The stream directory of DESIGN.md: what acquire and simulate record and reconstruct reads.
/// Depth sensors: one 16-bit PNG per view. Laser line scanners: one 16-bit PNG per sweep, one
/// profile per row (docs/formats.md).
#include <cstdint>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace s2c {

enum class Sensor { depth, laser };
const char* to_string(Sensor s);

struct StreamInfo {
  Sensor sensor = Sensor::depth;
  std::string device = "unknown";
  int width = 0, height = 0;                               ///< pixels per frame (laser: points × profiles)
  double depth_unit_mm = 1.0;                              ///< mm per PNG count
  Eigen::Matrix3d camera_matrix = Eigen::Matrix3d::Identity();  ///< fx 0 cx; 0 fy cy; 0 0 1 (pixels)
  Eigen::Matrix<double, 5, 1> dist_coeffs = Eigen::Matrix<double, 5, 1>::Zero();  ///< k1 k2 p1 p2 k3
  double pose_unit_mm = 1.0;                               ///< poses.txt translation unit (1000 = metres)
  double profile_step_mm = 0.0;                            ///< laser: sensor travel along its +y per row
};

struct StreamFrame {
  double timestamp = 0;  ///< seconds
  std::string file;      ///< relative to the stream directory, e.g. "depth/000000.png"
  int line = 0;          ///< line in depth.txt (for messages)
};

struct StreamPose {
  double timestamp = 0;
  Eigen::Isometry3d camera_to_world = Eigen::Isometry3d::Identity();  ///< translation in mm
};

struct Stream {
  std::filesystem::path dir;
  StreamInfo info;
  std::vector<StreamFrame> frames;
  std::vector<StreamPose> poses;  ///< empty when the stream has no poses.txt

  /// The pose recorded for a frame: same timestamp, or the nearest within 20 ms (TUM association).
  std::optional<Eigen::Isometry3d> pose_of(std::size_t frame) const;
};

/// A depth frame: width × height counts, row-major, 0 = no measurement.
struct DepthImage {
  int width = 0, height = 0;
  std::vector<std::uint16_t> data;
  std::uint16_t at(int u, int v) const { return data[static_cast<std::size_t>(v) * width + u]; }
};

/// Reads and validates stream.yaml, depth.txt and poses.txt.
/// \throw InvalidInput naming the file, the line or key, and what is wrong.
Stream read_stream(const std::filesystem::path& dir);

/// Reads a live sensor's calibration (OpenCV YAML; docs/acquire.md): camera_matrix, dist_coeffs
/// and depth_unit_mm; for a laser also width (fan rays) and profile_step_mm. image_width and
/// image_height, when present, are the size the intrinsics belong to (0 otherwise).
/// \throw InvalidInput naming the file and the missing or bad key.
StreamInfo read_calibration(const std::filesystem::path& file, Sensor sensor);

/// Reads frame `i`. \throw InvalidInput naming the frame file if it is missing, unreadable,
///        not 16-bit single channel, or of the wrong size.
DepthImage read_frame(const Stream& stream, std::size_t i);

/// Back-projection of a sensor's pixels: a ray per pixel computed once (undistorted like
/// cv::undistortPoints), reused for every frame.
class Deprojector {
 public:
  explicit Deprojector(const StreamInfo& info);
  /// Points of the valid pixels in the sensor frame (mm), row-major. `to_sensor`, if given,
  /// receives the unit direction from each point towards where it was seen from.
  /// `pixels`, if given, receives each point's pixel index (v · width + u).
  std::vector<Eigen::Vector3d> sensor_points(const DepthImage& depth,
                                             std::vector<Eigen::Vector3d>* to_sensor = nullptr,
                                             std::vector<int>* pixels = nullptr) const;

 private:
  StreamInfo info_;
  std::vector<Eigen::Vector2d> rays_;  // (x/z, y/z) per pixel; laser: (x/z, row offset in mm)
};

/// Back-projects frame pixels into world coordinates (mm) using the camera matrix, distortion
/// and the frame's pose (identity without poses). `view_dirs`, if given, receives the unit
/// direction from each point towards the sensor (for normal orientation).
std::vector<Eigen::Vector3d> deproject(const Stream& stream, std::size_t i, const DepthImage& depth,
                                       std::vector<Eigen::Vector3d>* view_dirs = nullptr);

/// Writes a stream directory atomically: everything goes to a temporary sibling folder that
/// replaces `dir` on finish(); destroyed unfinished, it removes the temporary folder.
class StreamWriter {
 public:
  StreamWriter(std::filesystem::path dir, StreamInfo info);
  ~StreamWriter();
  StreamWriter(const StreamWriter&) = delete;
  StreamWriter& operator=(const StreamWriter&) = delete;

  void add_frame(double timestamp, const DepthImage& depth, const std::optional<Eigen::Isometry3d>& pose);
  void finish();

 private:
  std::filesystem::path dir_, temp_;
  StreamInfo info_;
  std::vector<StreamFrame> frames_;
  std::vector<StreamPose> poses_;
  bool finished_ = false;
};

/// The stream's 16-bit PNG bytes of a depth image: the same image always gives the same bytes,
/// so a replayed and re-recorded stream is byte-identical to the original.
std::string encode_depth_png(const DepthImage& depth);
/// Writes stream.yaml for `info` (not atomically: callers write into a folder of their own).
void write_stream_yaml(const std::filesystem::path& file, const StreamInfo& info);

/// The lines of depth.txt and poses.txt, and their header comments.
constexpr const char* kIndexHeader = "# scan2cad stream: timestamp filename\n";
constexpr const char* kPosesHeader = "# timestamp tx ty tz qx qy qz qw (camera-to-world, translation in pose_unit_mm)\n";
std::string index_line(const StreamFrame& frame);
std::string pose_line(const StreamPose& pose, double pose_unit_mm);

/// Writes a 16-bit single-channel PNG (atomically). \throw IoError
void write_depth_png(const std::filesystem::path& path, const DepthImage& depth);
/// Reads a 16-bit single-channel PNG. \throw InvalidInput naming the file.
DepthImage read_depth_png(const std::filesystem::path& path);

}  // namespace s2c
