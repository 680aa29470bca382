// reconstruct's point search (nanoflann) against PCL's own KdTree (FLANN) and its statistical
// outlier filter: same neighbours, same order, same distances, same points kept.
#include <cmath>
#include <limits>
#include <random>

#include <gtest/gtest.h>
#include <pcl/features/normal_3d.h>
#include <pcl/filters/statistical_outlier_removal.h>
#include <pcl/search/kdtree.h>

#include "cloud_util.h"
#include "gicp_covariances.h"
#include "kd_search.h"

using namespace s2c;

namespace {

// Points on a noisy wavy sheet, a few far outliers, and (with `holes`) NaN points among them.
pcl::PointCloud<pcl::PointNormal>::Ptr sheet(int n, bool holes, unsigned seed = 7) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(0.0f, 10.0f);
  std::normal_distribution<float> noise(0.0f, 0.02f);
  auto c = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  for (int i = 0; i < n; ++i) {
    pcl::PointNormal p;
    p.x = u(rng);
    p.y = u(rng);
    p.z = 0.3f * std::sin(p.x) + noise(rng);
    if (i % 97 == 0) p.z += 3.0f;  // outlier
    if (holes && i % 31 == 5) p.x = std::numeric_limits<float>::quiet_NaN();
    c->push_back(p);
  }
  return c;
}

void expect_same(const pcl::Indices& ia, const std::vector<float>& da, const pcl::Indices& ib,
                 const std::vector<float>& db) {
  ASSERT_EQ(ia.size(), ib.size());
  for (std::size_t j = 0; j < ia.size(); ++j) {
    EXPECT_FLOAT_EQ(da[j], db[j]) << j;
    // Equal distances may come in either order; distinct ones must not.
    if (j + 1 < ia.size() && da[j] != da[j + 1] && (j == 0 || da[j] != da[j - 1])) {
      EXPECT_EQ(ia[j], ib[j]) << j;
    }
  }
}

}  // namespace

TEST(PointSearch, AnswersAsPclsKdTree) {
  for (bool holes : {false, true}) {
    const auto cloud = sheet(3000, holes);
    pcl::search::KdTree<pcl::PointNormal> flann;
    flann.setInputCloud(cloud);
    NanoSearch<pcl::PointNormal> nano;
    nano.setInputCloud(cloud);
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> u(-1.0f, 11.0f);
    pcl::Indices ia, ib;
    std::vector<float> da, db;
    for (int q = 0; q < 200; ++q) {
      pcl::PointNormal p;
      p.x = u(rng), p.y = u(rng), p.z = 0.1f * u(rng);
      for (int k : {1, 2, 16, 24}) {
        ASSERT_EQ(flann.nearestKSearch(p, k, ia, da), nano.nearestKSearch(p, k, ib, db));
        expect_same(ia, da, ib, db);
      }
      for (unsigned max_nn : {0u, 5u}) {
        ASSERT_EQ(flann.radiusSearch(p, 0.4, ia, da, max_nn), nano.radiusSearch(p, 0.4, ib, db, max_nn));
        expect_same(ia, da, ib, db);
      }
    }
    // Queries by index (PCL's base class: the outlier filter, normal estimation) and the cloud's
    // own indices in the answers, NaN points never among them.
    for (int i = 0; i < 3000; i += 37) {
      if (!std::isfinite((*cloud)[i].x)) continue;
      ASSERT_EQ(flann.nearestKSearch(i, 8, ia, da), nano.nearestKSearch(i, 8, ib, db));
      expect_same(ia, da, ib, db);
      EXPECT_EQ(ib[0], i);
      for (auto j : ib) EXPECT_TRUE(std::isfinite((*cloud)[j].x));
    }
  }
}

