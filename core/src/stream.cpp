#include "s2c/core/stream.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <regex>
#include <sstream>

#include <fmt/format.h>
#include <opencv2/core.hpp>

#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "depth_image.h"

namespace fs = std::filesystem;

namespace s2c {
namespace {

constexpr const char* kFormat = "scan2cad.stream/1";

[[noreturn]] void bad(const fs::path& file, const std::string& what) {
  throw InvalidInput(fmt::format("{}: {}", file.string(), what));
}

cv::FileNode need(const cv::FileStorage& fs, const fs::path& file, const char* key) {
  cv::FileNode n = fs[key];
  if (n.empty()) bad(file, fmt::format("missing key '{}'", key));
  return n;
}

double need_number(const cv::FileStorage& fs, const fs::path& file, const char* key) {
  cv::FileNode n = need(fs, file, key);
  if (!n.isReal() && !n.isInt()) bad(file, fmt::format("key '{}' must be a number", key));
  const double v = n.real();
  if (!std::isfinite(v)) bad(file, fmt::format("key '{}' is not finite", key));
  return v;
}

cv::Mat need_matrix(const cv::FileStorage& fs, const fs::path& file, const char* key, int rows, int cols) {
  cv::FileNode n = need(fs, file, key);
  // Check the shape before OpenCV reads it: it allocates rows × cols as written, whatever they are.
  if (!n.isMap() || !n["rows"].isInt() || !n["cols"].isInt() || !n["data"].isSeq())
    bad(file, fmt::format("key '{}' is not an !!opencv-matrix (rows, cols, dt, data)", key));
  if (static_cast<int>(n["rows"]) * static_cast<long long>(static_cast<int>(n["cols"])) != rows * cols ||
      n["data"].size() != static_cast<std::size_t>(rows * cols))
    bad(file, fmt::format("key '{}' must be a {}x{} matrix (found rows {}, cols {}, {} values)", key, rows, cols,
                          static_cast<int>(n["rows"]), static_cast<int>(n["cols"]), n["data"].size()));
  cv::Mat m;
  try {
    n >> m;
  } catch (const std::exception&) {
    bad(file, fmt::format("key '{}' is not an !!opencv-matrix", key));
  }
  if (m.empty() || m.rows * m.cols != rows * cols)
    bad(file, fmt::format("key '{}' must be a {}x{} matrix (found {}x{})", key, rows, cols, m.rows, m.cols));
  m.convertTo(m, CV_64F);
  m = m.reshape(1, rows);
  for (int i = 0; i < m.rows * m.cols; ++i)
    if (!std::isfinite(m.at<double>(i))) bad(file, fmt::format("key '{}' has a non-finite entry", key));
  return m;
}

/// OpenCV's YAML parser hangs or throws on some malformed documents (found by fuzzing), so a
/// stream.yaml or calibration file must first look like what OpenCV writes: a "%YAML:1.0" line,
/// "---", then `key: value` lines, indented `rows: / cols: / dt: / data:` lines of a matrix and
/// their continuation lines of numbers. No anchors, tags other than !!opencv-matrix, flow maps,
/// block scalars or complex keys.
void check_yaml_shape(const fs::path& file) {
  std::error_code ec;
  if (fs::file_size(file, ec) > 65536) bad(file, "larger than 64 KiB: not a stream.yaml / calibration file");
  std::ifstream in(file, std::ios::binary);
  std::string line;
  int no = 0;
  static const std::regex key_line(R"(^( {0,8})[A-Za-z_][A-Za-z0-9_]*:( .*)?$)");
  static const std::regex numbers_line(R"(^ +[-+0-9.eE, \[\]]*$)");
  static const std::regex value(R"(^ *("[^"\\]*"|'[^']*'|!!opencv-matrix|[-+0-9.eE]+|[A-Za-z_][A-Za-z0-9_ .:/-]*|\[[-+0-9.eE, ]*\]?)? *(#.*)?$)");
  while (std::getline(in, line)) {
    ++no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    for (unsigned char c : line)
      if (c < 0x20 || c > 0x7e) bad(file, fmt::format("line {}: byte 0x{:02x} (tabs and control bytes are not YAML here)", no, c));
    if (no == 1) {
      if (line != "%YAML:1.0" && line != "%YAML 1.0") bad(file, "line 1: expected %YAML:1.0 (an OpenCV FileStorage YAML file)");
      continue;
    }
    if (no == 2) {
      if (line != "---") bad(file, "line 2: expected ---");
      continue;
    }
    const auto first = line.find_first_not_of(' ');
    if (first == std::string::npos || line[first] == '#') continue;
    std::smatch m;
    if (std::regex_match(line, m, key_line)) {
      if (!std::regex_match(m[2].str().empty() ? std::string() : m[2].str().substr(1), value))
        bad(file, fmt::format("line {}: value '{}' is not a number, a string, a list of numbers or !!opencv-matrix", no,
                              m[2].str().substr(0, 60)));
    } else if (!std::regex_match(line, numbers_line)) {
      bad(file, fmt::format("line {}: expected 'key: value' or a continued list of numbers, found '{}'", no, line.substr(0, 60)));
    }
  }
  if (no < 2) bad(file, "expected %YAML:1.0 and --- (an OpenCV FileStorage YAML file)");
}

cv::FileStorage open_yaml(const fs::path& file, const char* what) {
  if (!fs::exists(file)) bad(file, fmt::format("missing: {}", what));
  check_yaml_shape(file);
  cv::FileStorage fs;
  try {
    if (!fs.open(file.string(), cv::FileStorage::READ | cv::FileStorage::FORMAT_YAML)) bad(file, "cannot be parsed as YAML");
  } catch (const cv::Exception& e) {
    bad(file, fmt::format("malformed YAML: {}", e.err));
  } catch (const std::exception& e) {  // OpenCV's parser also lets std::length_error out (found by fuzzing)
    bad(file, fmt::format("malformed YAML: {}", e.what()));
  }
  // A document that is a list or a scalar: OpenCV asserts (throws) on the first key lookup.
  if (!fs.root().isMap()) bad(file, "expected a map of keys (key: value lines)");
  return fs;
}

/// The optics every sensor shares: camera matrix, distortion, depth unit (and the laser's step).
void read_optics(const cv::FileStorage& fs, const fs::path& file, StreamInfo& info) {
  info.depth_unit_mm = need_number(fs, file, "depth_unit_mm");
  if (info.depth_unit_mm <= 0) bad(file, "depth_unit_mm must be positive");
  cv::Mat K = need_matrix(fs, file, "camera_matrix", 3, 3);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) info.camera_matrix(r, c) = K.at<double>(r, c);
  if (info.camera_matrix(0, 0) <= 0 || (info.sensor == Sensor::depth && info.camera_matrix(1, 1) <= 0))
    bad(file, "camera_matrix: focal lengths must be positive");
  cv::Mat D = need_matrix(fs, file, "dist_coeffs", 1, 5);
  for (int i = 0; i < 5; ++i) info.dist_coeffs[i] = D.at<double>(i);
  if (info.sensor == Sensor::laser) {
    info.profile_step_mm = need_number(fs, file, "profile_step_mm");
    if (info.profile_step_mm <= 0) bad(file, "profile_step_mm must be positive");
  }
}

int need_size(const cv::FileStorage& fs, const fs::path& file, const char* key) {
  const double v = need_number(fs, file, key);
  if (v < 1 || v > 16384 || v != std::floor(v)) bad(file, fmt::format("key '{}' = {} out of range (1..16384)", key, v));
  return static_cast<int>(v);
}

StreamInfo read_info_fields(const fs::path& file) {
  cv::FileStorage fs = open_yaml(file, "a stream directory needs stream.yaml (see docs/formats.md)");
  StreamInfo info;
  const std::string format = (std::string)need(fs, file, "format");
  if (format != kFormat) bad(file, fmt::format("format is '{}', expected '{}'", format, kFormat));
  const std::string sensor = (std::string)need(fs, file, "sensor");
  if (sensor == "depth") info.sensor = Sensor::depth;
  else if (sensor == "laser") info.sensor = Sensor::laser;
  else bad(file, fmt::format("sensor is '{}', expected depth or laser", sensor));
  if (!fs["device"].empty()) info.device = (std::string)fs["device"];
  info.width = need_size(fs, file, "width");
  info.height = need_size(fs, file, "height");
  read_optics(fs, file, info);
  info.pose_unit_mm = fs["pose_unit_mm"].empty() ? 1.0 : need_number(fs, file, "pose_unit_mm");
  if (info.pose_unit_mm <= 0) bad(file, "pose_unit_mm must be positive");
  return info;
}

/// OpenCV reports some malformed documents by throwing from a key lookup: still bad input.
template <class F>
auto yaml_guard(const fs::path& file, F&& read) -> decltype(read()) {
  try {
    return read();
  } catch (const cv::Exception& e) {
    bad(file, fmt::format("malformed: {}", e.err));
  }
}

StreamInfo read_info(const fs::path& file) {
  return yaml_guard(file, [&] { return read_info_fields(file); });
}

std::vector<std::string> split_fields(const std::string& line) {
  std::istringstream ss(line);
  std::vector<std::string> out;
  std::string t;
  while (ss >> t) out.push_back(t);
  return out;
}

double parse_double(const fs::path& file, int line, const std::string& tok, const char* what) {
  char* end = nullptr;
  const double v = std::strtod(tok.c_str(), &end);
  if (end == tok.c_str() || *end) bad(file, fmt::format("line {}: {} '{}' is not a number", line, what, tok));
  if (!std::isfinite(v)) bad(file, fmt::format("line {}: {} is {}", line, what, tok));
  return v;
}

template <class F>
void for_each_record(const fs::path& file, F&& f) {
  std::ifstream in(file);
  if (!in) throw IoError(fmt::format("{}: cannot open", file.string()));
  std::string line;
  int no = 0;
  while (std::getline(in, line)) {
    ++no;
    const auto first = line.find_first_not_of(" \t\r");
    if (first == std::string::npos || line[first] == '#') continue;
    f(no, split_fields(line));
  }
}

}  // namespace

const char* to_string(Sensor s) { return s == Sensor::depth ? "depth" : "laser"; }

StreamInfo read_calibration(const fs::path& file, Sensor sensor) {
  return yaml_guard(file, [&] {
    cv::FileStorage fs = open_yaml(file, "the calibration file does not exist");
    StreamInfo info;
    info.sensor = sensor;
    read_optics(fs, file, info);
    if (sensor == Sensor::laser) {
      info.width = need_size(fs, file, "width");  // the fan's rays: columns of a sweep
    } else if (!fs["image_width"].empty() || !fs["image_height"].empty()) {
      info.width = need_size(fs, file, "image_width");
      info.height = need_size(fs, file, "image_height");
    }
    return info;
  });
}

Stream read_stream(const fs::path& dir) {
  if (!fs::is_directory(dir)) throw InvalidInput(fmt::format("{}: not a stream directory", dir.string()));
  Stream s;
  s.dir = dir;
  s.info = read_info(dir / "stream.yaml");
  const fs::path index = dir / "depth.txt";
  if (!fs::exists(index)) bad(index, "missing: the frame index 'timestamp filename' per line");
  for_each_record(index, [&](int no, const std::vector<std::string>& f) {
    if (f.size() != 2) bad(index, fmt::format("line {}: expected 'timestamp filename', found {} fields", no, f.size()));
    StreamFrame fr{parse_double(index, no, f[0], "timestamp"), f[1], no};
    if (fr.file.find("..") != std::string::npos || fs::path(fr.file).is_absolute())
      bad(index, fmt::format("line {}: frame path '{}' must stay inside the stream directory", no, fr.file));
    s.frames.push_back(fr);
  });
  if (s.frames.empty()) bad(index, "lists no frames");
  const fs::path poses = dir / "poses.txt";
  if (fs::exists(poses)) {
    for_each_record(poses, [&](int no, const std::vector<std::string>& f) {
      if (f.size() != 8) bad(poses, fmt::format("line {}: expected 'timestamp tx ty tz qx qy qz qw', found {} fields", no, f.size()));
      double v[8];
      for (int i = 0; i < 8; ++i) v[i] = parse_double(poses, no, f[i], i == 0 ? "timestamp" : "pose value");
      Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
      if (std::abs(q.norm() - 1.0) > 1e-3)
        bad(poses, fmt::format("line {}: quaternion has norm {:.6f}, expected 1 (qx qy qz qw order)", no, q.norm()));
      StreamPose p;
      p.timestamp = v[0];
      p.camera_to_world.linear() = q.normalized().toRotationMatrix();
      p.camera_to_world.translation() = Eigen::Vector3d(v[1], v[2], v[3]) * s.info.pose_unit_mm;
      s.poses.push_back(p);
    });
  }
  return s;
}

std::optional<Eigen::Isometry3d> Stream::pose_of(std::size_t frame) const {
  const double t = frames.at(frame).timestamp;
  const StreamPose* best = nullptr;
  for (const auto& p : poses)
    if (!best || std::abs(p.timestamp - t) < std::abs(best->timestamp - t)) best = &p;
  if (!best || std::abs(best->timestamp - t) > 0.02) return std::nullopt;
  return best->camera_to_world;
}

/// \throw InvalidInput when frame `i` is not the size stream.yaml gives.
static void expect_frame_size(const Stream& s, std::size_t i, std::uint64_t w, std::uint64_t h) {
  if (w != static_cast<std::uint64_t>(s.info.width) || h != static_cast<std::uint64_t>(s.info.height))
    throw InvalidInput(fmt::format("{}: frame {} is {}x{}, stream.yaml says {}x{}", (s.dir / s.frames[i].file).string(), i,
                                   w, h, s.info.width, s.info.height));
}

DepthImage read_frame(const Stream& s, std::size_t i) {
  const fs::path path = s.dir / s.frames.at(i).file;
  if (const auto size = png_size(path)) expect_frame_size(s, i, size->first, size->second);  // before decoding
  DepthImage d = read_depth_png(path);
  expect_frame_size(s, i, d.width, d.height);  // formats without a readable header (TIFF)
  return d;
}

std::string index_line(const StreamFrame& f) { return fmt::format("{:.6f} {}\n", f.timestamp, f.file); }

std::string pose_line(const StreamPose& p, double pose_unit_mm) {
  Eigen::Quaterniond q(p.camera_to_world.linear());
  q.normalize();
  // q and −q are one rotation: always print the same one (w > 0, or the first non-zero component
  // positive), and no "−0", so that a pose read and written again gives the same line.
  Eigen::Vector4d c(q.w(), q.x(), q.y(), q.z());
  for (int i = 0; i < 4; ++i) c[i] = std::abs(c[i]) < 5e-13 ? 0.0 : c[i];
  for (int i = 0; i < 4; ++i)
    if (c[i] != 0) {
      if (c[i] < 0) c = -c;
      break;
    }
  q = Eigen::Quaterniond(c[0], c[1], c[2], c[3]);
  Eigen::Vector3d t = p.camera_to_world.translation() / pose_unit_mm;
  for (int i = 0; i < 3; ++i) t[i] = std::abs(t[i]) < 5e-10 ? 0.0 : t[i];
  return fmt::format("{:.6f} {:.9f} {:.9f} {:.9f} {:.12f} {:.12f} {:.12f} {:.12f}\n", p.timestamp, t.x(), t.y(), t.z(),
                     q.x(), q.y(), q.z(), q.w());
}

void write_stream_yaml(const fs::path& file, const StreamInfo& info) {
  cv::FileStorage fsw(file.string(), cv::FileStorage::WRITE | cv::FileStorage::FORMAT_YAML);
  if (!fsw.isOpened()) throw IoError(fmt::format("{}: cannot write", file.string()));
  fsw << "format" << kFormat << "sensor" << to_string(info.sensor) << "device" << info.device;
  fsw << "width" << info.width << "height" << info.height << "depth_unit_mm" << info.depth_unit_mm;
  cv::Mat K(3, 3, CV_64F), D(1, 5, CV_64F);
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) K.at<double>(r, c) = info.camera_matrix(r, c);
  for (int i = 0; i < 5; ++i) D.at<double>(i) = info.dist_coeffs[i];
  fsw << "camera_matrix" << K << "dist_coeffs" << D << "pose_unit_mm" << info.pose_unit_mm;
  if (info.sensor == Sensor::laser) fsw << "profile_step_mm" << info.profile_step_mm;
  fsw.release();
}

