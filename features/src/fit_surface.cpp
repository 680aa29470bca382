// Surface fits: plane (weighted PCA), sphere, cylinder and cone (algebraic / normal-based initial
// estimates, then Levenberg–Marquardt on the geometric distance in normalised coordinates).
#include <cmath>
#include <limits>
#include <memory>
#include <mutex>
#include <vector>

#include <tbb/parallel_for.h>

#include "fit_models.h"
#include "fit_util.h"

namespace s2c::features {
namespace {

using fit::Normalized;
using fit::CylinderModel;
using fit::ConeModel;
using fit::SphereModel;
using Eigen::Vector3d;
constexpr double kInf = std::numeric_limits<double>::infinity();
/// Candidate initial estimates are refined on at most this many samples; the best one then on all
/// of the (≤ kMaxRefineSamples) refinement samples.
constexpr int kCoarseSamples = 1000;
/// The coarse runs only rank the starts: a dozen steps tell the start that leads somewhere from
/// the others (most starts of a cone fit to a patch that is no cone crept on to the iteration
/// cap, half of a million-vertex part's analysis), and the best one then runs to convergence.
constexpr int kCoarseIterations = 12;

/// Every k-th sample of `s`, at most `max` of them (s is already a stratified subsample).
Normalized thin(const Normalized& s, int max) {
  if (s.size() <= max) return s;
  Normalized out;
  out.center = s.center;
  out.scale = s.scale;
  out.p.reserve(max), out.n.reserve(max), out.w.reserve(max), out.sw.reserve(max);
  const double step = static_cast<double>(s.size()) / max;
  for (int k = 0; k < max; ++k) {
    const int i = static_cast<int>(k * step);
    out.p.push_back(s.p[i]);
    out.n.push_back(s.n[i]);
    out.w.push_back(s.w[i]);
    out.sw.push_back(s.sw[i]);
    out.normal_count += s.n[i].squaredNorm() > 0;
  }
  return out;
}

/// An axis-model start: axis, point on it, radius there, half angle (0 for a cylinder).
struct AxisStart {
  Vector3d a, p;
  double r, theta;
};

/// Smallest-eigenvalue eigenvector of Σ w n nᵀ (or of the normals' covariance when `centred`)
/// over the samples with normals: the direction all normals are perpendicular to (cylinder), or
/// make a constant angle with (cone).
bool normal_axis(const Normalized& s, bool centred, Vector3d& axis) {
  if (s.normal_count < 3) return false;
  Vector3d mean = Vector3d::Zero();
  double wsum = 0;
  for (int i = 0; i < s.size(); ++i)
    if (s.n[i].squaredNorm() > 0) {
      mean += s.w[i] * s.n[i];
      wsum += s.w[i];
    }
  if (!(wsum > 0)) return false;
  mean = centred ? Vector3d(mean / wsum) : Vector3d::Zero();
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  for (int i = 0; i < s.size(); ++i)
    if (s.n[i].squaredNorm() > 0) M += s.w[i] * (s.n[i] - mean) * (s.n[i] - mean).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(M / wsum);
  if (!(es.eigenvalues()[2] > 1e-12)) return false;  // all normals equal: no axis
  axis = es.eigenvectors().col(0);
  return axis.allFinite();
}

/// The axis candidates: from the normals when known (the fit this is for says how), and the three
/// principal axes `pc` of the points (long cylinders: the largest; short ones and symmetric sectors:
/// one of the others), which also serve when there are no normals.
std::vector<Vector3d> candidate_axes(const Normalized& s, const fit::Pca& pc, bool centred_normals) {
  std::vector<Vector3d> axes;
  Vector3d a;
  if (normal_axis(s, centred_normals, a)) axes.push_back(a);
  for (int k = 0; k < 3; ++k) axes.push_back(pc.vectors.col(k));
  return axes;
}

/// Cylinder start for an axis: a circle fitted to the points projected on the plane ⟂ a.
bool circle_start(const Normalized& s, const Vector3d& a, AxisStart& out) {
  const auto uv = fit::perpendicular_frame(a);
  std::vector<Eigen::Vector2d> q(s.size());
  for (int i = 0; i < s.size(); ++i) q[i] = uv.transpose() * s.p[i];
  Eigen::Vector2d c;
  double r;
  if (!fit::kasa_circle(q, s.w, c, r)) return false;
  out = {a, uv * c, r, 0.0};
  return true;
}

/// Cone start for an axis, algebraic: |q - c| = r0 + k h (q ⟂ a, h along a) squared is linear in
/// (c, |c|² - r0², r0 k, k²). Needs samples at three or more heights.
bool algebraic_cone_start(const Normalized& s, const Vector3d& a, AxisStart& out) {
  const auto uv = fit::perpendicular_frame(a);
  const int n = s.size();
  if (n < 5) return false;
  Eigen::MatrixXd A(n, 5);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector2d q = uv.transpose() * s.p[i];
    const double h = a.dot(s.p[i]), w = s.sw[i];
    A.row(i) << w * q.x(), w * q.y(), w, w * h, w * h * h;
    b[i] = -w * q.squaredNorm();
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  qr.setThreshold(1e-9);
  if (qr.rank() < 5) return false;
  const Eigen::Matrix<double, 5, 1> x = qr.solve(b);
  const double k2 = -x[4];
  if (!x.allFinite() || !(k2 > 1e-12)) return false;  // not a cone (a cylinder start covers that)
  const double r0 = std::abs(x[3]) / (2.0 * std::sqrt(k2));
  const double k = -x[3] / (2.0 * r0);
  const Eigen::Vector2d c = -0.5 * x.head<2>();
  if (!(r0 > 0) || !std::isfinite(k)) return false;
  out = {a, uv * c, r0, std::atan(k)};
  return true;
}

/// Cone start from the normals (the spec's construction): the axis from the normals' covariance,
/// the apex as the least-squares intersection of the tangent planes n·(x − p) = 0, the half angle
/// from the mean |n·a|; the axis oriented from the apex towards the samples.
bool tangent_plane_cone_start(const Normalized& s, AxisStart& out) {
  Vector3d a;
  if (s.normal_count < 6 || !normal_axis(s, true, a)) return false;
  Eigen::Matrix3d M = Eigen::Matrix3d::Zero();
  Vector3d rhs = Vector3d::Zero();
  double sin_sum = 0, wsum = 0;
  for (int i = 0; i < s.size(); ++i) {
    const Vector3d& n = s.n[i];
    if (n.squaredNorm() == 0) continue;
    const Eigen::Matrix3d nn = s.w[i] * n * n.transpose();
    M += nn;
    rhs += nn * s.p[i];
    sin_sum += s.w[i] * std::abs(n.dot(a));
    wsum += s.w[i];
  }
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es(M);
  // Nearly a cylinder: the tangent planes meet far away or nowhere; the other starts cover it.
  if (!(es.eigenvalues()[0] > 1e-6 * es.eigenvalues()[2])) return false;
  const Vector3d apex = es.eigenvectors() * es.eigenvalues().cwiseInverse().asDiagonal() *
                        es.eigenvectors().transpose() * rhs;
  const double theta = std::asin(std::min(1.0, sin_sum / wsum));
  double side = 0;
  for (int i = 0; i < s.size(); ++i) side += s.w[i] * a.dot(s.p[i] - apex);
  if (side < 0) a = -a;
  const double height = -a.dot(apex);  // the centroid (origin) above the apex
  const Vector3d p = apex + height * a;
  if (!apex.allFinite() || !(height > 0)) return false;
  out = {a, p, height * std::tan(theta), theta};
  return true;
}

/// True when every parameter of the start is finite.
bool all_finite(const AxisStart& st) {
  return st.a.allFinite() && st.p.allFinite() && std::isfinite(st.r) && std::isfinite(st.theta);
}

/// One Levenberg–Marquardt run of the model from `start` on the samples `s`, whose columns are
/// `columns`.
template <class Model>
bool refine_from(const Normalized& s, const std::shared_ptr<const fit::SampleColumns>& columns, AxisStart& start) {
  Model m(s, columns, start.a, start.p, start.r, start.theta);
  if (!std::isfinite(fit::levenberg_marquardt(m))) return false;
  start = {m.a, m.p, m.r, m.theta};
  return all_finite(start);
}

/// Refines every start on a coarse subsample for kCoarseIterations steps, then the best one on all
/// refinement samples to convergence.
template <class Model>
bool refine_best(const Normalized& s, const std::shared_ptr<const fit::SampleColumns>& columns_of_s,
                 const std::vector<AxisStart>& starts, AxisStart& best) {
  // (A copy only when thinned: most sample sets are smaller, and their columns then serve the
  // last run too.)
  const bool thinned = s.size() > kCoarseSamples;
  const Normalized thinned_samples = thinned ? thin(s, kCoarseSamples) : Normalized{};
  const Normalized& coarse = thinned ? thinned_samples : s;
  // The starts' runs are independent: side by side (a cone's nine are the longest path of a
  // small region's shape choice), then the best taken in start order as one loop would.
  std::vector<double> costs(starts.size());
  std::vector<AxisStart> refined(starts.size());
  const auto columns = thinned ? std::make_shared<const fit::SampleColumns>(coarse) : columns_of_s;
  tbb::parallel_for(std::size_t{0}, starts.size(), [&](std::size_t i) {
    const AxisStart& st = starts[i];
    Model m(coarse, columns, st.a, st.p, st.r, st.theta);
    costs[i] = fit::levenberg_marquardt(m, kCoarseIterations);
    refined[i] = {m.a, m.p, m.r, m.theta};
  });
  double best_cost = kInf;
  for (std::size_t i = 0; i < starts.size(); ++i) {
    if (!(costs[i] < best_cost) || !all_finite(refined[i])) continue;
    best_cost = costs[i];
    best = refined[i];
  }
  return best_cost < kInf && refine_from<Model>(s, columns_of_s, best);
}

/// The plane fit of `s` (which has enough samples for one).
Fit plane_fit(const Samples& s) {
  Fit out;
  out.shape.type = ShapeType::plane;
  // Weighted PCA over all samples is already the exact least-squares plane (orthogonal
  // distance), so there is nothing left for a nonlinear refinement to do.
  const fit::Pca pc = fit::pca(s.points, s.weights);
  if (!(pc.values[1] > 1e-10 * pc.values[2])) return out;  // collinear
  Vector3d n = pc.vectors.col(0);
  if (!s.normals.empty()) {
    double agree = 0;
    for (std::size_t i = 0; i < s.points.size(); ++i)
      agree += (s.weights.empty() ? 1.0 : s.weights[i]) * n.dot(s.normals[i]);
    if (agree < 0) n = -n;
  }
  out.shape.point = pc.mean;
  out.shape.dir = n;
  fit::finish(out, s);
  return out;
}

/// The sphere fit of `s`, refined from `m` (normalised coordinates).
Fit sphere_fit(const Samples& s, const Normalized& ns, SphereModel m) {
  Fit out;
  out.shape.type = ShapeType::sphere;
  if (!std::isfinite(fit::levenberg_marquardt(m)) || !(m.r > 0)) return out;
  out.shape.point = ns.to_world(m.c);
  out.shape.radius = m.r * ns.scale;
  fit::finish(out, s);
  return out;
}

/// The sphere fit of `s` from the algebraic start on its normalised samples `ns`.
Fit sphere_fit(const Samples& s, const Normalized& ns, const std::shared_ptr<const fit::SampleColumns>& columns) {
  Fit out;
  out.shape.type = ShapeType::sphere;
  // Algebraic: |x|² + D·x + E = 0 is linear in (D, E); coplanar points leave it undetermined.
  const int n = ns.size();
  Eigen::MatrixXd A(n, 4);
  Eigen::VectorXd b(n);
  for (int i = 0; i < n; ++i) {
    const double w = ns.sw[i];
    A.row(i) << w * ns.p[i].transpose(), w;
    b[i] = -w * ns.p[i].squaredNorm();
  }
  Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  qr.setThreshold(1e-9);
  if (qr.rank() < 4) return out;
  const Eigen::Vector4d x = qr.solve(b);
  const Vector3d c = -0.5 * x.head<3>();
  const double r2 = c.squaredNorm() - x[3];
  if (!x.allFinite() || !(r2 > 0)) return out;
  return sphere_fit(s, ns, SphereModel{&ns, c, std::sqrt(r2), columns});
}

/// The cylinder fit of `s` from a refined axis start (normalised coordinates).
Fit cylinder_fit(const Samples& s, const Normalized& ns, const AxisStart& best) {
  Fit out;
  out.shape.type = ShapeType::cylinder;
  if (!(best.r > 0)) return out;
  const Vector3d foot = best.p - best.a * best.a.dot(best.p);  // nearest the centroid
  out.shape.point = ns.to_world(foot);
  out.shape.dir = best.a.normalized();
  out.shape.radius = best.r * ns.scale;
  fit::finish(out, s);
  return out;
}

/// The cylinder fit of `s` from the robust starts on `ns`, whose principal axes are `pc`.
Fit cylinder_fit(const Samples& s, const Normalized& ns, const std::shared_ptr<const fit::SampleColumns>& columns,
                 const fit::Pca& pc) {
  Fit out;
  out.shape.type = ShapeType::cylinder;
  std::vector<AxisStart> starts;
  for (const Vector3d& a : candidate_axes(ns, pc, false)) {
    AxisStart st;
    if (circle_start(ns, a, st)) starts.push_back(st);
  }
  AxisStart best;
  if (starts.empty() || !refine_best<CylinderModel>(ns, columns, starts, best)) return out;
  return cylinder_fit(s, ns, best);
}

/// The cone fit of `s` from a refined axis start (normalised coordinates).
Fit cone_fit(const Samples& s, const Normalized& ns, const AxisStart& best) {
  Fit out;
  out.shape.type = ShapeType::cone;
  // Half angle into [0, π/2): the line at theta ± π is the same line, at −theta it is the same
  // line seen along −a.
  Vector3d a = best.a.normalized();
  double theta = best.theta - M_PI * std::round(best.theta / M_PI);
  if (theta < 0) {
    theta = -theta;
    a = -a;
  }
  const double t = std::tan(theta);
  if (!(t > 1e-9) || !std::isfinite(t)) return out;  // a cylinder: no apex
  const Vector3d apex = best.p - (best.r / t) * a;
  // The nappe holding the samples: a points from the apex into the opening.
  double side = 0;
  for (int i = 0; i < ns.size(); ++i) side += ns.w[i] * a.dot(ns.p[i] - apex);
  out.shape.point = ns.to_world(apex);
  out.shape.dir = side < 0 ? Vector3d(-a) : a;
  out.shape.half_angle_deg = theta * 180.0 / M_PI;
  fit::finish(out, s);
  return out;
}

/// The axis start of a fitted cylinder or cone in normalised coordinates: for a cone, the point
/// on the axis level with the samples' centroid (the origin) and the radius there.
bool axis_start_of(const Shape& shape, const Normalized& ns, AxisStart& out) {
  const Vector3d a = shape.dir.normalized();
  const Vector3d q = (shape.point - ns.center) / ns.scale;
  if (shape.type == ShapeType::cylinder) {
    out = {a, q, shape.radius / ns.scale, 0.0};
  } else {
    const double theta = shape.half_angle_deg * M_PI / 180.0;
    const double height = -a.dot(q);  // the centroid above the apex
    out = {a, q + height * a, height * std::tan(theta), theta};
  }
  return all_finite(out) && out.r > 0;
}

/// The cone fit of `s` from the robust starts on `ns`, whose principal axes are `pc`.
Fit cone_fit(const Samples& s, const Normalized& ns, const std::shared_ptr<const fit::SampleColumns>& columns,
             const fit::Pca& pc) {
  Fit out;
  out.shape.type = ShapeType::cone;
  std::vector<AxisStart> starts;
  AxisStart st;
  if (tangent_plane_cone_start(ns, st)) starts.push_back(st);
  for (const Vector3d& a : candidate_axes(ns, pc, true)) {
    if (algebraic_cone_start(ns, a, st)) starts.push_back(st);
    if (circle_start(ns, a, st)) starts.push_back(st);
  }
  AxisStart best;
  if (starts.empty() || !refine_best<ConeModel>(ns, columns, starts, best)) return out;
  return cone_fit(s, ns, best);
}

}  // namespace

namespace fit {

SurfaceFits::SurfaceFits(const Samples& s) : s_(s), n_(normalization(s)) {}

const Pca& SurfaceFits::principal_axes() const {
  std::call_once(pca_once_, [&] { pca_ = pca(n_.samples.p, n_.samples.w); });
  return pca_;
}

const std::shared_ptr<const SampleColumns>& SurfaceFits::columns() const {
  std::call_once(columns_once_, [&] { columns_ = std::make_shared<const SampleColumns>(n_.samples); });
  return columns_;
}

Fit SurfaceFits::fit(ShapeType type) const {
  Fit out;
  out.shape.type = type;
  const Normalized& ns = n_.samples;
  switch (type) {
    case ShapeType::plane: return n_.enough(3) ? plane_fit(s_) : out;
    case ShapeType::sphere: return n_.enough(4) ? sphere_fit(s_, ns, columns()) : out;
    case ShapeType::cylinder: return n_.enough(5) ? cylinder_fit(s_, ns, columns(), principal_axes()) : out;
    case ShapeType::cone: return n_.enough(6) ? cone_fit(s_, ns, columns(), principal_axes()) : out;
    default: return Fit{};
  }
}

Fit SurfaceFits::refit(const Shape& start) const {
  Fit out;
  out.shape.type = start.type;
  const Normalized& ns = n_.samples;
  switch (start.type) {
    case ShapeType::plane: return fit(ShapeType::plane);
    case ShapeType::sphere: {
      if (!n_.enough(4)) return out;
      const SphereModel m{&ns, (start.point - ns.center) / ns.scale, start.radius / ns.scale, columns()};
      return m.c.allFinite() && m.r > 0 ? sphere_fit(s_, ns, m) : out;
    }
    case ShapeType::cylinder:
    case ShapeType::cone: {
      const bool cone = start.type == ShapeType::cone;
      AxisStart st;
      if (!n_.enough(cone ? 6 : 5) || !axis_start_of(start, ns, st)) return out;
      if (cone ? !refine_from<ConeModel>(ns, columns(), st) : !refine_from<CylinderModel>(ns, columns(), st)) return out;
      return cone ? cone_fit(s_, ns, st) : cylinder_fit(s_, ns, st);
    }
    default: return out;
  }
}

}  // namespace fit

Fit fit_plane(const Samples& s) { return fit::SurfaceFits(s).fit(ShapeType::plane); }
Fit fit_sphere(const Samples& s) { return fit::SurfaceFits(s).fit(ShapeType::sphere); }
Fit fit_cylinder(const Samples& s) { return fit::SurfaceFits(s).fit(ShapeType::cylinder); }
Fit fit_cone(const Samples& s) { return fit::SurfaceFits(s).fit(ShapeType::cone); }
Fit refit_surface(const Samples& s, const Shape& start) { return fit::SurfaceFits(s).refit(start); }

}  // namespace s2c::features
