#include "cloud_util.h"

#include <algorithm>
#include <cmath>

#include <pcl/point_types.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "kd_search.h"

namespace s2c {

double median_spacing(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 2) return 0;
  pcl::PointCloud<pcl::PointXYZ> cloud;
  cloud.reserve(points.size());
  for (const auto& p : points) cloud.emplace_back(static_cast<float>(p.x()), static_cast<float>(p.y()), static_cast<float>(p.z()));
  const PointIndex<pcl::PointXYZ> tree(cloud);
  std::vector<double> d;
  pcl::Indices idx;
  std::vector<float> sq;
  const std::size_t step = std::max<std::size_t>(1, cloud.size() / 4000);
  for (std::size_t i = 0; i < cloud.size(); i += step)
    if (tree.knn(cloud[i].data, 2, idx, sq) == 2 && sq[1] > 0) d.push_back(std::sqrt(sq[1]));
  if (d.empty()) return 0;
  std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
  return d[d.size() / 2];
}

}  // namespace s2c

#include <unordered_map>

namespace s2c {

pcl::PointCloud<pcl::PointNormal> voxel_downsample(const pcl::PointCloud<pcl::PointNormal>& in, double voxel) {
  struct Acc {
    Eigen::Vector3d p = Eigen::Vector3d::Zero(), n = Eigen::Vector3d::Zero();
    double curvature = 0;
    int count = 0;
  };
  std::unordered_map<std::uint64_t, Acc> cells;
  cells.reserve(in.size() / 2 + 1);
  std::vector<std::uint64_t> order;  // first-seen order keeps the output deterministic
  const double inv = 1.0 / voxel;
  for (const auto& q : in) {
    if (!std::isfinite(q.x) || !std::isfinite(q.y) || !std::isfinite(q.z)) continue;
    // 21 bits per axis around the origin: ±10^6 voxels, far beyond any scan here.
    auto key = [&](float c) { return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(c * inv)) + (1 << 20)) & 0x1fffff; };
    const std::uint64_t k = key(q.x) | (key(q.y) << 21) | (key(q.z) << 42);
    auto [it, fresh] = cells.try_emplace(k);
    if (fresh) order.push_back(k);
    Acc& a = it->second;
    a.p += Eigen::Vector3d(q.x, q.y, q.z);
    a.n += Eigen::Vector3d(q.normal_x, q.normal_y, q.normal_z);
    a.curvature += q.curvature;
    ++a.count;
  }
  pcl::PointCloud<pcl::PointNormal> out;
  out.reserve(order.size());
  for (std::uint64_t k : order) {
    const Acc& a = cells[k];
    pcl::PointNormal q = point_normal(a.p / a.count, a.n / a.count);
    q.curvature = static_cast<float>(a.curvature / a.count);
    out.push_back(q);
  }
  return out;
}

pcl::PointCloud<pcl::PointNormal> remove_statistical_outliers(const pcl::PointCloud<pcl::PointNormal>& in, int mean_k,
                                                              double sigma) {
  const PointIndex<pcl::PointNormal> index(in);
  // Per point, as PCL: the mean of the square roots of the k nearest squared distances, the
  // query itself (first, at distance 0) left out; non-finite points count 0 and are kept.
  std::vector<float> mean_distance(in.size(), 0.0f);
  std::vector<char> valid(in.size(), 0);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, in.size(), 2048), [&](const auto& r) {
    pcl::Indices idx;
    std::vector<float> sq;
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      if (index.knn(in[i].data, mean_k + 1, idx, sq) == 0) continue;
      double sum = 0.0;
      for (std::size_t k = 1; k < sq.size(); ++k) sum += std::sqrt(sq[k]);
      mean_distance[i] = static_cast<float>(sum / mean_k);
      valid[i] = 1;
    }
  });
  // Sums in PCL's order and precision (float products), so the threshold is PCL's to the bit.
  double sum = 0, sq_sum = 0;
  int count = 0;
  for (std::size_t i = 0; i < in.size(); ++i) {
    sum += mean_distance[i];
    sq_sum += mean_distance[i] * mean_distance[i];
    count += valid[i];
  }
  const double mean = sum / count;
  const double variance = (sq_sum - sum * sum / count) / (count - 1);
  const double threshold = mean + sigma * std::sqrt(variance);
  pcl::PointCloud<pcl::PointNormal> out;
  out.reserve(in.size());
  for (std::size_t i = 0; i < in.size(); ++i)
    if (!(mean_distance[i] > threshold)) out.push_back(in[i]);
  return out;
}

}  // namespace s2c
