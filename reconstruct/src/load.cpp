// Reading every kind of reconstruct input into views (sensor-frame points + recorded pose).
#include <algorithm>
#include <cmath>
#include <exception>
#include <regex>
#include <sstream>

#include <fmt/format.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>
#include <tbb/parallel_for.h>

#include "s2c/core/errors.h"
#include "s2c/core/io.h"
#include "s2c/core/progress.h"
#include "s2c/core/stream.h"
#include "s2c/reconstruct/views.h"
#include "cloud_util.h"

namespace fs = std::filesystem;

namespace s2c {
namespace {

std::vector<View> views_of_stream(const Stream& s) {
  const Deprojector deproject(s.info);
  std::vector<View> views(s.frames.size());
  Progress progress("frames", s.frames.size());
  // Frames are decoded side by side; a bad frame's error is kept and the first bad frame's is
  // thrown, as a sequential read would.
  std::vector<std::exception_ptr> failed(s.frames.size());
  tbb::parallel_for(std::size_t{0}, s.frames.size(), [&](std::size_t i) {
    try {
      View& v = views[i];
      v.name = (s.dir / s.frames[i].file).string();
      v.points = deproject.sensor_points(read_frame(s, i), &v.to_sensor, &v.pixel);
      v.width = s.info.width;
      v.height = s.info.height;
      if (!s.poses.empty()) {
        v.pose = s.pose_of(i);
        if (!v.pose)
          throw InvalidInput(fmt::format("{}: frame {} ({}) has no pose within 20 ms in poses.txt", s.dir.string(), i,
                                         s.frames[i].file));
      }
      v.spacing_mm = median_spacing(v.points);
      progress.advance();
    } catch (...) {
      failed[i] = std::current_exception();
    }
  });
  for (const auto& e : failed)
    if (e) std::rethrow_exception(e);
  return views;
}

StreamInfo info_for_folder(const fs::path& dir, const InputOptions& o, int width, int height) {
  StreamInfo info;
  info.device = "folder:" + dir.string();
  info.width = width;
  info.height = height;
  info.depth_unit_mm = o.depth_unit_mm > 0 ? o.depth_unit_mm : 0.2;
  info.camera_matrix << (*o.intrinsics)[0], 0, (*o.intrinsics)[2], 0, (*o.intrinsics)[1], (*o.intrinsics)[3], 0, 0, 1;
  return info;
}

// A TUM RGB-D folder (depth.txt, depth/*.png, optional groundtruth.txt in metres) or a folder
// of depth images (sorted by name), read through the stream machinery.
std::vector<View> views_of_folder(const fs::path& dir, const InputOptions& o) {
  Stream s;
  s.dir = dir;
  if (fs::exists(dir / "depth.txt")) {
    // Reuse the stream reader's index parsing by giving it the folder's own files.
    std::vector<StreamFrame> frames;
    std::ifstream in(dir / "depth.txt");
    std::string line;
    int no = 0;
    while (std::getline(in, line)) {
      ++no;
      if (line.empty() || line[0] == '#') continue;
      std::istringstream ls(line);
      StreamFrame f;
      f.line = no;
      if (!(ls >> f.timestamp >> f.file))
        throw InvalidInput(fmt::format("{}: line {}: expected 'timestamp filename'", (dir / "depth.txt").string(), no));
      frames.push_back(f);
    }
    s.frames = frames;
    if (fs::exists(dir / "groundtruth.txt")) {
      std::ifstream gt(dir / "groundtruth.txt");
      no = 0;
      while (std::getline(gt, line)) {
        ++no;
        if (line.empty() || line[0] == '#') continue;
        std::istringstream ls(line);
        double v[8];
        for (double& x : v)
          if (!(ls >> x) || !std::isfinite(x))
            throw InvalidInput(fmt::format("{}: line {}: expected 'timestamp tx ty tz qx qy qz qw'",
                                           (dir / "groundtruth.txt").string(), no));
        const Eigen::Quaterniond q(v[7], v[4], v[5], v[6]);
        if (std::abs(q.norm() - 1) > 1e-3)
          throw InvalidInput(fmt::format("{}: line {}: quaternion norm {:.4f}", (dir / "groundtruth.txt").string(), no, q.norm()));
        StreamPose p;
        p.timestamp = v[0];
        p.camera_to_world.linear() = q.normalized().toRotationMatrix();
        p.camera_to_world.translation() = Eigen::Vector3d(v[1], v[2], v[3]) * 1000.0;  // TUM: metres
        s.poses.push_back(p);
      }
    }
  } else {
    std::vector<fs::path> files;
    for (const auto& e : fs::directory_iterator(dir)) {
      const std::string name = e.path().filename().string();
      const std::string ext = e.path().extension().string();
      if (name.find("depth") != std::string::npos && (ext == ".png" || ext == ".tiff" || ext == ".tif"))
        files.push_back(e.path());
    }
    if (files.empty())
      throw InvalidInput(fmt::format("{}: no stream.yaml, no depth.txt and no *depth*.png/.tiff images", dir.string()));
    std::sort(files.begin(), files.end());
    for (std::size_t i = 0; i < files.size(); ++i) s.frames.push_back({static_cast<double>(i), files[i].filename().string(), 0});
  }
  if (s.frames.empty()) throw InvalidInput(fmt::format("{}: lists no frames", dir.string()));
  if (!o.intrinsics)
    throw InvalidInput(fmt::format("{}: a folder without stream.yaml needs --intrinsics fx,fy,cx,cy "
                                   "(and --depth-unit-mm; TUM uses 0.2)", dir.string()));
  const DepthImage first = read_depth_png(dir / s.frames[0].file);
  s.info = info_for_folder(dir, o, first.width, first.height);
  return views_of_stream(s);
}

View view_of_cloud(const fs::path& path, const InputOptions& o) {
  if (!fs::exists(path)) throw InvalidInput(fmt::format("{}: no such file", path.string()));
  pcl::PCLPointCloud2 blob;
  const std::string ext = path.extension().string();
  int rc = -1;
  Eigen::Vector4f origin = Eigen::Vector4f::Zero();  // PCD's VIEWPOINT: where the sensor was
  Eigen::Quaternionf orientation = Eigen::Quaternionf::Identity();
  // PCL allocates what a header promises: check it against the file first (exit 2, not an OOM kill).
  if (ext == ".pcd") check_pcd_header(path);
  else if (ext == ".ply") check_mesh_header(path);
  else throw InvalidInput(fmt::format("{}: a cloud must be .ply or .pcd", path.string()));
  try {
    rc = ext == ".pcd" ? pcl::io::loadPCDFile(path.string(), blob, origin, orientation)
                       : pcl::io::loadPLYFile(path.string(), blob);
  } catch (const std::exception& e) {  // PCL's readers throw on some malformed headers (found by fuzzing)
    throw InvalidInput(fmt::format("{}: cannot be read as a point cloud: {}", path.string(), e.what()));
  }
  if (rc < 0) throw InvalidInput(fmt::format("{}: cannot be read as a point cloud", path.string()));
  // fromPCLPointCloud2 takes &cloud[0] of an empty cloud (UBSan: a null reference): refuse first.
  if (std::size_t(blob.width) * blob.height == 0 || blob.data.empty())
    throw InvalidInput(fmt::format("{}: only 0 finite points (the cloud is empty)", path.string()));
  pcl::PointCloud<pcl::PointXYZ> cloud;
  pcl::fromPCLPointCloud2(blob, cloud);
  View v;
  v.name = path.string();
  if (cloud.isOrganized()) {
    v.width = static_cast<int>(cloud.width);
    v.height = static_cast<int>(cloud.height);
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    const auto& p = cloud[i];
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) continue;  // organized holes are NaN
    v.points.emplace_back(p.x * o.input_unit_mm, p.y * o.input_unit_mm, p.z * o.input_unit_mm);
    if (v.width) v.pixel.push_back(static_cast<int>(i));
    if (v.width && ext == ".pcd") {
      // An organized PCD cloud is one view seen from its VIEWPOINT, which orients its normals
      // (otherwise they face away from the centroid, wrong for a table seen from above). A PLY
      // range grid (the Stanford scans) says nothing of where its scanner stood.
      const Eigen::Vector3d sensor = origin.head<3>().cast<double>() * o.input_unit_mm;
      const Eigen::Vector3d d = sensor - v.points.back();
      v.to_sensor.push_back(d.norm() > 0 ? Eigen::Vector3d(d.normalized()) : Eigen::Vector3d::Zero());
    }
  }
  if (v.points.size() < 10)
    throw InvalidInput(fmt::format("{}: only {} finite points", path.string(), v.points.size()));
  v.spacing_mm = median_spacing(v.points);
  return v;
}

}  // namespace

