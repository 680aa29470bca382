#include "s2c/reconstruct/register.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>

#include <fmt/format.h>
#include <Eigen/Geometry>
#include <pcl/common/transforms.h>
#include <pcl/features/fpfh_omp.h>
#include <pcl/features/normal_3d.h>
#include <pcl/point_types.h>
#include <pcl/registration/gicp.h>
#include <pcl/registration/sample_consensus_prerejective.h>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>

#include "s2c/core/errors.h"
#include "s2c/core/progress.h"
#include "cloud_util.h"
#include "gicp_covariances.h"
#include "kd_search.h"

namespace s2c {
namespace {

using PN = pcl::PointNormal;
using CloudPN = pcl::PointCloud<PN>;
constexpr std::size_t kMaxRegistrationPoints = 6000;

// A view downsampled to `voxel` with normals oriented towards its sensor, in the sensor frame.
// The direction to the sensor rides in the normal fields through the voxel grid (which
// averages every field), then decides each estimated normal's sign.
CloudPN::Ptr prepare(const View& v, double voxel) {
  auto raw = std::make_shared<CloudPN>();
  raw->reserve(v.points.size());
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero();
  for (const auto& p : v.points) centroid += p;
  centroid /= static_cast<double>(std::max<std::size_t>(1, v.points.size()));
  for (std::size_t i = 0; i < v.points.size(); ++i) {
    // Unknown sensor (plain clouds): face away from the view's centroid.
    const Eigen::Vector3d d = v.to_sensor.empty() ? Eigen::Vector3d(v.points[i] - centroid) : v.to_sensor[i];
    raw->push_back(point_normal(v.points[i], d));
  }
  auto down = std::make_shared<CloudPN>(voxel_downsample(*raw, voxel));
  // Six unknowns need a few thousand well-spread points, not a room's worth: coarsen the grid
  // (not a stride, which would thin the density that overlap tests rely on).
  for (double cell = voxel; down->size() > kMaxRegistrationPoints;) {
    cell *= std::sqrt(static_cast<double>(down->size()) / kMaxRegistrationPoints);
    *down = voxel_downsample(*raw, cell);
  }
  // One thread per view: the views are prepared side by side.
  pcl::NormalEstimation<PN, pcl::Normal> ne;
  ne.setSearchMethod(std::make_shared<NanoSearch<PN>>());
  ne.setInputCloud(down);
  ne.setKSearch(16);
  pcl::PointCloud<pcl::Normal> normals;
  ne.compute(normals);
  auto out = std::make_shared<CloudPN>();
  for (std::size_t i = 0; i < down->size(); ++i) {
    Eigen::Vector3f n(normals[i].normal_x, normals[i].normal_y, normals[i].normal_z);
    if (!n.allFinite()) continue;
    PN q = (*down)[i];
    const Eigen::Vector3f dir(q.normal_x, q.normal_y, q.normal_z);
    if (n.dot(dir) < 0) n = -n;
    q.normal_x = n.x();
    q.normal_y = n.y();
    q.normal_z = n.z();
    q.curvature = normals[i].curvature;
    out->push_back(q);
  }
  return out;
}

CloudPN::Ptr union_of(const std::vector<CloudPN::Ptr>& clouds, const std::vector<Eigen::Isometry3d>& poses,
                      const std::vector<int>& which) {
  auto out = std::make_shared<CloudPN>();
  for (int j : which) {
    CloudPN t;
    pcl::transformPointCloudWithNormals(*clouds[j], t, poses[j].matrix().cast<float>());
    *out += t;
  }
  return out;
}

struct Fit {
  double rms = 0, overlap = 0;
};

// Residual of a placed view against a target: share of its points with a partner within
// `radius`, and the point-to-plane RMS over those.
Fit evaluate(const CloudPN& source, const Eigen::Isometry3d& pose, const CloudPN::Ptr& target, double radius) {
  Fit f;
  if (source.empty() || target->empty()) return f;
  const PointIndex<PN> tree(*target);
  pcl::Indices idx;
  std::vector<float> sq;
  double sum = 0;
  std::size_t hits = 0;
  const Eigen::Matrix4f T = pose.matrix().cast<float>();
  for (const auto& p : source) {
    PN q;
    q.getVector4fMap() = T * Eigen::Vector4f(p.x, p.y, p.z, 1);
    if (tree.knn(q.data, 1, idx, sq) != 1 || sq[0] > radius * radius) continue;
    const PN& t = (*target)[static_cast<std::size_t>(idx[0])];
    const double d = (q.getVector3fMap() - t.getVector3fMap()).dot(t.getNormalVector3fMap());
    sum += d * d;
    ++hits;
  }
  f.overlap = static_cast<double>(hits) / static_cast<double>(source.size());
  f.rms = hits ? std::sqrt(sum / static_cast<double>(hits)) : 0;
  return f;
}

// Generalized ICP (plane-to-plane), coarse to fine: correspondence radii shrink to the last of
// `radii` × spacing. On partial overlaps of machined parts it converged markedly closer than
// PCL's symmetric point-to-plane ICP (tests/unit/reconstruct: worst misfit 1.05 vs 1.51 mm
// from 0.5° / 0.3 mm pose errors). `source_covariances` are the source's, computed once per
// view (a view is aligned several times; its covariances, in its own frame, do not change).
Eigen::Isometry3d icp_refine(const CloudPN::Ptr& source, const CloudPN::Ptr& target, const Eigen::Isometry3d& init,
                             double spacing, const std::vector<double>& radii,
                             const Gicp::MatricesVectorPtr& source_covariances) {
  // The target's tree, built once: GICP searches it and its covariances come from it.
  auto target_tree = std::make_shared<NanoSearch<PN>>();
  target_tree->setInputCloud(target);
  // Too few points for a covariance (PCL's GICP would read an empty covariance list): nothing to
  // refine against, the pose stays.
  const Gicp::MatricesVectorPtr target_covariances = gicp_covariances(*target, target_tree->index());
  if (!source_covariances || !target_covariances) return init;
  Eigen::Matrix4f guess = init.matrix().cast<float>();
  Gicp gicp;
  gicp.setSearchMethodTarget(target_tree, true);  // built above: not again
  gicp.setSearchMethodSource(std::make_shared<NanoSearch<PN>>());
  gicp.setInputSource(source);
  gicp.setInputTarget(target);
  gicp.setCorrespondenceRandomness(kCovarianceNeighbours);
  gicp.setSourceCovariances(source_covariances);
  gicp.setTargetCovariances(target_covariances);
  for (double f : radii) {
    gicp.setMaxCorrespondenceDistance(f * spacing);
    gicp.setMaximumIterations(30);
    gicp.setTransformationEpsilon(1e-10);
    CloudPN aligned;
    gicp.align(aligned, guess);
    if (gicp.hasConverged()) guess = gicp.getFinalTransformation();
  }
  Eigen::Isometry3d out = Eigen::Isometry3d::Identity();
  out.matrix() = guess.cast<double>();
  // Re-orthonormalise: float accumulation leaves the rotation slightly off.
  out.linear() = Eigen::Quaterniond(out.rotation()).normalized().toRotationMatrix();
  return out;
}

// FPFH + SampleConsensusPrerejective: a pose for `source` (sensor frame) on `target` (world).
std::optional<Eigen::Isometry3d> global_align(const CloudPN::Ptr& source, const CloudPN::Ptr& target, double voxel) {
  using Features = pcl::PointCloud<pcl::FPFHSignature33>;
  auto features = [&](const CloudPN::Ptr& c) {
    auto f = std::make_shared<Features>();
    pcl::FPFHEstimationOMP<PN, PN, pcl::FPFHSignature33> est(2);
    est.setSearchMethod(std::make_shared<NanoSearch<PN>>());
    est.setInputCloud(c);
    est.setInputNormals(c);
    est.setRadiusSearch(5.0 * voxel);
    est.compute(*f);
    return f;
  };
  const auto fs = features(source), ft = features(target);
  pcl::SampleConsensusPrerejective<PN, PN, pcl::FPFHSignature33> ransac;
  ransac.setSearchMethodTarget(std::make_shared<NanoSearch<PN>>());
  ransac.setInputSource(source);
  ransac.setSourceFeatures(fs);
  ransac.setInputTarget(target);
  ransac.setTargetFeatures(ft);
  ransac.setMaximumIterations(20000);
  ransac.setNumberOfSamples(3);
  ransac.setCorrespondenceRandomness(5);
  ransac.setSimilarityThreshold(0.9f);
  ransac.setMaxCorrespondenceDistance(static_cast<float>(2.5 * voxel));
  ransac.setInlierFraction(0.2f);
  std::srand(1);  // PCL's sampler uses rand(): same input, same result
  CloudPN aligned;
  ransac.align(aligned);
  if (!ransac.hasConverged()) return std::nullopt;
  Eigen::Isometry3d T = Eigen::Isometry3d::Identity();
  T.matrix() = ransac.getFinalTransformation().cast<double>();
  return T;
}

double angle_deg(const Eigen::Matrix3d& R) {
  return Eigen::AngleAxisd(R).angle() * 180.0 / M_PI;
}

// The `k` other placed views whose sensors are nearest to view i's.
std::vector<int> neighbours_of(int i, const std::vector<Eigen::Isometry3d>& poses, const std::vector<char>& placed, int k) {
  std::vector<std::pair<double, int>> d;
  for (int j = 0; j < static_cast<int>(poses.size()); ++j)
    if (j != i && placed[j]) d.emplace_back((poses[j].translation() - poses[i].translation()).norm(), j);
  std::sort(d.begin(), d.end());
  std::vector<int> out;
  for (int m = 0; m < std::min<int>(k, static_cast<int>(d.size())); ++m) out.push_back(d[m].second);
  return out;
}

}  // namespace

std::vector<Eigen::Isometry3d> register_views(const std::vector<View>& views, double spacing,
                                              const RegistrationOptions& o, std::vector<ViewAlignment>& report) {
  const int n = static_cast<int>(views.size());
  report.assign(n, {});
  std::vector<Eigen::Isometry3d> poses(n, Eigen::Isometry3d::Identity());
  const bool have_poses = std::all_of(views.begin(), views.end(), [](const View& v) { return v.pose.has_value(); });
  for (int i = 0; i < n; ++i) {
    report[i].name = views[i].name;
    if (views[i].pose) poses[i] = *views[i].pose;
  }
  RegistrationMode mode = o.mode;
  if (mode == RegistrationMode::automatic) mode = have_poses ? RegistrationMode::refine : RegistrationMode::global;
  if (mode == RegistrationMode::refine && !have_poses)
    throw InvalidInput("--register refine needs recorded poses for every view (poses.txt)");
  if (n < 2 || mode == RegistrationMode::off) {
    if (!have_poses && n > 1)
      throw InvalidInput("several views without poses cannot be fused unregistered; use --register global");
    return poses;
  }
  if (!(spacing > 0)) throw ProcessingError("cannot register: the point spacing is zero");

  // Registration works on a coarser copy of each view: plenty of constraints for six unknowns,
  // and a fraction of the cost.
  const double voxel = 3.0 * spacing;
  const std::vector<double> radii = {12.0, 6.0, 3.0};
  std::vector<CloudPN::Ptr> fine(n);
  tbb::parallel_for(0, n, [&](int i) { fine[i] = prepare(views[i], voxel); });
  std::vector<char> placed(n, 0);
  spdlog::debug("registration: {} views, {} points each after thinning (voxel {:.3f} mm)", n, fine[0]->size(), voxel);
  // Each view's GICP covariances, in its own frame: computed once, for every alignment of it.
  std::vector<Gicp::MatricesVectorPtr> covariances(n);
  auto covariances_of = [&](int i) -> const Gicp::MatricesVectorPtr& {
    if (!covariances[i]) covariances[i] = gicp_covariances(*fine[i]);
    return covariances[i];
  };

  if (mode == RegistrationMode::global) {
    // Place view 0, then each next view against everything placed so far.
    const double gvoxel = 2.5 * voxel;
    std::vector<CloudPN::Ptr> coarse(n);
    tbb::parallel_for(0, n, [&](int i) { coarse[i] = prepare(views[i], gvoxel); });
    placed[0] = 1;
    Progress progress("global", n - 1);
    for (int i = 1; i < n; ++i) {
      std::vector<int> done;
      for (int j = 0; j < n; ++j)
        if (placed[j]) done.push_back(j);
      const auto target_fine = union_of(fine, poses, done);
      progress.advance();
      // A sequence moves little between frames: try starting from the previous placed view's
      // pose; only a clear fit is taken, anything else goes to the global search.
      const Eigen::Isometry3d T_seq =
          icp_refine(fine[i], target_fine, poses[done.back()], spacing, radii, covariances_of(i));
      const Fit seq_fit = evaluate(*fine[i], T_seq, target_fine, voxel);
      spdlog::debug("view {}: from the previous pose overlap {:.2f}, rms {:.3f} mm", i, seq_fit.overlap, seq_fit.rms);
      if (seq_fit.overlap >= 0.5 && seq_fit.rms <= 2.0 * spacing) {
        poses[i] = T_seq;
        placed[i] = 1;
        continue;
      }
      const auto T0 = global_align(coarse[i], union_of(coarse, poses, done), gvoxel);
      if (!T0) {
        report[i].rejected = true;
        report[i].reason = "no global alignment found (too little overlap or too few distinct features)";
        continue;
      }
      const Eigen::Isometry3d T = icp_refine(fine[i], target_fine, *T0, spacing, radii, covariances_of(i));
      const Fit fit = evaluate(*fine[i], T, target_fine, voxel);
      if (fit.overlap < o.min_overlap) {
        report[i].rejected = true;
        report[i].reason = fmt::format("aligns with only {:.0f}% of its points", 100 * fit.overlap);
        continue;
      }
      poses[i] = T;
      placed[i] = 1;
    }
  } else {
    std::fill(placed.begin(), placed.end(), 1);
  }

  // Multi-view refinement: every view against its nearest neighbours, a few passes, so that
  // no view carries the error of a chain. In global mode view 0 stays put to fix the frame.
  // Sequential on purpose: each view sees the poses refined before it (Gauss–Seidel). Refining
  // every view against the pass's starting poses (Jacobi, in parallel) left 0.3–0.8 mm misfits
  // from 0.5° pose errors after two passes; refining non-neighbouring pairs side by side worked
  // but moved the poses enough to change the features found on the fixture scans downstream
  // (stop 29, bench/README.md).
  const int rounds = o.rounds;
  Progress progress("refine", static_cast<std::size_t>(rounds) * n);
  for (int round = 0; round < rounds; ++round)
    for (int i = 0; i < n; ++i) {
      progress.advance();
      if (!placed[i] || (mode == RegistrationMode::global && i == 0)) continue;
      const auto nb = neighbours_of(i, poses, placed, o.neighbours);
      if (nb.empty()) continue;
      const Eigen::Isometry3d T =
          icp_refine(fine[i], union_of(fine, poses, nb), poses[i], spacing, radii, covariances_of(i));
      if (views[i].pose) {
        const Eigen::Isometry3d delta = views[i].pose->inverse() * T;
        if (angle_deg(delta.rotation()) > o.max_correction_deg) {
          report[i].reason = "refinement moved the recorded pose too far; kept the recorded pose";
          continue;
        }
      }
      poses[i] = T;
    }

  // Refining every view leaves the set free to drift as a whole. Recorded poses define the
  // frame (the turntable's, the part's): put the refined set back where the recording had it,
  // by the rigid motion that best maps refined onto recorded sample points of every view.
  if (mode == RegistrationMode::refine) {
    Eigen::Matrix3Xd from(3, 0), to(3, 0);
    for (int i = 0; i < n; ++i) {
      if (!placed[i]) continue;
      const std::size_t step = std::max<std::size_t>(1, fine[i]->size() / 200);
      for (std::size_t k = 0; k < fine[i]->size(); k += step) {
        const Eigen::Vector3d p = (*fine[i])[k].getVector3fMap().cast<double>();
        from.conservativeResize(3, from.cols() + 1);
        to.conservativeResize(3, to.cols() + 1);
        from.col(from.cols() - 1) = poses[i] * p;
        to.col(to.cols() - 1) = *views[i].pose * p;
      }
    }
    if (from.cols() >= 3) {
      Eigen::Isometry3d C = Eigen::Isometry3d::Identity();
      C.matrix() = Eigen::umeyama(from, to, false);
      for (auto& P : poses) P = C * P;
    }
  }

  // Final residuals and rejection of views that do not fit with the others.
  int kept = 0;
  for (int i = 0; i < n; ++i) {
    if (!placed[i]) continue;
    const auto nb = neighbours_of(i, poses, placed, o.neighbours);
    const Fit fit = nb.empty() ? Fit{} : evaluate(*fine[i], poses[i], union_of(fine, poses, nb), voxel);
    report[i].rms_mm = fit.rms;
    report[i].overlap = fit.overlap;
    if (views[i].pose) {
      const Eigen::Isometry3d delta = views[i].pose->inverse() * poses[i];
      report[i].corrected_mm = delta.translation().norm();
      report[i].corrected_deg = angle_deg(delta.rotation());
    }
    if (!nb.empty() && fit.overlap < o.min_overlap) {
      report[i].rejected = true;
      report[i].reason = fmt::format("overlaps the other views with only {:.0f}% of its points", 100 * fit.overlap);
      continue;
    }
    ++kept;
  }
  for (const auto& r : report)
    if (r.rejected) spdlog::warn("view {} rejected: {}", r.name, r.reason);
  if (kept < 1 || (n > 1 && kept < 2))
    throw ProcessingError(fmt::format("registration failed: the {} views do not overlap (see the warnings above)", n));
  return poses;
}

}  // namespace s2c
