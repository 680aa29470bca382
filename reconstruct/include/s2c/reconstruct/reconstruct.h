#pragma once
/// \file From a recorded scan (stream directory) or a point cloud to a fused cloud and a mesh.
/// PCL does the work inside reconstruct/src; this header stays light.
#include <algorithm>
#include <filesystem>
#include <string>
#include <vector>

#include "s2c/core/mesh.h"
#include "s2c/reconstruct/register.h"
#include "s2c/reconstruct/views.h"

namespace s2c {

enum class MeshMethod { poisson, gp3, organized, imls };

/// PCL's Poisson as the stage runs it, beyond the depth (s2c-bench-poisson runs the same):
/// samples per octree node, and the octree depth of the blocks it solves and extracts in
/// (reconstruct.cpp, mesh_cloud: why blocks).
constexpr float kPoissonSamplesPerNode = 1.5f;
inline int poisson_block_depth(int depth) { return std::min(depth, 6); }

struct ReconstructOptions {
  InputOptions input;
  RegistrationOptions registration;
  MeshMethod method = MeshMethod::poisson;
  double voxel_mm = 0;        ///< fusion voxel; 0 = the measured point spacing
  int poisson_depth = 0;      ///< octree depth; 0 = cells of about two point spacings (6..9)
  double trim_mm = 0;         ///< drop surface farther than this from the data; 0 = 3 × spacing
  int normal_neighbours = 24; ///< k for normal estimation
  /// Statistical outlier removal: drop points whose mean distance to 16 neighbours exceeds
  /// mean + sigma·stddev; 0 = off. Lenient by default: surface seen sparsely at grazing angles
  /// looks statistically like outliers (2.5σ cost the pocket fixture 4 % of its coverage).
  double outlier_sigma = 6.0;
  double mls_radius_mm = 0;   ///< moving-least-squares smoothing radius; 0 = off, < 0 = 3 × spacing
  double imls_support_mm = 0; ///< imls: support radius of a point; 0 = 2.5 × voxel, or 10 × the noise if that is above 0.45 voxel
  double simplify_mm = -1;    ///< poisson, imls: decimation tolerance; 0 = off, < 0 = a tenth of the voxel
};

struct ReconstructReport {
  int frames = 0;
  std::vector<ViewAlignment> views;  ///< registration residual per view
  double load_s = 0, register_s = 0, fuse_s = 0, mesh_s = 0;  ///< seconds per step
  std::size_t points_in = 0, points_fused = 0, outliers_removed = 0;
  double spacing_mm = 0, voxel_mm = 0, trim_mm = 0, mls_radius_mm = 0;
  double imls_support_mm = 0;  ///< imls: the support radius used
  double imls_noise_mm = 0;    ///< imls: measured spread of the points along their normals (median RMS)
  double simplify_mm = 0;      ///< poisson, imls: the decimation tolerance used (0: none)
  int poisson_depth = 0;
  int poisson_block_depth = 0;  ///< Poisson solves and extracts in blocks of this octree depth
  std::size_t faces_before_trim = 0, faces = 0, vertices = 0;
};

/// A cloud with normals (oriented towards the sensor) in mm.
struct OrientedCloud {
  std::vector<Eigen::Vector3d> points, normals;
};

/// Reads the inputs (load_views), registers the views (register_views) and fuses them into one
/// cloud with sensor-oriented normals.
/// \throw InvalidInput naming the file or frame; ProcessingError when views do not overlap.
OrientedCloud fuse_input(const std::vector<std::filesystem::path>& inputs, const ReconstructOptions& options,
                         ReconstructReport& report);

struct Reconstruction {
  OrientedCloud cloud;
  Mesh mesh;
};

/// The whole stage: load, register, fuse, mesh (Poisson or GP3 on the fused cloud, or
/// OrganizedFastMesh per view, concatenated, for organized frames).
Reconstruction reconstruct(const std::vector<std::filesystem::path>& inputs, const ReconstructOptions& options,
                           ReconstructReport& report);

/// Meshes each organized view on its pixel grid (OrganizedFastMesh) and concatenates them:
/// exact to the measurements, but overlapping views stay separate sheets (a preview, or for
/// single frames). \throw ProcessingError when no view is organized.
Mesh mesh_views_organized(const std::vector<View>& views, const std::vector<Eigen::Isometry3d>& poses,
                          const ReconstructOptions& options, ReconstructReport& report);

/// Fuses registered views (rejected ones in `alignment` skipped): voxel grid at the spacing,
/// statistical outlier removal, normals oriented towards the sensors.
OrientedCloud fuse_views(const std::vector<View>& views, const std::vector<Eigen::Isometry3d>& poses,
                         const ReconstructOptions& options, ReconstructReport& report);
/// The same, consuming the views: each is released as soon as its points are copied, and `views`
/// is empty afterwards (a scan's frames need not be held beside their fused copy).
OrientedCloud fuse_views(std::vector<View>&& views, const std::vector<Eigen::Isometry3d>& poses,
                         const ReconstructOptions& options, ReconstructReport& report);

/// Meshes a fused cloud; regions without data stay open (holes for repair).
/// \throw ProcessingError when the mesher produces nothing.
Mesh mesh_cloud(const OrientedCloud& cloud, const ReconstructOptions& options, ReconstructReport& report);

/// Writes a cloud with normals as binary PLY, atomically.
void write_cloud(const OrientedCloud& cloud, const std::filesystem::path& path);

}  // namespace s2c
