#include "kd_search.h"

#include <algorithm>
#include <cmath>
#include <limits>

// Points at exactly equal distance come in the order the tree's traversal meets them, as in
// FLANN, but the two trees are shaped differently: such ties are the only answers that differ
// from PCL's search (3 normals of the pocket scan's 451 k fused points, none on three other
// fixture scans).
#include <nanoflann.hpp>

namespace s2c {
namespace {

/// The finite points, xyz packed, and the cloud index of each.
struct Points {
  std::vector<float> xyz;
  std::vector<pcl::index_t> id;

  std::size_t kdtree_get_point_count() const { return id.size(); }
  float kdtree_get_pt(pcl::index_t i, std::size_t d) const { return xyz[3 * static_cast<std::size_t>(i) + d]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

// Positions in Points are pcl::index_t, so a query writes straight into the caller's indices.
using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<float, Points, float, pcl::index_t>,
                                                 Points, 3, pcl::index_t>;

bool finite3(const float* q) { return std::isfinite(q[0]) && std::isfinite(q[1]) && std::isfinite(q[2]); }

}  // namespace

template <class PointT>
struct PointIndex<PointT>::Impl {
  Points points;
  std::unique_ptr<Tree> tree;
};

template <class PointT>
PointIndex<PointT>::PointIndex() : impl_(std::make_unique<Impl>()) {}

template <class PointT>
PointIndex<PointT>::PointIndex(const pcl::PointCloud<PointT>& cloud, const pcl::Indices* subset)
    : impl_(std::make_unique<Impl>()) {
  Points& p = impl_->points;
  const std::size_t n = subset ? subset->size() : cloud.size();
  p.xyz.reserve(3 * n);
  p.id.reserve(n);
  for (std::size_t k = 0; k < n; ++k) {
    const pcl::index_t i = subset ? (*subset)[k] : static_cast<pcl::index_t>(k);
    const PointT& q = cloud[static_cast<std::size_t>(i)];
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) continue;  // as PCL's KdTree
    p.xyz.insert(p.xyz.end(), {q.x, q.y, q.z});
    p.id.push_back(i);
  }
  // Leaves of 15 points, as FLANN's single index in PCL.
  impl_->tree = std::make_unique<Tree>(3, p, nanoflann::KDTreeSingleIndexAdaptorParams(15));
}

template <class PointT>
PointIndex<PointT>::~PointIndex() = default;
template <class PointT>
PointIndex<PointT>::PointIndex(PointIndex&&) noexcept = default;
template <class PointT>
PointIndex<PointT>& PointIndex<PointT>::operator=(PointIndex&&) noexcept = default;

template <class PointT>
std::size_t PointIndex<PointT>::size() const {
  return impl_->points.id.size();
}

template <class PointT>
int PointIndex<PointT>::knn(const float* query, int k, pcl::Indices& indices, std::vector<float>& sq_dists) const {
  indices.clear();
  sq_dists.clear();
  if (!impl_->tree || k <= 0 || size() == 0 || !finite3(query)) return 0;
  const std::size_t want = std::min<std::size_t>(static_cast<std::size_t>(k), size());
  indices.resize(want);
  sq_dists.resize(want);
  const std::size_t found = impl_->tree->knnSearch(query, want, indices.data(), sq_dists.data());
  indices.resize(found);
  sq_dists.resize(found);
  for (auto& i : indices) i = impl_->points.id[static_cast<std::size_t>(i)];  // position → cloud index
  return static_cast<int>(found);
}

template <class PointT>
int PointIndex<PointT>::radius(const float* query, double radius, pcl::Indices& indices, std::vector<float>& sq_dists,
                               unsigned max_nn) const {
  indices.clear();
  sq_dists.clear();
  if (!impl_->tree || size() == 0 || !finite3(query) || !(radius >= 0)) return 0;
  std::vector<std::pair<pcl::index_t, float>> matches;
  impl_->tree->radiusSearch(query, static_cast<float>(radius * radius), matches, nanoflann::SearchParams(32, 0, true));
  if (max_nn > 0 && matches.size() > max_nn) matches.resize(max_nn);  // nearest first: keep the closest
  indices.reserve(matches.size());
  sq_dists.reserve(matches.size());
  for (const auto& [i, d] : matches) {
    indices.push_back(impl_->points.id[static_cast<std::size_t>(i)]);
    sq_dists.push_back(d);
  }
  return static_cast<int>(indices.size());
}

template <class PointT>
float PointIndex<PointT>::nearest_sq(const float* query) const {
  if (!impl_->tree || size() == 0 || !finite3(query)) return std::numeric_limits<float>::infinity();
  pcl::index_t i = 0;
  float d = std::numeric_limits<float>::infinity();
  impl_->tree->knnSearch(query, 1, &i, &d);
  return d;
}

template <class PointT>
void NanoSearch<PointT>::setInputCloud(const PointCloudConstPtr& cloud, const IndicesConstPtr& indices) {
  // The base keeps input_ and indices_ for the index-based queries; the FLANN tree stays empty.
  pcl::search::Search<PointT>::setInputCloud(cloud, indices);
  index_ = cloud ? PointIndex<PointT>(*cloud, indices.get()) : PointIndex<PointT>();
}

template <class PointT>
int NanoSearch<PointT>::nearestKSearch(const PointT& point, int k, pcl::Indices& k_indices,
                                       std::vector<float>& k_sqr_distances) const {
  const float q[3] = {point.x, point.y, point.z};
  return index_.knn(q, k, k_indices, k_sqr_distances);
}

template <class PointT>
int NanoSearch<PointT>::radiusSearch(const PointT& point, double radius, pcl::Indices& k_indices,
                                     std::vector<float>& k_sqr_distances, unsigned int max_nn) const {
  const float q[3] = {point.x, point.y, point.z};
  return index_.radius(q, radius, k_indices, k_sqr_distances, max_nn);
}

template class PointIndex<pcl::PointXYZ>;
template class PointIndex<pcl::PointNormal>;
template class NanoSearch<pcl::PointXYZ>;
template class NanoSearch<pcl::PointNormal>;

}  // namespace s2c