Deprojector::Deprojector(const StreamInfo& info) : info_(info) {
  const auto& K = info.camera_matrix;
  const double fx = K(0, 0), fy = K(1, 1), cx = K(0, 2), cy = K(1, 2);
  const auto& k = info.dist_coeffs;
  const bool distorted = !k.isZero();
  rays_.resize(static_cast<std::size_t>(info.width) * info.height);
  for (int v = 0; v < info.height; ++v)
    for (int u = 0; u < info.width; ++u) {
      Eigen::Vector2d r;
      if (info.sensor == Sensor::laser) {
        // One profile per row: a fan in the sensor's x-z plane, the sensor advanced along +y.
        r = Eigen::Vector2d((u - cx) / fx, v * info.profile_step_mm);
      } else {
        double x = (u - cx) / fx, y = (v - cy) / fy;
        if (distorted) {
          // Invert Brown-Conrady distortion by fixed-point iteration, as cv::undistortPoints does.
          const double x0 = x, y0 = y;
          for (int it = 0; it < 10; ++it) {
            const double r2 = x * x + y * y;
            const double radial = 1 + k[0] * r2 + k[1] * r2 * r2 + k[4] * r2 * r2 * r2;
            const double dx = 2 * k[2] * x * y + k[3] * (r2 + 2 * x * x);
            const double dy = k[2] * (r2 + 2 * y * y) + 2 * k[3] * x * y;
            x = (x0 - dx) / radial;
            y = (y0 - dy) / radial;
          }
        }
        r = Eigen::Vector2d(x, y);
      }
      rays_[static_cast<std::size_t>(v) * info.width + u] = r;
    }
}