TEST(PointSearch, MoreNeighboursThanPointsAndEmptyClouds) {
  const auto cloud = sheet(5, false);
  NanoSearch<pcl::PointNormal> nano;
  nano.setInputCloud(cloud);
  pcl::Indices idx;
  std::vector<float> sq;
  EXPECT_EQ(nano.nearestKSearch((*cloud)[0], 10, idx, sq), 5);
  EXPECT_EQ(idx.size(), 5u);
  pcl::PointNormal nan_query;
  nan_query.x = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(nano.nearestKSearch(nan_query, 3, idx, sq), 0);
  const PointIndex<pcl::PointNormal> empty(pcl::PointCloud<pcl::PointNormal>{});
  const float q[3] = {0, 0, 0};
  EXPECT_EQ(empty.knn(q, 3, idx, sq), 0);
  EXPECT_TRUE(std::isinf(empty.nearest_sq(q)));
}

TEST(PointSearch, NormalEstimationGivesPclsNormals) {
  const auto cloud = sheet(2000, false);
  pcl::PointCloud<pcl::Normal> a, b;
  pcl::NormalEstimation<pcl::PointNormal, pcl::Normal> ne;
  ne.setInputCloud(cloud);
  ne.setKSearch(16);
  ne.compute(a);
  ne.setSearchMethod(std::make_shared<NanoSearch<pcl::PointNormal>>());
  ne.compute(b);
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_FLOAT_EQ(a[i].normal_z, b[i].normal_z) << i;
    EXPECT_FLOAT_EQ(a[i].curvature, b[i].curvature) << i;
  }
}

TEST(PointSearch, OutlierRemovalKeepsWhatPclKeeps) {
  for (double sigma : {1.0, 2.5, 6.0}) {
    const auto cloud = sheet(4000, false, 11);
    pcl::PointCloud<pcl::PointNormal> expected;
    pcl::StatisticalOutlierRemoval<pcl::PointNormal> sor;
    sor.setInputCloud(cloud);
    sor.setMeanK(16);
    sor.setStddevMulThresh(sigma);
    sor.filter(expected);
    const auto kept = remove_statistical_outliers(*cloud, 16, sigma);
    ASSERT_EQ(kept.size(), expected.size()) << sigma;
    ASSERT_LT(kept.size(), cloud->size()) << "the outliers must go: " << sigma;
    for (std::size_t i = 0; i < kept.size(); ++i) {
      EXPECT_EQ(kept[i].x, expected[i].x);
      EXPECT_EQ(kept[i].z, expected[i].z);
    }
  }
}

/// PCL's own covariance loop, reachable through a derived class (it is protected), on PCL's
/// FLANN tree or on the search registration hands GICP (NanoSearch).
struct PclGicp : s2c::Gicp {
  MatricesVector covariances(const pcl::PointCloud<pcl::PointNormal>::Ptr& cloud,
                             pcl::search::KdTree<pcl::PointNormal>::Ptr tree) {
    tree->setInputCloud(cloud);
    k_correspondences_ = s2c::kCovarianceNeighbours;
    MatricesVector out;
    computeCovariances<pcl::PointNormal>(cloud, tree, out);
    return out;
  }
};

TEST(PointSearch, GicpCovariancesAreBitForBitPcls) {
  // Registration hands GICP covariances computed on both cores; GICP must get the matrices its
  // own serial loop would compute (with PCL's FLANN tree), or the poses would change.
  const auto cloud = sheet(3000, false, 5);
  const auto got = s2c::gicp_covariances(*cloud);
  ASSERT_TRUE(got);
  PclGicp pcl_gicp;
  for (const auto& tree : {std::make_shared<pcl::search::KdTree<pcl::PointNormal>>(),
                           pcl::search::KdTree<pcl::PointNormal>::Ptr(std::make_shared<NanoSearch<pcl::PointNormal>>())}) {
    const auto expected = pcl_gicp.covariances(cloud, tree);
    ASSERT_EQ(got->size(), expected.size());
    for (std::size_t i = 0; i < expected.size(); ++i)
      for (int k = 0; k < 9; ++k) ASSERT_EQ((*got)[i](k), expected[i](k)) << "point " << i << ", entry " << k;
  }
  // Too few points, or a non-finite one: no covariances (GICP cannot run on them).
  EXPECT_FALSE(s2c::gicp_covariances(*sheet(s2c::kCovarianceNeighbours - 1, false)));
  EXPECT_FALSE(s2c::gicp_covariances(*sheet(200, true)));
}
