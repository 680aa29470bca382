#include "s2c/reconstruct/reconstruct.h"

#include <fcntl.h>
#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cmath>
#include <fstream>

#include <fmt/format.h>
#include <pcl/features/normal_3d_omp.h>
#include <pcl/common/common.h>
#include <pcl/io/pcd_io.h>
#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>
#include <pcl/surface/gp3.h>
#include <pcl/surface/mls.h>
#include <pcl/surface/organized_fast_mesh.h>
#include <pcl/surface/poisson.h>
#include <spdlog/spdlog.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "s2c/core/progress.h"
#include "s2c/core/stream.h"
#include "s2c/repair/repair.h"
#include "s2c/repair/volumetric.h"
#include "cloud_util.h"
#include "kd_search.h"

namespace fs = std::filesystem;

namespace s2c {
namespace {

using Cloud = pcl::PointCloud<pcl::PointNormal>;

double measure_spacing(const Cloud::Ptr& cloud) {
  std::vector<Eigen::Vector3d> pts;
  pts.reserve(cloud->size());
  for (const auto& p : *cloud) pts.emplace_back(p.x, p.y, p.z);
  const double s = median_spacing(pts);
  if (!(s > 0)) throw InvalidInput("the cloud has no two distinct points");
  return s;
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

// Seconds since `t`, and restarts `t`: the report's per-step timings.
double lap(std::chrono::steady_clock::time_point& t) {
  const auto now = std::chrono::steady_clock::now();
  const double s = std::chrono::duration<double>(now - t).count();
  t = now;
  return s;
}

// Loads and registers; fills the spacing, frame count and timings of the report.
std::vector<View> load_and_register(const std::vector<fs::path>& inputs, const ReconstructOptions& o,
                                    ReconstructReport& rep, std::vector<Eigen::Isometry3d>& poses) {
  auto t = std::chrono::steady_clock::now();
  std::vector<View> views = load_views(inputs, o.input);
  rep.frames = static_cast<int>(views.size());
  // The sensor's sampling is the spacing of one view (overlapping views would look finer).
  std::vector<double> spacings;
  for (const auto& v : views)
    if (v.spacing_mm > 0) spacings.push_back(v.spacing_mm);
  if (spacings.empty()) throw InvalidInput("the input has no two distinct points");
  std::nth_element(spacings.begin(), spacings.begin() + spacings.size() / 2, spacings.end());
  rep.spacing_mm = spacings[spacings.size() / 2];
  rep.load_s = lap(t);
  poses = register_views(views, rep.spacing_mm, o.registration, rep.views);
  rep.register_s = lap(t);
  return views;
}

// The scan's noise, mm: the median over (a sample of) the points of the RMS distance of their 16
// nearest neighbours to the point's tangent plane (on a smooth surface sampled finely enough,
// the spread of the measurements along the normal).
double tangent_plane_noise(const OrientedCloud& in) {
  Cloud cloud;
  cloud.reserve(in.points.size());
  for (std::size_t i = 0; i < in.points.size(); ++i) cloud.push_back(point_normal(in.points[i], in.normals[i]));
  const PointIndex<pcl::PointNormal> index(cloud);
  const std::size_t stride = std::max<std::size_t>(1, in.points.size() / 4000);
  std::vector<double> rms((in.points.size() + stride - 1) / stride, 0.0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, rms.size(), 64), [&](const auto& r) {
    pcl::Indices idx;
    std::vector<float> sq;
    for (std::size_t k = r.begin(); k < r.end(); ++k) {
      const std::size_t i = k * stride;
      const int found = index.knn(cloud[i].data, 16, idx, sq);
      double sum = 0;
      for (int j = 0; j < found; ++j) {
        const double d = (in.points[static_cast<std::size_t>(idx[j])] - in.points[i]).dot(in.normals[i]);
        sum += d * d;
      }
      rms[k] = found > 0 ? std::sqrt(sum / found) : 0.0;
    }
  });
  std::nth_element(rms.begin(), rms.begin() + rms.size() / 2, rms.end());
  return rms[rms.size() / 2];
}

/// The triangles' aspect bound of each mesher's decimation (why 4 for Poisson: mesh_cloud).
constexpr double kImlsMaxAspect = 8.0, kPoissonMaxAspect = 4.0;

// The quadric decimation both cloud meshers end with (--simplify): bounded by a tenth of a voxel
// by default, so the surface stays where it was while its faces drop to 40 % (imls) or about half
// (Poisson). `max_aspect` bounds how long and thin its triangles may get.
void simplify(TriangleSoup& soup, const ReconstructOptions& o, double voxel, double max_aspect,
              ReconstructReport& rep) {
  rep.simplify_mm = o.simplify_mm >= 0 ? o.simplify_mm : 0.1 * voxel;
  if (rep.simplify_mm > 0) repair::decimate(soup, rep.simplify_mm, nullptr, max_aspect);
}

// Implicit moving least squares of the oriented cloud on a sparse grid, Marching Cubes
// (repair/volumetric.h): no solve, so it is several times faster than Poisson; the band ends
// where the data does, so no trim is needed.
Mesh mesh_cloud_imls(const OrientedCloud& in, const ReconstructOptions& o, ReconstructReport& rep) {
  if (in.points.size() < 10) throw ProcessingError("too few points with normals to mesh");
  repair::PointContourOptions po;
  po.voxel = rep.voxel_mm > 0 ? rep.voxel_mm : median_spacing(in.points);
  // The support: 2.5 voxels, unless the measurements scatter along the normal by more than 0.45
  // voxel (RGB-D and stereo frames: 0.6 on the PCL Kinect and TUM frames, against 0.24-0.34 on the
  // fixture scans); then 10 noise widths (at most 7.5 voxels, the gather's reach), or the band
  // breaks up into bubbles where the noisy sheet crosses zero several times (the TUM frame:
  // 5,789 boundary loops at 2.5 voxels, 468 at 10 σ; Poisson 177).
  rep.imls_noise_mm = tangent_plane_noise(in);
  if (o.imls_support_mm > 0) po.radius = o.imls_support_mm;
  else if (rep.imls_noise_mm > 0.45 * po.voxel) po.radius = std::min(10.0 * rep.imls_noise_mm, 7.5 * po.voxel);
  else po.radius = 2.5 * po.voxel;
  rep.imls_support_mm = po.radius;
  repair::VolumetricStats st;
  TriangleSoup soup = repair::contour_oriented_points(in.points, in.normals, po, &st);
  spdlog::debug("imls: {} blocks, {} band vertices, field {:.2f} s, extract {:.2f} s", st.blocks, st.band_vertices,
                st.seconds_field, st.seconds_extract);
  if (soup.faces.empty()) throw ProcessingError("the mesher produced no surface");
  rep.faces_before_trim = soup.faces.size();
  // Marching Cubes leaves slivers where its vertices crowd the grid nodes, and a noisy flat
  // face as a mesh of a voxel's triangles. A decimation bounded by a tenth of a voxel keeps the
  // surface where it was (the same accuracy) with 40 % of the faces, and the feature stage finds
  // more on it than on Poisson's meshes (bench/README.md, "imls").
  simplify(soup, o, po.voxel, kImlsMaxAspect, rep);
  Mesh mesh;
  soup_to_mesh(soup, mesh);
  rep.faces = mesh.n_faces();
  rep.vertices = mesh.n_vertices();
  return mesh;
}

}  // namespace

OrientedCloud fuse_input(const std::vector<fs::path>& inputs, const ReconstructOptions& o, ReconstructReport& rep) {
  std::vector<Eigen::Isometry3d> poses;
  std::vector<View> views = load_and_register(inputs, o, rep, poses);
  auto t = std::chrono::steady_clock::now();
  OrientedCloud cloud = fuse_views(std::move(views), poses, o, rep);
  rep.fuse_s = lap(t);
  return cloud;
}

Reconstruction reconstruct(const std::vector<fs::path>& inputs, const ReconstructOptions& o, ReconstructReport& rep) {
  std::vector<Eigen::Isometry3d> poses;
  std::vector<View> views = load_and_register(inputs, o, rep, poses);
  auto t = std::chrono::steady_clock::now();
  // The frames (a third of the memory before meshing) are not needed by the cloud mesher: the
  // fusion releases them as it goes.
  const bool organized = o.method == MeshMethod::organized;
  OrientedCloud cloud = organized ? fuse_views(views, poses, o, rep) : fuse_views(std::move(views), poses, o, rep);
  rep.fuse_s = lap(t);
  // Hand what the frames and the registration held back to the system before the mesher's peak:
  // frames decoded side by side were allocated in the worker threads' malloc arenas, which keep
  // freed memory (20 MB more peak on the bracket scan otherwise).
  malloc_trim(0);
  // The mesh is made in place (an OpenMesh mesh has no move assignment: assigned, it is copied).
  Reconstruction r{{}, organized ? mesh_views_organized(views, poses, o, rep) : mesh_cloud(cloud, o, rep)};
  r.cloud = std::move(cloud);
  rep.mesh_s = lap(t);
  spdlog::debug("load {:.2f} s, register {:.2f} s, fuse {:.2f} s, mesh {:.2f} s", rep.load_s, rep.register_s,
                rep.fuse_s, rep.mesh_s);
  return r;
}

Mesh mesh_views_organized(const std::vector<View>& views, const std::vector<Eigen::Isometry3d>& poses,
                          const ReconstructOptions& o, ReconstructReport& rep) {
  TriangleSoup soup;
  for (std::size_t i = 0; i < views.size(); ++i) {
    const View& v = views[i];
    if ((i < rep.views.size() && rep.views[i].rejected) || v.width == 0) continue;
    auto grid = std::make_shared<pcl::PointCloud<pcl::PointXYZ>>(v.width, v.height,
                                                                  pcl::PointXYZ(NAN, NAN, NAN));
    grid->is_dense = false;
    for (std::size_t k = 0; k < v.points.size(); ++k) {
      const Eigen::Vector3d p = poses[i] * v.points[k];
      (*grid)[v.pixel[k]] = pcl::PointXYZ(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
    }
    pcl::OrganizedFastMesh<pcl::PointXYZ> ofm;
    ofm.setInputCloud(grid);
    ofm.setTriangulationType(pcl::OrganizedFastMesh<pcl::PointXYZ>::TRIANGLE_ADAPTIVE_CUT);
    // Neighbouring pixels farther apart than a few spacings are a depth jump, not surface.
    ofm.setMaxEdgeLength(static_cast<float>(4.0 * rep.spacing_mm), 0.0f, 0.0f);
    ofm.storeShadowedFaces(false);
    std::vector<pcl::Vertices> polys;
    ofm.reconstruct(polys);
    const int base = static_cast<int>(soup.vertices.size());
    std::vector<int> index(grid->size(), -1);
    for (const auto& poly : polys) {
      if (poly.vertices.size() != 3) continue;
      std::array<int, 3> f{};
      for (int k = 0; k < 3; ++k) {
        const auto pv = poly.vertices[k];
        if (index[pv] < 0) {
          index[pv] = static_cast<int>(soup.vertices.size()) - base;
          const auto& q = (*grid)[pv];
          soup.vertices.emplace_back(q.x, q.y, q.z);
        }
        f[k] = base + index[pv];
      }
      soup.faces.push_back(f);
    }
  }
  if (soup.faces.empty()) throw ProcessingError("no organized views to mesh (organized meshing needs depth frames)");
  Mesh mesh;
  soup_to_mesh(soup, mesh);
  rep.faces = mesh.n_faces();
  rep.vertices = mesh.n_vertices();
  (void)o;
  return mesh;
}

namespace {

/// The registered views' points in one cloud, the direction to the sensor in the normal fields.
/// With `consumed` (the views themselves), each view's arrays are released once copied: the
/// frames and their copy were both held at the stage's peak.
Cloud::Ptr gather_views(const std::vector<View>& views, std::vector<View>* consumed,
                        const std::vector<Eigen::Isometry3d>& poses, const ReconstructReport& rep) {
  auto raw = std::make_shared<Cloud>();
  // Reserved: grown by doubling, the copy of 0.6 M points was the plate's heap peak (50 of 135 MB).
  std::size_t total = 0;
  for (const View& v : views) total += v.points.size();
  raw->reserve(total);
  for (std::size_t i = 0; i < views.size(); ++i) {
    if (i < rep.views.size() && rep.views[i].rejected) continue;
    const View& v = views[i];
    const Eigen::Isometry3d& T = poses[i];
    for (std::size_t k = 0; k < v.points.size(); ++k) {
      const Eigen::Vector3d p = T * v.points[k];
      // The direction to the sensor rides in the normal fields until normals are estimated.
      const Eigen::Vector3d d = v.to_sensor.empty() ? Eigen::Vector3d::Zero() : Eigen::Vector3d(T.linear() * v.to_sensor[k]);
      raw->push_back(point_normal(p, d));
    }
    if (consumed) (*consumed)[i] = View{};
  }
  return raw;
}

OrientedCloud fuse(const std::vector<View>& views, std::vector<View>* consumed,
                   const std::vector<Eigen::Isometry3d>& poses, const ReconstructOptions& o, ReconstructReport& rep) {
  Cloud::Ptr raw = gather_views(views, consumed, poses, rep);
  rep.points_in = raw->size();
  if (raw->size() < 10) throw InvalidInput(fmt::format("only {} valid points; nothing to reconstruct", raw->size()));
  if (rep.spacing_mm <= 0) rep.spacing_mm = measure_spacing(raw);
  // The imls mesher's grid is the fusion voxel: at 1.5 spacings a voxel averages 2-3 samples per
  // view, which halves the faces and lowers the noise (bench/README.md, "imls").
  rep.voxel_mm = o.voxel_mm > 0 ? o.voxel_mm : (o.method == MeshMethod::imls ? 1.5 : 1.0) * rep.spacing_mm;

  Cloud::Ptr fused = std::make_shared<Cloud>(voxel_downsample(*raw, rep.voxel_mm));
  raw.reset();  // the fused cloud is a fraction of it
  if (o.outlier_sigma > 0 && fused->size() > 50) {
    Cloud::Ptr kept = std::make_shared<Cloud>(remove_statistical_outliers(*fused, 16, o.outlier_sigma));
    rep.outliers_removed = fused->size() - kept->size();
    fused = kept;
  }
  rep.mls_radius_mm = o.mls_radius_mm < 0 ? 3.0 * rep.spacing_mm : o.mls_radius_mm;
  if (rep.mls_radius_mm > 0) {
    // Moving least squares smooths the positions; the sensor directions are carried over from
    // each smoothed point's nearest original point (MLS overwrites the normal fields).
    pcl::MovingLeastSquares<pcl::PointNormal, pcl::PointNormal> mls;
    auto tree = std::make_shared<NanoSearch<pcl::PointNormal>>();
    mls.setInputCloud(fused);
    mls.setSearchMethod(tree);
    mls.setSearchRadius(rep.mls_radius_mm);
    mls.setPolynomialOrder(2);
    mls.setComputeNormals(false);
    mls.setNumberOfThreads(2);
    Cloud::Ptr smooth = std::make_shared<Cloud>();
    mls.process(*smooth);
    const PointIndex<pcl::PointNormal> near(*fused);
    pcl::Indices idx;
    std::vector<float> sq;
    for (auto& q : *smooth)
      if (near.knn(q.data, 1, idx, sq) == 1) {
        q.normal_x = (*fused)[idx[0]].normal_x;
        q.normal_y = (*fused)[idx[0]].normal_y;
        q.normal_z = (*fused)[idx[0]].normal_z;
      }
    if (smooth->size() > 10) fused = smooth;
  }
  rep.points_fused = fused->size();

  pcl::NormalEstimationOMP<pcl::PointNormal, pcl::Normal> ne(2);
  auto tree = std::make_shared<NanoSearch<pcl::PointNormal>>();
  ne.setInputCloud(fused);
  ne.setSearchMethod(tree);
  ne.setKSearch(o.normal_neighbours);
  pcl::PointCloud<pcl::Normal> normals;
  ne.compute(normals);

  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : *fused) centroid += Eigen::Vector3d(p.x, p.y, p.z);
  centroid /= static_cast<double>(fused->size());
  OrientedCloud out;
  out.points.reserve(fused->size());
  out.normals.reserve(fused->size());
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

}  // namespace

OrientedCloud fuse_views(const std::vector<View>& views, const std::vector<Eigen::Isometry3d>& poses,
                         const ReconstructOptions& o, ReconstructReport& rep) {
  return fuse(views, nullptr, poses, o, rep);
}

OrientedCloud fuse_views(std::vector<View>&& views, const std::vector<Eigen::Isometry3d>& poses,
                         const ReconstructOptions& o, ReconstructReport& rep) {
  OrientedCloud out = fuse(views, &views, poses, o, rep);
  std::vector<View>().swap(views);
  return out;
}

Mesh mesh_cloud(const OrientedCloud& in, const ReconstructOptions& o, ReconstructReport& rep) {
  if (o.method == MeshMethod::imls) return mesh_cloud_imls(in, o, rep);
  auto cloud = std::make_shared<Cloud>();
  for (std::size_t i = 0; i < in.points.size(); ++i) cloud->push_back(point_normal(in.points[i], in.normals[i]));
  if (cloud->size() < 10) throw ProcessingError("too few points with normals to mesh");
  Eigen::Vector4f lo, hi;
  pcl::getMinMax3D(*cloud, lo, hi);
  const double diag = (hi - lo).head<3>().norm();
  const double spacing = rep.voxel_mm > 0 ? rep.voxel_mm : measure_spacing(cloud);
  pcl::PolygonMesh pm;
  if (o.method == MeshMethod::poisson) {
    // Octree cells about the point spacing, within the range PCL's Poisson handles well.
    rep.poisson_depth = o.poisson_depth > 0 ? o.poisson_depth
                                            : std::clamp(static_cast<int>(std::ceil(std::log2(diag / (2.0 * spacing)))), 6, 9);
    pcl::Poisson<pcl::PointNormal> poisson;
    poisson.setDepth(rep.poisson_depth);
    poisson.setInputCloud(cloud);
    poisson.setSamplesPerNode(kPoissonSamplesPerNode);
    // One thread: PCL's Poisson sums in a thread-dependent order, so two threads give a different
    // mesh on every run (a re-run after a crash must reproduce its outputs), though they would
    // save 1.5-2 s on the plate scan.
    poisson.setThreads(1);
    // Solve and extract in blocks of the depth-6 octree instead of one system over the finest
    // depth: the depth-8 Laplacian alone was 283 MB of the plate scan's 507 MB heap peak; in
    // blocks the peak is 245 MB with the same accuracy (mean distance to the part 0.0108 mm),
    // for 1.2 s more (mesh step 5.1 -> 6.3 s).
    rep.poisson_block_depth = poisson_block_depth(rep.poisson_depth);
    poisson.setSolverDivide(rep.poisson_block_depth);
    poisson.setIsoDivide(rep.poisson_block_depth);
    QuietStdio quiet(spdlog::get_level() > spdlog::level::debug);
    poisson.reconstruct(pm);
  } else {
    auto tree = std::make_shared<NanoSearch<pcl::PointNormal>>();
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
  const PointIndex<pcl::PointNormal> tree(*cloud);
  std::vector<char> keep(verts.size(), 0);
  // Compared as a float distance against the trim, as always, so vertices on the border stay put.
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, verts.size(), 4096), [&](const auto& r) {
    for (std::size_t i = r.begin(); i < r.end(); ++i) keep[i] = std::sqrt(tree.nearest_sq(verts[i].data)) <= rep.trim_mm;
  });
  TriangleSoup soup;
  std::vector<int> remap(verts.size(), -1);
  for (const auto& poly : pm.polygons) {
    if (poly.vertices.size() != 3) continue;
    bool ok = true;
    for (auto v : poly.vertices) ok = ok && static_cast<std::size_t>(v) < verts.size() && keep[v];
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
  // Poisson's mesh is uniformly fine: at the default depth a flat face is as many triangles as a
  // fillet. Decimated within a tenth of a voxel, the surface is where it was (the same distances
  // to the true part on the fixture scans) with about half the faces, and the stages after it
  // are faster and find more: on the pocket scan repair and features take half the time, and
  // the feature stage finds the counterbore (13 of 14 primitives; the 14th, the counterbore's
  // floor, no view saw). Triangles at most 4 times longer than high (imls: 8): with 8 the plate
  // scan's widened corner holes folded a long bottom triangle at their rim in the edit stage's
  // first solve, which then freed every patch of the part. bench/README.md, "Poisson decimated".
  if (o.method == MeshMethod::poisson) simplify(soup, o, spacing, kPoissonMaxAspect, rep);
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