std::vector<Eigen::Vector3d> Deprojector::sensor_points(const DepthImage& depth, std::vector<Eigen::Vector3d>* to_sensor,
                                                        std::vector<int>* pixels) const {
  const std::size_t n = std::min(depth.data.size(), rays_.size());
  // Reserved exactly: grown by doubling, a frame's three arrays held up to twice their size, and
  // every frame of a scan is held until the fusion.
  const auto valid = static_cast<std::size_t>(
      std::count_if(depth.data.begin(), depth.data.begin() + static_cast<std::ptrdiff_t>(n), [](std::uint16_t d) { return d != 0; }));
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(valid);
  if (to_sensor) to_sensor->clear(), to_sensor->reserve(valid);
  if (pixels) pixels->clear(), pixels->reserve(valid);
  const bool laser = info_.sensor == Sensor::laser;
  for (std::size_t i = 0; i < n; ++i) {
    const std::uint16_t raw = depth.data[i];
    if (!raw) continue;
    const double z = raw * info_.depth_unit_mm;
    const Eigen::Vector2d& r = rays_[i];
    const Eigen::Vector3d p = laser ? Eigen::Vector3d(r.x() * z, r.y(), z) : Eigen::Vector3d(r.x() * z, r.y() * z, z);
    pts.push_back(p);
    if (pixels) pixels->push_back(static_cast<int>(i));
    if (to_sensor) {
      const Eigen::Vector3d origin = laser ? Eigen::Vector3d(0, r.y(), 0) : Eigen::Vector3d::Zero();
      to_sensor->push_back((origin - p).normalized());
    }
  }
  return pts;
}

