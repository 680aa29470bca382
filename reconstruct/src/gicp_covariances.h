#pragma once
// Generalized ICP's point covariances, computed as PCL computes them but on every core.
#include <pcl/point_types.h>
#include <pcl/registration/gicp.h>

#include "kd_search.h"

namespace s2c {

using Gicp = pcl::GeneralizedIterativeClosestPoint<pcl::PointNormal, pcl::PointNormal>;
/// Neighbours per GICP covariance (PCL's "correspondence randomness").
constexpr int kCovarianceNeighbours = 10;

/// GICP's point covariances of `cloud`, as pcl::GeneralizedIterativeClosestPoint computes them
/// for k = kCovarianceNeighbours (same neighbours, same sums in the same order, the same SVD: the
/// same matrices bit for bit), but on both cores: PCL's serial loop was 60 % of the registration
/// step. Null when a point has fewer than k finite neighbours (a cloud of fewer than k points,
/// a non-finite point): GICP cannot run on it.
Gicp::MatricesVectorPtr gicp_covariances(const pcl::PointCloud<pcl::PointNormal>& cloud);
/// The same with `index`, an index of `cloud` already built (GICP's target tree): one build less.
Gicp::MatricesVectorPtr gicp_covariances(const pcl::PointCloud<pcl::PointNormal>& cloud,
                                         const PointIndex<pcl::PointNormal>& index);

}  // namespace s2c
