#pragma once
// Small cloud helpers shared by reconstruct's steps: the point spacing every default derives
// from, a voxel grid that works at any extent, and Eigen → PCL point conversion.
#include <vector>

#include <Eigen/Core>

namespace s2c {

/// Median nearest-neighbour distance over (a sample of) the points, mm; 0 for fewer than two.
double median_spacing(const std::vector<Eigen::Vector3d>& points);

}  // namespace s2c

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>

namespace s2c {

/// Voxel-grid downsampling that averages every field of the points in a voxel (like
/// pcl::VoxelGrid), keyed by a 64-bit hash so any extent works: PCL's grid silently returns
/// its input when extent / leaf overflows 32-bit indices (room-sized scans at fine voxels).
pcl::PointCloud<pcl::PointNormal> voxel_downsample(const pcl::PointCloud<pcl::PointNormal>& in, double voxel);

/// PCL's StatisticalOutlierRemoval, same answers: drops the points whose mean distance to their
/// `mean_k` nearest neighbours exceeds the mean of that over all points by `sigma` standard
/// deviations. Its own, because PCL's filter cannot be given a search (kd_search.h) and queries
/// one point at a time; here the queries run in parallel.
pcl::PointCloud<pcl::PointNormal> remove_statistical_outliers(const pcl::PointCloud<pcl::PointNormal>& in, int mean_k,
                                                              double sigma);

/// A PCL point from a position and a direction (a normal, or the way to the sensor).
inline pcl::PointNormal point_normal(const Eigen::Vector3d& p, const Eigen::Vector3d& n) {
  pcl::PointNormal q;
  q.x = static_cast<float>(p.x());
  q.y = static_cast<float>(p.y());
  q.z = static_cast<float>(p.z());
  q.normal_x = static_cast<float>(n.x());
  q.normal_y = static_cast<float>(n.y());
  q.normal_z = static_cast<float>(n.z());
  q.curvature = 0;
  return q;
}

}  // namespace s2c