std::vector<Eigen::Vector3d> deproject(const Stream& s, std::size_t i, const DepthImage& depth,
                                       std::vector<Eigen::Vector3d>* view_dirs) {
  const Eigen::Isometry3d T = s.pose_of(i).value_or(Eigen::Isometry3d::Identity());
  std::vector<Eigen::Vector3d> pts = Deprojector(s.info).sensor_points(depth, view_dirs);
  for (auto& p : pts) p = T * p;
  if (view_dirs)
    for (auto& d : *view_dirs) d = T.linear() * d;
  return pts;
}

// ---------------------------------------------------------------------------------------------

StreamWriter::StreamWriter(fs::path dir, StreamInfo info) : dir_(std::move(dir)), info_(std::move(info)) {
  if (fs::exists(dir_) && !fs::is_directory(dir_)) throw InvalidInput(fmt::format("{}: exists and is not a directory", dir_.string()));
  if (fs::is_directory(dir_) && !fs::is_empty(dir_) && !fs::exists(dir_ / "stream.yaml"))
    throw InvalidInput(fmt::format("{}: exists, is not empty and is not a stream; choose another --out", dir_.string()));
  const fs::path parent = dir_.parent_path().empty() ? fs::path(".") : dir_.parent_path();
  fs::create_directories(parent);
  temp_ = parent / fmt::format(".{}.tmp-{}", dir_.filename().string(), ::getpid());
  fs::remove_all(temp_);
  fs::create_directories(temp_ / "depth");
}

