#pragma once
// Point spacing: the scale every reconstruct default derives from.
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

}  // namespace s2c
