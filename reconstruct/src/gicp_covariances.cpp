#include "gicp_covariances.h"

#include <atomic>

#include <Eigen/SVD>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "kd_search.h"

namespace s2c {
namespace {

/// PCL's GICP epsilon: the covariance's smallest singular value (the surface's normal direction).
constexpr double kGicpEpsilon = 0.001;

}  // namespace

Gicp::MatricesVectorPtr gicp_covariances(const pcl::PointCloud<pcl::PointNormal>& cloud) {
  if (cloud.size() < static_cast<std::size_t>(kCovarianceNeighbours)) return nullptr;
  return gicp_covariances(cloud, PointIndex<pcl::PointNormal>(cloud));
}

Gicp::MatricesVectorPtr gicp_covariances(const pcl::PointCloud<pcl::PointNormal>& cloud,
                                         const PointIndex<pcl::PointNormal>& index) {
  if (cloud.size() < static_cast<std::size_t>(kCovarianceNeighbours)) return nullptr;
  auto out = std::make_shared<Gicp::MatricesVector>(cloud.size());
  std::atomic<bool> short_answer{false};  // a non-finite point, or fewer than k finite ones
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, cloud.size(), 512), [&](const auto& range) {
    pcl::Indices nn;
    std::vector<float> sq;
    for (std::size_t i = range.begin(); i < range.end(); ++i) {
      Eigen::Matrix3d& cov = (*out)[i];
      cov.setZero();
      Eigen::Vector3d mean = Eigen::Vector3d::Zero();
      if (index.knn(cloud[i].data, kCovarianceNeighbours, nn, sq) < kCovarianceNeighbours) {
        short_answer = true;
        continue;
      }
      for (int j = 0; j < kCovarianceNeighbours; ++j) {
        const pcl::PointNormal& q = cloud[static_cast<std::size_t>(nn[j])];
        mean[0] += q.x;
        mean[1] += q.y;
        mean[2] += q.z;
        // Float products, summed in double: as PCL does.
        cov(0, 0) += q.x * q.x;
        cov(1, 0) += q.y * q.x;
        cov(1, 1) += q.y * q.y;
        cov(2, 0) += q.z * q.x;
        cov(2, 1) += q.z * q.y;
        cov(2, 2) += q.z * q.z;
      }
      mean /= static_cast<double>(kCovarianceNeighbours);
      for (int k = 0; k < 3; ++k)
        for (int l = 0; l <= k; ++l) {
          cov(k, l) /= static_cast<double>(kCovarianceNeighbours);
          cov(k, l) -= mean[k] * mean[l];
          cov(l, k) = cov(k, l);
        }
      // The two larger singular values become 1 and the smallest epsilon: a plane's covariance.
      const Eigen::JacobiSVD<Eigen::Matrix3d> svd(cov, Eigen::ComputeFullU);
      const Eigen::Matrix3d U = svd.matrixU();
      cov.setZero();
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d col = U.col(k);
        cov += (k == 2 ? kGicpEpsilon : 1.0) * col * col.transpose();
      }
    }
  });
  return short_answer ? nullptr : out;
}

}  // namespace s2c