StreamWriter::~StreamWriter() {
  if (!finished_) {
    std::error_code ec;
    fs::remove_all(temp_, ec);
  }
}

void StreamWriter::add_frame(double timestamp, const DepthImage& depth, const std::optional<Eigen::Isometry3d>& pose) {
  const std::string name = fmt::format("depth/{:06d}.png", frames_.size());
  write_depth_png(temp_ / name, depth);
  frames_.push_back({timestamp, name, 0});
  if (pose) poses_.push_back({timestamp, *pose});
}

void StreamWriter::finish() {
  write_stream_yaml(temp_ / "stream.yaml", info_);
  std::string index = kIndexHeader;
  for (const auto& f : frames_) index += index_line(f);
  write_file_atomic(temp_ / "depth.txt", index);
  if (!poses_.empty()) {
    std::string poses = kPosesHeader;
    for (const auto& p : poses_) poses += pose_line(p, info_.pose_unit_mm);
    write_file_atomic(temp_ / "poses.txt", poses);
  }
  // Swap the finished folder into place; the old stream (if any) goes only after that succeeded.
  const fs::path old = temp_.string() + ".old";
  std::error_code ec;
  if (fs::exists(dir_)) fs::rename(dir_, old);
  fs::rename(temp_, dir_, ec);
  if (ec) {
    if (fs::exists(old)) fs::rename(old, dir_);
    throw IoError(fmt::format("{}: cannot move the stream into place: {}", dir_.string(), ec.message()));
  }
  fs::remove_all(old, ec);
  finished_ = true;
}

}  // namespace s2c
