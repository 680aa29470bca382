// The analytic Jacobians of the surface models (fit_models.h) against central differences of
// their own residuals: a wrong derivative would still let Levenberg–Marquardt creep downhill, so
// only a direct comparison catches it.
#include <algorithm>
#include <cstring>
#include <random>
#include <set>

#include <gtest/gtest.h>

#include "fit_models.h"

namespace s2c::features::fit {
namespace {

/// Points scattered around (not on) a cone about a tilted axis, with weights not all 1.
Normalized noisy_samples(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Normalized s;
  for (int i = 0; i < n; ++i) {
    const double h = u(rng), phi = 3.0 * u(rng), rho = 0.8 + 0.3 * h + 0.05 * u(rng);
    s.p.emplace_back(rho * std::cos(phi), rho * std::sin(phi) + 0.1 * h, h);
    s.n.push_back(Vector3d::Zero());
    s.w.push_back(0.5 + 0.5 * (u(rng) + 1.0));
    s.sw.push_back(std::sqrt(s.w.back()));
  }
  return s;
}

template <class Model>
void expect_jacobian_matches_differences(const Model& m, double tol) {
  constexpr int k = Model::kParams;
  const int n = m.residual_count();
  Jacobian<k> J(n, k);
  m.jacobian(J);
  Eigen::VectorXd plus(n), minus(n);
  const double h = 1e-6;
  for (int j = 0; j < k; ++j) {
    typename Model::Vec d = Model::Vec::Zero();
    d[j] = h;
    m.residuals(d, plus);
    m.residuals(-d, minus);
    const Eigen::VectorXd numeric = (plus - minus) / (2 * h);
    EXPECT_LT((J.col(j) - numeric).cwiseAbs().maxCoeff(), tol) << "parameter " << j;
    EXPECT_GT(numeric.cwiseAbs().maxCoeff(), 1e-3) << "parameter " << j << " moves nothing: a weak test";
  }
}

TEST(FitModels, ConeJacobianMatchesFiniteDifferences) {
  const Normalized s = noisy_samples(300, 1);
  const ConeModel m(s, Vector3d(0.1, -0.2, 1.0), Vector3d(0.05, 0.02, 0.0), 0.75, 0.25);
  expect_jacobian_matches_differences(m, 1e-6);
}

TEST(FitModels, CylinderJacobianMatchesFiniteDifferences) {
  const Normalized s = noisy_samples(300, 2);
  const CylinderModel m(s, Vector3d(-0.1, 0.1, 1.0), Vector3d(0.0, 0.03, 0.0), 0.8, 0.0);
  expect_jacobian_matches_differences(m, 1e-6);
}

/// The axis models keep the geometry of their last residual pass for the Jacobian after the step
/// is taken: that Jacobian must be, to the bit, the one computed afresh at the new parameters,
/// also when a rejected trial came between (its geometry is for other parameters).
template <class Model>
void expect_jacobian_after_step_is_fresh(const Normalized& s, Model m, bool rejected_trial_between) {
  constexpr int k = Model::kParams;
  const int n = m.residual_count();
  typename Model::Vec step, other;
  for (int j = 0; j < k; ++j) step[j] = 0.01 * (j + 1), other[j] = -0.02 * (j + 1);
  Eigen::VectorXd r(n);
  m.residuals(step, r);
  if (rejected_trial_between) m.residuals(other, r);
  m.update(step);
  Jacobian<k> kept(n, k), fresh(n, k);
  m.jacobian(kept);
  Model again(s, m.a, m.p, m.r, m.theta);
  again.a = m.a;  // as it is: the constructor would normalise it once more
  again.uv = perpendicular_frame(again.a);
  again.jacobian(fresh);
  EXPECT_TRUE(kept == fresh) << "largest difference " << (kept - fresh).cwiseAbs().maxCoeff();
}

TEST(FitModels, JacobianAfterAStepIsTheOneComputedThere) {
  const Normalized s = noisy_samples(300, 5);
  for (const bool between : {false, true}) {
    expect_jacobian_after_step_is_fresh(s, ConeModel(s, Vector3d(0.1, -0.2, 1.0), Vector3d(0.05, 0.02, 0.0), 0.75, 0.25),
                                        between);
    expect_jacobian_after_step_is_fresh(s, CylinderModel(s, Vector3d(-0.1, 0.1, 1.0), Vector3d(0.0, 0.03, 0.0), 0.8, 0.0),
                                        between);
  }
}

TEST(FitModels, SphereJacobianMatchesFiniteDifferences) {
  const Normalized s = noisy_samples(300, 3);
  const SphereModel m{&s, Vector3d(0.1, 0.0, -0.1), 0.9};
  expect_jacobian_matches_differences(m, 1e-6);
}

TEST(FitModels, LevenbergMarquardtUsesTheAnalyticJacobian) {
  static_assert(has_jacobian<ConeModel>::value && has_jacobian<CylinderModel>::value &&
                has_jacobian<SphereModel>::value);
  static_assert(has_normal_equations<ConeModel>::value && has_normal_equations<CylinderModel>::value &&
                has_normal_equations<SphereModel>::value);
  // From a perturbed start the cone fit converges to the samples' cone (radius 0.8 at h = 0,
  // slope 0.3 → half angle atan 0.3, axis tilted by the 0.1 h shear).
  const Normalized s = noisy_samples(2000, 4);
  ConeModel m(s, Vector3d(0.2, 0.1, 1.0), Vector3d(0.1, -0.1, 0.0), 0.6, 0.1);
  const double before = [&] {
    Eigen::VectorXd r(m.residual_count());
    m.residuals(ConeModel::Vec::Zero(), r);
    return r.squaredNorm();
  }();
  const double after = levenberg_marquardt(m);
  EXPECT_LT(after, 0.05 * before);
}

/// Equal to the bit, NaN for NaN.
template <class A, class B>
bool same_bits(const A& a, const B& b) {
  if (a.size() != b.size()) return false;
  return std::memcmp(a.derived().data(), b.derived().data(), sizeof(double) * static_cast<std::size_t>(a.size())) == 0;
}

/// The axis model's passes four samples at a time (AVX) against its two-lane passes: residuals,
/// normal equations before and after a step, and whole refinements, to the bit, for sample counts
/// around the four-sample groups and the 32-sample blocks.
template <class Model>
void expect_avx_passes_give_the_same_bits(const Normalized& s) {
  constexpr int k = Model::kParams;
  Model avx(s, Vector3d(0.1, -0.2, 1.0), Vector3d(0.05, 0.02, 0.0), 0.75, k > 5 ? 0.25 : 0.0);
  Model lanes = avx;
  avx.avx = true;
  lanes.avx = false;
  typename Model::Vec step;
  for (int j = 0; j < k; ++j) step[j] = 0.01 * (j + 1);
  Eigen::VectorXd ra(s.size()), rl(s.size());
  Eigen::Matrix<double, k, k> Aa, Al;
  typename Model::Vec ga, gl;
  avx.residuals(Model::Vec::Zero(), ra);
  lanes.residuals(Model::Vec::Zero(), rl);
  EXPECT_TRUE(same_bits(ra, rl)) << s.size() << " samples: residuals";
  avx.normal_equations(ra, Aa, ga);
  lanes.normal_equations(rl, Al, gl);
  EXPECT_TRUE(same_bits(Aa, Al) && same_bits(ga, gl)) << s.size() << " samples: normal equations";
  avx.residuals(step, ra);
  lanes.residuals(step, rl);
  EXPECT_TRUE(same_bits(ra, rl)) << s.size() << " samples: residuals after a step";
  avx.update(step);  // the geometry of the residual pass is kept for the next normal equations
  lanes.update(step);
  avx.normal_equations(ra, Aa, ga);
  lanes.normal_equations(rl, Al, gl);
  EXPECT_TRUE(same_bits(Aa, Al) && same_bits(ga, gl)) << s.size() << " samples: normal equations after a step";
  const double ca = levenberg_marquardt(avx), cl = levenberg_marquardt(lanes);
  EXPECT_TRUE(ca == cl && avx.a == lanes.a && avx.p == lanes.p && avx.r == lanes.r && avx.theta == lanes.theta)
      << s.size() << " samples: refinement";
}

/// The same for the sphere (no geometry is kept between its passes).
void expect_sphere_avx_passes_give_the_same_bits(const Normalized& s) {
  SphereModel avx{&s, Vector3d(0.1, 0.0, -0.1), 0.9}, plain = avx;
  avx.avx = true;
  plain.avx = false;
  const SphereModel::Vec step(0.01, -0.02, 0.03, 0.04);
  Eigen::VectorXd ra(s.size()), rp(s.size());
  Eigen::Matrix4d Aa, Ap;
  SphereModel::Vec ga, gp;
  for (const SphereModel::Vec& d : {SphereModel::Vec(SphereModel::Vec::Zero()), step}) {
    avx.residuals(d, ra);
    plain.residuals(d, rp);
    EXPECT_TRUE(same_bits(ra, rp)) << s.size() << " samples: residuals";
  }
  avx.normal_equations(ra, Aa, ga);
  plain.normal_equations(rp, Ap, gp);
  EXPECT_TRUE(same_bits(Aa, Ap) && same_bits(ga, gp)) << s.size() << " samples: normal equations";
  const double ca = levenberg_marquardt(avx), cp = levenberg_marquardt(plain);
  EXPECT_TRUE(ca == cp && avx.c == plain.c && avx.r == plain.r) << s.size() << " samples: refinement";
}

TEST(FitModels, AvxPassesGiveTheTwoLanePassesBits) {
  if (!have_avx_passes()) GTEST_SKIP() << "this CPU has no AVX";
  for (const int n : {6, 7, 8, 9, 31, 32, 33, 37, 300}) {
    const Normalized s = noisy_samples(n, 10 + n);
    expect_avx_passes_give_the_same_bits<ConeModel>(s);
    expect_avx_passes_give_the_same_bits<CylinderModel>(s);
    expect_sphere_avx_passes_give_the_same_bits(s);
  }
}

/// fit::normal_equations against the plain sums, entry by entry in row order, to the bit.
template <int K>
void expect_normal_equations_are_row_sums(int m) {
  std::mt19937 rng(K * 100 + m);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Jacobian<K> J(m, K);
  Eigen::VectorXd r(m);
  for (int i = 0; i < m; ++i) {
    for (int c = 0; c < K; ++c) J(i, c) = u(rng);
    r[i] = u(rng);
  }
  Eigen::Matrix<double, K, K> A, plain = Eigen::Matrix<double, K, K>::Zero();
  Eigen::Matrix<double, K, 1> g, plain_g = Eigen::Matrix<double, K, 1>::Zero();
  normal_equations<K>(J.data(), r.data(), m, A, g);
  for (int i = 0; i < m; ++i)
    for (int a = 0; a < K; ++a) {
      for (int b = 0; b < K; ++b) plain(a, b) += J(i, a) * J(i, b);
      plain_g[a] += J(i, a) * r[i];
    }
  EXPECT_TRUE(same_bits(A, plain) && same_bits(g, plain_g)) << "K = " << K << ", " << m << " rows";
}

TEST(FitUtil, NormalEquationsAreTheRowSumsInOrder) {
  for (const int m : {1, 2, 5, 64}) {
    expect_normal_equations_are_row_sums<3>(m);
    expect_normal_equations_are_row_sums<4>(m);
    expect_normal_equations_are_row_sums<5>(m);
    expect_normal_equations_are_row_sums<6>(m);
  }
}

}  // namespace
}  // namespace s2c::features::fit

TEST(FitUtil, StratifiedPickCoversTheRangeWithoutAliasing) {
  EXPECT_EQ(s2c::features::fit::stratified_pick(5, 10), (std::vector<std::size_t>{0, 1, 2, 3, 4}));
  // 1000 rings of 96 vertices: a plain stride of 96 would pick one vertex of every ring, all at
  // the same angle (a cylinder seen as a straight line).
  const std::size_t n = 96 * 1000, max = 1000;
  const std::vector<std::size_t> pick = s2c::features::fit::stratified_pick(n, max);
  ASSERT_EQ(pick.size(), max);
  EXPECT_TRUE(std::is_sorted(pick.begin(), pick.end()));
  EXPECT_EQ(std::adjacent_find(pick.begin(), pick.end()), pick.end()) << "no index twice";
  EXPECT_LT(pick.front(), n / max);
  EXPECT_GE(pick.back(), n - n / max);
  std::set<std::size_t> angles;
  for (std::size_t i : pick) angles.insert(i % 96);
  EXPECT_GT(angles.size(), 48u);
  EXPECT_EQ(s2c::features::fit::stratified_pick(n, max), pick) << "deterministic";
}
