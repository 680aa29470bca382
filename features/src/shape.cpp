// Shapes: names, distances, normals; and the helpers the fits share (fit_util.h).
#include "s2c/features/shape.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "fit_util.h"
#include "s2c/core/errors.h"
#include "vector_math.h"

namespace s2c::features {
namespace {

constexpr double kDegPerRad = 180.0 / M_PI;

struct NamedType {
  ShapeType type;
  const char* name;
};
constexpr NamedType kNames[] = {{ShapeType::freeform, "freeform"}, {ShapeType::plane, "plane"},
                                {ShapeType::cylinder, "cylinder"}, {ShapeType::sphere, "sphere"},
                                {ShapeType::cone, "cone"},         {ShapeType::line, "line"},
                                {ShapeType::circle, "circle"},     {ShapeType::arc, "arc"}};

/// Component of v perpendicular to the unit axis a.
Eigen::Vector3d radial(const Eigen::Vector3d& v, const Eigen::Vector3d& a) { return v - a * a.dot(v); }

}  // namespace

const char* shape_name(ShapeType type) {
  for (const auto& n : kNames)
    if (n.type == type) return n.name;
  return "freeform";
}

ShapeType shape_type(const std::string& name) {
  for (const auto& n : kNames)
    if (name == n.name) return n.type;
  throw InvalidInput("unknown shape type '" + name + "'");
}

bool is_surface(ShapeType type) {
  return type == ShapeType::plane || type == ShapeType::cylinder || type == ShapeType::sphere ||
         type == ShapeType::cone;
}

ShapeMetric::ShapeMetric(const Shape& shape) : s_(&shape) {
  if (shape.type != ShapeType::cone) return;
  const double th = shape.half_angle_deg / kDegPerRad;
  cos_ = std::cos(th);
  sin_ = std::sin(th);
}

double ShapeMetric::distance(const Eigen::Vector3d& p) const {
  const Shape& s = *s_;
  const Eigen::Vector3d v = p - s.point;
  switch (s.type) {
    case ShapeType::plane: return std::abs(s.dir.dot(v));
    case ShapeType::cylinder: return std::abs(radial(v, s.dir).norm() - s.radius);
    case ShapeType::sphere: return std::abs(v.norm() - s.radius);
    case ShapeType::cone: {
      // In the half plane through the axis and p: h along the axis, rho away from it; the nappe is
      // the ray from the apex at half_angle from the axis. Points whose foot on that ray's line
      // falls behind the apex are nearest to the apex itself.
      const double h = s.dir.dot(v), rho = radial(v, s.dir).norm();
      if (h * cos_ + rho * sin_ >= 0) return std::abs(rho * cos_ - h * sin_);
      return v.norm();
    }
    case ShapeType::line: {
      const double t = std::clamp(s.dir.dot(v), 0.0, std::max(s.length, 0.0));
      return (v - t * s.dir).norm();
    }
    case ShapeType::circle:
    case ShapeType::arc: {
      const double h = s.dir.dot(v), rho = radial(v, s.dir).norm();
      return std::hypot(h, rho - s.radius);
    }
    case ShapeType::freeform: break;
  }
  return 0.0;
}

Eigen::Vector3d ShapeMetric::normal(const Eigen::Vector3d& p) const {
  const Shape& s = *s_;
  const Eigen::Vector3d v = p - s.point;
  switch (s.type) {
    case ShapeType::plane: return s.dir.normalized();
    case ShapeType::sphere: {
      const double len = v.norm();
      return len > 0 ? Eigen::Vector3d(v / len) : Eigen::Vector3d::Zero();
    }
    case ShapeType::cylinder:
    case ShapeType::cone: {
      const Eigen::Vector3d r = radial(v, s.dir);
      const double len = r.norm();
      if (!(len > 0)) return Eigen::Vector3d::Zero();  // on the axis: no direction away from it
      if (s.type == ShapeType::cylinder) return r / len;
      return cos_ * (r / len) - sin_ * s.dir;
    }
    default: break;
  }
  return Eigen::Vector3d::Zero();
}

double distance(const Shape& s, const Eigen::Vector3d& p) { return ShapeMetric(s).distance(p); }

Eigen::Vector3d surface_normal(const Shape& s, const Eigen::Vector3d& p) { return ShapeMetric(s).normal(p); }

// ---- helpers of the fits (fit_util.h) ----
namespace fit {
namespace {

/// Deterministic value in [0, 1) for stratified subsampling (splitmix64 finaliser).
double jitter(std::uint64_t k) {
  k += 0x9e3779b97f4a7c15ull;
  k = (k ^ (k >> 30)) * 0xbf58476d1ce4e5b9ull;
  k = (k ^ (k >> 27)) * 0x94d049bb133111ebull;
  k ^= k >> 31;
  return static_cast<double>(k >> 11) * (1.0 / 9007199254740992.0);
}

}  // namespace

std::vector<std::size_t> stratified_pick(std::size_t n, std::size_t max) {
  // One sample per stratum at a pseudo-random offset, so a stride cannot alias with a regular
  // layout (every 96th vertex of 96-vertex rings would be one straight line).
  std::vector<std::size_t> pick;
  if (n <= max) {
    pick.resize(n);
    for (std::size_t i = 0; i < n; ++i) pick[i] = i;
    return pick;
  }
  pick.resize(max);
  const double stratum = static_cast<double>(n) / static_cast<double>(max);
  for (std::size_t k = 0; k < max; ++k)
    pick[k] = std::min(n - 1, static_cast<std::size_t>((static_cast<double>(k) + jitter(k)) * stratum));
  return pick;
}

bool Normalization::enough(int min_count) const {
  return valid && positive >= min_count && pick_positive >= min_count;
}

Normalization normalization(const Samples& s, int max_samples) {
  const std::size_t n = s.points.size();
  if (!s.normals.empty() && s.normals.size() != n)
    throw InvalidInput("shape fit: " + std::to_string(s.normals.size()) + " normals for " + std::to_string(n) +
                       " points");
  if (!s.weights.empty() && s.weights.size() != n)
    throw InvalidInput("shape fit: " + std::to_string(s.weights.size()) + " weights for " + std::to_string(n) +
                       " points");
  Normalization result;
  Normalized& out = result.samples;
  auto weight = [&](std::size_t i) { return s.weights.empty() ? 1.0 : s.weights[i]; };
  double wsum = 0;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (std::size_t i = 0; i < n; ++i) {
    const double w = weight(i);
    if (!s.points[i].allFinite() || !std::isfinite(w) || w < 0) return result;
    if (!s.normals.empty() && !s.normals[i].allFinite()) return result;
    if (w > 0) {
      ++result.positive;
      wsum += w;
      c += w * s.points[i];
    }
  }
  if (!(wsum > 0)) return result;
  c /= wsum;
  double var = 0;
  for (std::size_t i = 0; i < n; ++i) var += weight(i) * (s.points[i] - c).squaredNorm();
  const double scale = std::sqrt(var / wsum);
  if (!(scale > 1e-12 * std::max(1.0, c.norm())) || !std::isfinite(scale)) return result;  // all points equal

  const std::vector<std::size_t> pick = stratified_pick(n, static_cast<std::size_t>(max_samples));
  out.center = c;
  out.scale = scale;
  out.p.reserve(pick.size()), out.n.reserve(pick.size()), out.w.reserve(pick.size()), out.sw.reserve(pick.size());
  double wpick = 0;
  for (std::size_t i : pick) {
    out.p.push_back((s.points[i] - c) / scale);
    Eigen::Vector3d nn = Eigen::Vector3d::Zero();
    if (!s.normals.empty()) {
      const double len = s.normals[i].norm();
      if (len > 1e-12) {
        nn = s.normals[i] / len;
        ++out.normal_count;
      }
    }
    out.n.push_back(nn);
    out.w.push_back(weight(i));
    wpick += weight(i);
    result.pick_positive += weight(i) > 0;
  }
  if (!(wpick > 0)) return result;
  const double mean = wpick / static_cast<double>(pick.size());
  for (double& w : out.w) {
    w /= mean;
    out.sw.push_back(std::sqrt(w));
  }
  result.valid = true;
  return result;
}

bool normalize(const Samples& s, int min_count, Normalized& out, int max_samples) {
  Normalization n = normalization(s, max_samples);
  if (!n.enough(min_count)) return false;
  out = std::move(n.samples);
  return true;
}

Pca pca(const std::vector<Eigen::Vector3d>& p, const std::vector<double>& w) {
  Pca out;
  double wsum = 0;
  for (std::size_t i = 0; i < p.size(); ++i) {
    const double wi = w.empty() ? 1.0 : w[i];
    out.mean += wi * p[i];
    wsum += wi;
  }
  if (!(wsum > 0)) return out;
  out.mean /= wsum;
  Eigen::Matrix3d C = Eigen::Matrix3d::Zero();
  for (std::size_t i = 0; i < p.size(); ++i) {
    const Eigen::Vector3d d = p[i] - out.mean;
    C += (w.empty() ? 1.0 : w[i]) * d * d.transpose();
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(C / wsum);
  out.values = es.eigenvalues();
  out.vectors = es.eigenvectors();
  return out;
}

Eigen::Matrix<double, 3, 2> perpendicular_frame(const Eigen::Vector3d& a) {
  // Cross with the world axis least aligned with a: never (nearly) parallel.
  Eigen::Index i = 0;
  a.cwiseAbs().minCoeff(&i);
  const Eigen::Vector3d u = a.cross(Eigen::Vector3d::Unit(i)).normalized();
  Eigen::Matrix<double, 3, 2> f;
  f.col(0) = u;
  f.col(1) = a.cross(u);
  return f;
}

bool kasa_circle(const std::vector<Eigen::Vector2d>& q, const std::vector<double>& w, Eigen::Vector2d& center,
                 double& radius) {
  const int n = static_cast<int>(q.size());
  if (n < 3) return false;
  Eigen::MatrixXd A(n, 3);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) {
    const double s = std::sqrt(w.empty() ? 1.0 : w[i]);
    A.row(i) << s * q[i].x(), s * q[i].y(), s;
    b[i] = -s * q[i].squaredNorm();
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  qr.setThreshold(1e-9);
  if (qr.rank() < 3) return false;
  const Eigen::Vector3d x = qr.solve(b);
  center = -0.5 * x.head<2>();
  const double r2 = center.squaredNorm() - x[2];
  if (!(r2 > 0) || !x.allFinite()) return false;
  radius = std::sqrt(r2);
  return true;
}

bool finite(const Shape& s) {
  return s.point.allFinite() && s.dir.allFinite() && s.start.allFinite() && s.end.allFinite() &&
         std::isfinite(s.radius) && std::isfinite(s.half_angle_deg) && std::isfinite(s.length) &&
         std::isfinite(s.angle_deg);
}

void finish(Fit& f, const Samples& s) {
  // Each sample's distance and normal angle (an arccosine: the expensive part) first, in parallel
  // over large sample sets (a merge's union, a region grown to a million faces); then the sums in
  // sample order, so the metrics do not depend on the threads.
  const std::size_t n = s.points.size();
  // Per sample the cosine between its normal and the shape's, then the arccosines of a block in
  // one call (vectorised, vector_math.h); a sample without a normal counts for the distances only.
  std::vector<double> dist(n), angle(n);
  std::vector<char> has_angle(n, 0);
  const ShapeMetric metric(f.shape);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n, 16384), [&](const tbb::blocked_range<std::size_t>& r) {
    for (std::size_t i = r.begin(); i != r.end(); ++i) {
      dist[i] = metric.distance(s.points[i]);
      angle[i] = 1.0;
      if (s.normals.empty()) continue;
      const double len = s.normals[i].norm();
      if (!(len > 1e-12)) continue;
      const Eigen::Vector3d sn = metric.normal(s.points[i]);
      if (sn.squaredNorm() == 0) continue;
      angle[i] = std::min(1.0, std::abs(sn.dot(s.normals[i])) / len);
      has_angle[i] = 1;
    }
    acos_in_place(angle.data() + r.begin(), r.size());
  });
  double sum = 0, wsum = 0, worst = 0, nsum = 0, nwsum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double w = s.weights.empty() ? 1.0 : s.weights[i];
    const double d = dist[i];
    sum += w * d * d;
    wsum += w;
    worst = std::max(worst, d);
    if (!has_angle[i]) continue;
    const double a = angle[i] * kDegPerRad;
    nsum += w * a * a;
    nwsum += w;
  }
  f.rms = wsum > 0 ? std::sqrt(sum / wsum) : 0.0;
  f.max_error = worst;
  f.normal_rms_deg = nwsum > 0 ? std::sqrt(nsum / nwsum) : 0.0;
  f.ok = finite(f.shape) && std::isfinite(f.rms) && std::isfinite(f.max_error) && std::isfinite(f.normal_rms_deg);
}

}  // namespace fit
}  // namespace s2c::features
