#pragma once
// Nearest-neighbour search for reconstruct's point clouds, on nanoflann.
//
// Why not PCL's own KdTree: Debian's PCL searches through FLANN, and FLANN opens an OpenMP
// parallel region for every single-point query. Ending a region costs a futex syscall even with
// one thread, and PCL queries one point at a time (normal estimation, generalized ICP, the
// outlier filter): 5.6 million syscalls for the plate scan, 40 % of its run time on a VM where
// syscalls are slow. nanoflann answers the same exact queries with no threading of its own, so
// callers parallelise over queries where it pays.
#include <memory>
#include <vector>

#include <pcl/point_cloud.h>
#include <pcl/point_types.h>
#include <pcl/search/kdtree.h>

namespace s2c {

/// Exact k-nearest and radius search over the finite points of a cloud (indices are the cloud's).
/// Thread-safe for concurrent queries once built. Instantiated for PointXYZ and PointNormal.
template <class PointT>
class PointIndex {
 public:
  PointIndex();
  explicit PointIndex(const pcl::PointCloud<PointT>& cloud, const pcl::Indices* subset = nullptr);
  ~PointIndex();
  PointIndex(PointIndex&&) noexcept;
  PointIndex& operator=(PointIndex&&) noexcept;

  /// Up to k nearest points, nearest first; the number found (0 for a non-finite query).
  int knn(const float* query, int k, pcl::Indices& indices, std::vector<float>& sq_dists) const;
  /// Points within `radius`, nearest first, at most max_nn of them when max_nn > 0.
  int radius(const float* query, double radius, pcl::Indices& indices, std::vector<float>& sq_dists,
             unsigned max_nn = 0) const;
  /// Squared distance to the nearest point (infinity for an empty index or a non-finite query).
  float nearest_sq(const float* query) const;
  std::size_t size() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// PointIndex behind PCL's search interface, for PCL's algorithms that take a search method
/// (normal estimation, generalized ICP, FPFH, SampleConsensusPrerejective, MLS, greedy
/// projection): same answers as pcl::search::KdTree (exact, sorted), no OpenMP region per query.
/// (PCL's StatisticalOutlierRemoval takes none: see remove_statistical_outliers.)
template <class PointT>
class NanoSearch : public pcl::search::KdTree<PointT> {
 public:
  using Ptr = std::shared_ptr<NanoSearch>;
  using typename pcl::search::Search<PointT>::PointCloudConstPtr;
  using typename pcl::search::Search<PointT>::IndicesConstPtr;
  using pcl::search::Search<PointT>::nearestKSearch;
  using pcl::search::Search<PointT>::radiusSearch;

  NanoSearch() : pcl::search::KdTree<PointT>(true) {}
  void setInputCloud(const PointCloudConstPtr& cloud, const IndicesConstPtr& indices = IndicesConstPtr()) override;
  int nearestKSearch(const PointT& point, int k, pcl::Indices& k_indices,
                     std::vector<float>& k_sqr_distances) const override;
  int radiusSearch(const PointT& point, double radius, pcl::Indices& k_indices, std::vector<float>& k_sqr_distances,
                   unsigned int max_nn = 0) const override;
  /// The index built by the last setInputCloud, for callers that search the same cloud too.
  const PointIndex<PointT>& index() const { return index_; }

 private:
  PointIndex<PointT> index_;
};

}  // namespace s2c
