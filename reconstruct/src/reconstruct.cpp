#include "s2c/reconstruct/reconstruct.h"

#include <fcntl.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cmath>
#include <fstream>

#include <fmt/format.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/common/common.h>
#include <pcl/filters/voxel_grid.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/kdtree/kdtree_flann.h>
#include <pcl/point_types.h>
#include <pcl/surface/gp3.h>
#include <pcl/surface/poisson.h>
#include <spdlog/spdlog.h>

#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "s2c/core/progress.h"
#include "s2c/core/stream.h"

namespace fs = std::filesystem;

namespace s2c {
namespace {

using Cloud = pcl::PointCloud<pcl::PointNormal>;

// Median nearest-neighbour distance over a sample of points: the scan's point spacing.
double measure_spacing(const Cloud::Ptr& cloud) {
  pcl::KdTreeFLANN<pcl::PointNormal> tree;
  tree.setInputCloud(cloud);
  std::vector<double> d;
  std::vector<int> idx(2);
  std::vector<float> sq(2);
  const std::size_t step = std::max<std::size_t>(1, cloud->size() / 5000);
  for (std::size_t i = 0; i < cloud->size(); i += step)
    if (tree.nearestKSearch((*cloud)[i], 2, idx, sq) == 2 && sq[1] > 0) d.push_back(std::sqrt(sq[1]));
  if (d.empty()) throw InvalidInput("the cloud has no two distinct points");
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

// Silences a noisy third-party call (PCL's Poisson prints to stdout/stderr) unless verbose.
class QuietStdio {
 public:
  explicit QuietStdio(bool active) {
    if (!active) return;
    std::fflush(stdout);
    std::fflush(stderr);
    saved_out_ = ::dup(STDOUT_FILENO);
    saved_err_ = ::dup(STDERR_FILENO);
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, STDOUT_FILENO);
    ::dup2(null, STDERR_FILENO);
    ::close(null);
  }
  ~QuietStdio() {
    if (saved_out_ < 0) return;
    std::fflush(stdout);
    std::fflush(stderr);
    ::dup2(saved_out_, STDOUT_FILENO);
    ::dup2(saved_err_, STDERR_FILENO);
    ::close(saved_out_);
    ::close(saved_err_);
  }
  QuietStdio(const QuietStdio&) = delete;
  QuietStdio& operator=(const QuietStdio&) = delete;

 private:
  int saved_out_ = -1, saved_err_ = -1;
};

Cloud::Ptr load_stream(const fs::path& dir, ReconstructReport& rep) {
  const Stream s = read_stream(dir);
  if (s.poses.empty())
    throw InvalidInput(fmt::format("{}: no poses.txt; registration without poses is not available yet", dir.string()));
  auto cloud = std::make_shared<Cloud>();
  Progress progress("frames", s.frames.size());
  for (std::size_t i = 0; i < s.frames.size(); ++i) {
    if (!s.pose_of(i))
      throw InvalidInput(fmt::format("{}: frame {} ({}) has no pose within 20 ms in poses.txt", dir.string(), i,
                                     s.frames[i].file));
    std::vector<Eigen::Vector3d> view;
    const auto pts = deproject(s, i, read_frame(s, i), &view);
    for (std::size_t k = 0; k < pts.size(); ++k) {
      pcl::PointNormal p;
      p.x = static_cast<float>(pts[k].x());
      p.y = static_cast<float>(pts[k].y());
      p.z = static_cast<float>(pts[k].z());
      // The view direction rides in the normal fields until normals are estimated.
      p.normal_x = static_cast<float>(view[k].x());
      p.normal_y = static_cast<float>(view[k].y());
      p.normal_z = static_cast<float>(view[k].z());
      cloud->push_back(p);
    }
    progress.advance();
    // The spacing of one view is the sensor's sampling; overlapping views would make it look finer.
    if (i == 0 && cloud->size() > 10) rep.spacing_mm = measure_spacing(cloud);
  }
  rep.frames = static_cast<int>(s.frames.size());
  return cloud;
}

Cloud::Ptr load_cloud_file(const fs::path& path) {
  if (!fs::exists(path)) throw InvalidInput(fmt::format("{}: no such file", path.string()));
  auto cloud = std::make_shared<Cloud>();
  pcl::PCLPointCloud2 blob;
  const std::string ext = path.extension().string();
  int rc = -1;
  if (ext == ".pcd") rc = pcl::io::loadPCDFile(path.string(), blob);
  else if (ext == ".ply") rc = pcl::io::loadPLYFile(path.string(), blob);
  else throw InvalidInput(fmt::format("{}: a cloud must be .ply or .pcd", path.string()));
  if (rc < 0) throw InvalidInput(fmt::format("{}: cannot be read as a point cloud", path.string()));
  pcl::fromPCLPointCloud2(blob, *cloud);
  // Drop NaN points (organized clouds mark missing pixels that way).
  Cloud::Ptr finite = std::make_shared<Cloud>();
  for (const auto& p : *cloud)
    if (std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z)) {
      pcl::PointNormal q = p;
      // Without a sensor position, orient normals away from the centroid (fixed below).
      q.normal_x = q.normal_y = q.normal_z = 0;
      finite->push_back(q);
    }
  return finite;
}

}  // namespace