Eigen::Vector4d parse_intrinsics(const std::string& text) {
  std::vector<double> v;
  std::stringstream ss(text);
  std::string tok;
  while (std::getline(ss, tok, ',')) {
    char* end = nullptr;
    const double x = std::strtod(tok.c_str(), &end);
    if (end == tok.c_str() || *end || !std::isfinite(x) || x <= 0)
      throw InvalidInput(fmt::format("--intrinsics '{}': expected four positive numbers fx,fy,cx,cy", text));
    v.push_back(x);
  }
  if (v.size() != 4) throw InvalidInput(fmt::format("--intrinsics '{}': expected fx,fy,cx,cy", text));
  return {v[0], v[1], v[2], v[3]};
}

std::vector<View> load_views(const std::vector<fs::path>& inputs, const InputOptions& o) {
  if (inputs.empty()) throw InvalidInput("no input given");
  std::vector<View> views;
  for (const auto& in : inputs) {
    if (fs::is_directory(in)) {
      if (inputs.size() > 1) throw InvalidInput(fmt::format("{}: give one stream folder, or several cloud files", in.string()));
      return fs::exists(in / "stream.yaml") ? views_of_stream(read_stream(in)) : views_of_folder(in, o);
    }
    views.push_back(view_of_cloud(in, o));
  }
  return views;
}

}  // namespace s2c