OrientedCloud fuse_input(const fs::path& input, const ReconstructOptions& o, ReconstructReport& rep) {
  Cloud::Ptr raw = fs::is_directory(input) ? load_stream(input, rep) : load_cloud_file(input);
  rep.points_in = raw->size();
  if (raw->size() < 10) throw InvalidInput(fmt::format("{}: only {} valid points; nothing to reconstruct", input.string(), raw->size()));
  if (rep.spacing_mm <= 0) rep.spacing_mm = measure_spacing(raw);
  rep.voxel_mm = o.voxel_mm > 0 ? o.voxel_mm : rep.spacing_mm;

  Cloud::Ptr fused = std::make_shared<Cloud>();
  pcl::VoxelGrid<pcl::PointNormal> grid;
  grid.setInputCloud(raw);
  grid.setLeafSize(static_cast<float>(rep.voxel_mm), static_cast<float>(rep.voxel_mm), static_cast<float>(rep.voxel_mm));
  grid.filter(*fused);
  if (o.remove_outliers && fused->size() > 50) {
    Cloud::Ptr kept = std::make_shared<Cloud>();
    pcl::StatisticalOutlierRemoval<pcl::PointNormal> sor;
    sor.setInputCloud(fused);
    sor.setMeanK(16);
    sor.setStddevMulThresh(2.5);
    sor.filter(*kept);
    rep.outliers_removed = fused->size() - kept->size();
    fused = kept;
  }
  rep.points_fused = fused->size();

  pcl::NormalEstimationOMP<pcl::PointNormal, pcl::Normal> ne(2);
  auto tree = std::make_shared<pcl::search::KdTree<pcl::PointNormal>>();
  ne.setInputCloud(fused);
  ne.setSearchMethod(tree);
  ne.setKSearch(o.normal_neighbours);
  pcl::PointCloud<pcl::Normal> normals;
  ne.compute(normals);

  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : *fused) centroid += Eigen::Vector3d(p.x, p.y, p.z);
  centroid /= static_cast<double>(fused->size());
  OrientedCloud out;
  for (std::size_t i = 0; i < fused->size(); ++i) {
    const auto& p = (*fused)[i];
    Eigen::Vector3d n(normals[i].normal_x, normals[i].normal_y, normals[i].normal_z);
    if (!n.allFinite() || n.norm() < 0.5) continue;
    Eigen::Vector3d view(p.normal_x, p.normal_y, p.normal_z);
    const Eigen::Vector3d pos(p.x, p.y, p.z);
    if (view.norm() < 1e-6) view = pos - centroid;  // no sensor known: outward from the centroid
    if (n.dot(view) < 0) n = -n;
    out.points.push_back(pos);
    out.normals.push_back(n.normalized());
  }
  return out;
}

Mesh mesh_cloud(const OrientedCloud& in, const ReconstructOptions& o, ReconstructReport& rep) {
  auto cloud = std::make_shared<Cloud>();
  for (std::size_t i = 0; i < in.points.size(); ++i) {
    pcl::PointNormal p;
    p.x = static_cast<float>(in.points[i].x());
    p.y = static_cast<float>(in.points[i].y());
    p.z = static_cast<float>(in.points[i].z());
    p.normal_x = static_cast<float>(in.normals[i].x());
    p.normal_y = static_cast<float>(in.normals[i].y());
    p.normal_z = static_cast<float>(in.normals[i].z());
    cloud->push_back(p);
  }
  if (cloud->size() < 10) throw ProcessingError("too few points with normals to mesh");
  Eigen::Vector4f lo, hi;
  pcl::getMinMax3D(*cloud, lo, hi);
  const double diag = (hi - lo).head<3>().norm();
  const double spacing = rep.voxel_mm > 0 ? rep.voxel_mm : measure_spacing(cloud);
  pcl::PolygonMesh pm;
  if (o.method == MeshMethod::poisson) {
    // Octree cells about the point spacing, within the range PCL's Poisson handles well.
    rep.poisson_depth = o.poisson_depth > 0 ? o.poisson_depth
                                            : std::clamp(static_cast<int>(std::ceil(std::log2(diag / (2.0 * spacing)))), 6, 10);
    pcl::Poisson<pcl::PointNormal> poisson;
    poisson.setDepth(rep.poisson_depth);
    poisson.setInputCloud(cloud);
    poisson.setSamplesPerNode(1.5f);
    poisson.setThreads(2);
    QuietStdio quiet(spdlog::get_level() > spdlog::level::debug);
    poisson.reconstruct(pm);
  } else {
    auto tree = std::make_shared<pcl::search::KdTree<pcl::PointNormal>>();
    tree->setInputCloud(cloud);
    pcl::GreedyProjectionTriangulation<pcl::PointNormal> gp3;
    gp3.setSearchRadius(4.0 * spacing);
    gp3.setMu(2.5);
    gp3.setMaximumNearestNeighbors(100);
    gp3.setMaximumSurfaceAngle(M_PI / 4);
    gp3.setMinimumAngle(M_PI / 18);
    gp3.setMaximumAngle(2 * M_PI / 3);
    gp3.setNormalConsistency(true);
    gp3.setInputCloud(cloud);
    gp3.setSearchMethod(tree);
    gp3.reconstruct(pm);
  }
  pcl::PointCloud<pcl::PointXYZ> verts;
  pcl::fromPCLPointCloud2(pm.cloud, verts);
  if (pm.polygons.empty() || verts.empty()) throw ProcessingError("the mesher produced no surface");
  rep.faces_before_trim = pm.polygons.size();

  // Trim: surface far from every input point was invented (unseen regions); leave it open.
  rep.trim_mm = o.trim_mm > 0 ? o.trim_mm : 3.0 * spacing;
  pcl::KdTreeFLANN<pcl::PointNormal> tree;
  tree.setInputCloud(cloud);
  std::vector<char> keep(verts.size(), 0);
  std::vector<int> idx(1);
  std::vector<float> sq(1);
  for (std::size_t i = 0; i < verts.size(); ++i) {
    pcl::PointNormal q;
    q.x = verts[i].x;
    q.y = verts[i].y;
    q.z = verts[i].z;
    keep[i] = tree.nearestKSearch(q, 1, idx, sq) == 1 && std::sqrt(sq[0]) <= rep.trim_mm;
  }
  TriangleSoup soup;
  std::vector<int> remap(verts.size(), -1);
  for (const auto& poly : pm.polygons) {
    if (poly.vertices.size() != 3) continue;
    bool ok = true;
    for (auto v : poly.vertices) ok = ok && v < verts.size() && keep[v];
    if (!ok) continue;
    std::array<int, 3> f{};
    for (int k = 0; k < 3; ++k) {
      const auto v = poly.vertices[k];
      if (remap[v] < 0) {
        remap[v] = static_cast<int>(soup.vertices.size());
        soup.vertices.emplace_back(verts[v].x, verts[v].y, verts[v].z);
      }
      f[k] = remap[v];
    }
    if (f[0] != f[1] && f[1] != f[2] && f[0] != f[2]) soup.faces.push_back(f);
  }
  if (soup.faces.empty()) throw ProcessingError("trimming removed the whole surface; try a larger --trim");
  Mesh mesh;
  soup_to_mesh(soup, mesh);
  rep.faces = mesh.n_faces();
  rep.vertices = mesh.n_vertices();
  return mesh;
}

void write_cloud(const OrientedCloud& c, const fs::path& path) {
  AtomicFile out(path);
  {
    std::ofstream f(out.temp_path(), std::ios::binary);
    f << "ply\nformat binary_little_endian 1.0\ncomment scan2cad fused cloud, mm\nelement vertex " << c.points.size()
      << "\nproperty float x\nproperty float y\nproperty float z\nproperty float nx\nproperty float ny\n"
         "property float nz\nend_header\n";
    for (std::size_t i = 0; i < c.points.size(); ++i) {
      float v[6];
      for (int k = 0; k < 3; ++k) {
        v[k] = static_cast<float>(c.points[i][k]);
        v[3 + k] = static_cast<float>(c.normals[i][k]);
      }
      f.write(reinterpret_cast<const char*>(v), sizeof v);
    }
    f.flush();
    if (!f) throw IoError(fmt::format("{}: write failed", path.string()));
  }
  out.commit();
}

}  // namespace s2c
