#include "arap.h"

#include <algorithm>
#include <cmath>
#include <unordered_map>

#include <Eigen/Dense>
#include <Eigen/SparseCholesky>
#include <tbb/parallel_for.h>

#include "s2c/core/errors.h"

namespace s2c::edit {

using Eigen::Matrix3d;
using Eigen::Vector3d;

struct ArapSolver::Impl {
  std::vector<std::array<int, 3>> faces;
  std::vector<int> unknowns;
  std::vector<int> verts;                     // region vertices (global), local index = position
  std::unordered_map<int, int> local;         // global → local
  std::vector<int> unknown_slot;              // local → index among unknowns, or -1
  // Symmetric edge list with weights, CSR by local vertex.
  std::vector<int> start, nbr;
  std::vector<double> weight;
  std::vector<Vector3d> rest;                 // local rest positions
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt;
};

namespace {

double cot(const Vector3d& a, const Vector3d& b) {
  const double s = a.cross(b).norm();
  return s > 0.0 ? a.dot(b) / s : 0.0;
}

// The closest rotation to the covariance S (Sorkine & Alexa: R = V Uᵀ of S = U Σ Vᵀ, reflection
// removed). Σ and V come from the closed-form eigen decomposition of SᵀS, U = S V Σ⁻¹ for the two
// largest singular values and u₃ = ±u₁ × u₂; a cell of coplanar edges (rank 2, every interior
// vertex of a plane) is handled exactly that way. Rank < 2 falls back to Jacobi SVD.
Matrix3d closest_rotation(const Matrix3d& s) {
  Eigen::SelfAdjointEigenSolver<Matrix3d> eig;
  eig.computeDirect(s.transpose() * s);
  const Eigen::Vector3d ev = eig.eigenvalues();  // ascending
  const Matrix3d& v = eig.eigenvectors();
  const double s1 = std::sqrt(std::max(ev(2), 0.0)), s2 = std::sqrt(std::max(ev(1), 0.0));
  if (s1 > 0.0 && s2 > 1e-6 * s1) {
    Matrix3d vv;
    vv << v.col(2), v.col(1), v.col(0);  // descending singular values
    Matrix3d u;
    u.col(0) = (s * vv.col(0) / s1).normalized();
    u.col(1) = s * vv.col(1) / s2;
    u.col(1) = (u.col(1) - u.col(1).dot(u.col(0)) * u.col(0)).normalized();
    u.col(2) = u.col(0).cross(u.col(1));
    // S v₃ = σ₃ u₃ with σ₃ ≥ 0; the cross product may point the other way, which flips det(U).
    if ((s * vv.col(2)).dot(u.col(2)) < 0.0) u.col(2) = -u.col(2);
    Matrix3d r = vv * u.transpose();
    if (r.determinant() < 0.0) {
      u.col(2) = -u.col(2);
      r = vv * u.transpose();
    }
    return r;
  }
  Eigen::JacobiSVD<Matrix3d> svd(s, Eigen::ComputeFullU | Eigen::ComputeFullV);
  Matrix3d u = svd.matrixU();
  Matrix3d r = svd.matrixV() * u.transpose();
  if (r.determinant() < 0.0) {
    u.col(2) *= -1.0;
    r = svd.matrixV() * u.transpose();
  }
  return r;
}

}  // namespace

ArapSolver::ArapSolver(const std::vector<Vector3d>& rest, const std::vector<std::array<int, 3>>& faces,
                       std::vector<int> unknowns)
    : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.faces = faces;
  m.unknowns = std::move(unknowns);
  for (const auto& f : faces)
    for (int v : f)
      if (m.local.emplace(v, static_cast<int>(m.verts.size())).second) m.verts.push_back(v);
  const int n = static_cast<int>(m.verts.size());
  m.rest.resize(n);
  for (int i = 0; i < n; ++i) m.rest[i] = rest[m.verts[i]];
  m.unknown_slot.assign(n, -1);
  for (std::size_t k = 0; k < m.unknowns.size(); ++k) {
    auto it = m.local.find(m.unknowns[k]);
    if (it == m.local.end()) throw ProcessingError("ARAP: an unknown vertex is not in the region's faces");
    m.unknown_slot[it->second] = static_cast<int>(k);
  }

  // Cotangent weights w_ij = ½ Σ cot of the angles opposite (i, j) within the region.
  std::unordered_map<std::uint64_t, double> w;
  w.reserve(faces.size() * 3);
  double mean_abs = 0.0;
  for (const auto& f : faces) {
    for (int c = 0; c < 3; ++c) {
      const int i = m.local[f[(c + 1) % 3]], j = m.local[f[(c + 2) % 3]];
      const Vector3d& pk = m.rest[m.local[f[c]]];
      const double ct = 0.5 * cot(m.rest[i] - pk, m.rest[j] - pk);
      const std::uint64_t key = i < j ? (std::uint64_t(i) << 32 | std::uint32_t(j)) : (std::uint64_t(j) << 32 | std::uint32_t(i));
      w[key] += ct;
      mean_abs += std::abs(ct);
    }
  }
  mean_abs /= std::max<std::size_t>(1, faces.size() * 3);
  // Negative cotangents (obtuse angles, common on CAD tessellations) make the Laplacian
  // indefinite; a small positive floor keeps it definite and hardly changes well-shaped regions.
  const double floor = std::max(1e-3 * mean_abs, 1e-9);
  std::vector<int> degree(n, 0);
  for (const auto& [key, value] : w) {
    ++degree[key >> 32];
    ++degree[key & 0xffffffffu];
  }
  m.start.assign(n + 1, 0);
  for (int i = 0; i < n; ++i) m.start[i + 1] = m.start[i] + degree[i];
  m.nbr.resize(m.start[n]);
  m.weight.resize(m.start[n]);
  std::vector<int> fill(m.start.begin(), m.start.end() - 1);
  for (const auto& [key, value] : w) {
    const int i = static_cast<int>(key >> 32), j = static_cast<int>(key & 0xffffffffu);
    const double wij = std::max(value, floor);
    m.nbr[fill[i]] = j;
    m.weight[fill[i]++] = wij;
    m.nbr[fill[j]] = i;
    m.weight[fill[j]++] = wij;
  }

  const int u = static_cast<int>(m.unknowns.size());
  if (u == 0) return;
  std::vector<Eigen::Triplet<double>> trip;
  trip.reserve(m.nbr.size() + u);
  for (int i = 0; i < n; ++i) {
    const int si = m.unknown_slot[i];
    if (si < 0) continue;
    double diag = 0.0;
    for (int e = m.start[i]; e < m.start[i + 1]; ++e) {
      diag += m.weight[e];
      const int sj = m.unknown_slot[m.nbr[e]];
      if (sj >= 0) trip.emplace_back(si, sj, -m.weight[e]);
    }
    trip.emplace_back(si, si, diag);
  }
  Eigen::SparseMatrix<double> a(u, u);
  a.setFromTriplets(trip.begin(), trip.end());
  m.ldlt.compute(a);
  if (m.ldlt.info() != Eigen::Success)
    throw ProcessingError("ARAP: the region's Laplacian cannot be factored (a free part touches no fixed vertex)");
}

ArapSolver::~ArapSolver() = default;

const std::vector<int>& ArapSolver::unknowns() const { return impl_->unknowns; }
const std::vector<std::array<int, 3>>& ArapSolver::faces() const { return impl_->faces; }

ArapStats ArapSolver::solve(std::vector<Vector3d>& positions, int max_iterations, double tolerance, bool warm) const {
  const Impl& m = *impl_;
  ArapStats stats;
  const int n = static_cast<int>(m.verts.size());
  const int u = static_cast<int>(m.unknowns.size());
  if (u == 0) return stats;
  std::vector<Vector3d> p(n);
  for (int i = 0; i < n; ++i) p[i] = positions[m.verts[i]];
  std::vector<Matrix3d> rot(n, Matrix3d::Identity());
  Eigen::MatrixXd rhs(u, 3), x(u, 3);
  double previous = -1.0;
  for (int it = 0; it < max_iterations; ++it) {
    // Local step: the best rotation of every cell. From a cold start the first iteration keeps
    // R = I: the Laplacian solve spreads the handles' displacement smoothly, where the rotations of
    // the undeformed interior against moved handles would start from folded cells.
    if (it > 0 || warm) tbb::parallel_for(0, n, [&](int i) {
      Matrix3d s = Matrix3d::Zero();
      for (int e = m.start[i]; e < m.start[i + 1]; ++e) {
        const int j = m.nbr[e];
        s += m.weight[e] * (m.rest[i] - m.rest[j]) * (p[i] - p[j]).transpose();
      }
      rot[i] = closest_rotation(s);
    });
    // Global step: L x = b with the constraints moved to the right-hand side.
    tbb::parallel_for(0, n, [&](int i) {
      const int si = m.unknown_slot[i];
      if (si < 0) return;
      Vector3d b = Vector3d::Zero();
      for (int e = m.start[i]; e < m.start[i + 1]; ++e) {
        const int j = m.nbr[e];
        b += 0.5 * m.weight[e] * (rot[i] + rot[j]) * (m.rest[i] - m.rest[j]);
        if (m.unknown_slot[j] < 0) b += m.weight[e] * p[j];
      }
      rhs.row(si) = b.transpose();
    });
    // The three coordinates are independent solves with one factorisation: one per core.
    tbb::parallel_for(0, 3, [&](int c) { x.col(c) = m.ldlt.solve(rhs.col(c)); });
    for (int i = 0; i < n; ++i)
      if (m.unknown_slot[i] >= 0) p[i] = x.row(m.unknown_slot[i]).transpose();
    // Energy after the step (with the rotations of this iteration): for the stopping test.
    double energy = 0.0;
    for (int i = 0; i < n; ++i)
      for (int e = m.start[i]; e < m.start[i + 1]; ++e) {
        const int j = m.nbr[e];
        energy += m.weight[e] * ((p[i] - p[j]) - rot[i] * (m.rest[i] - m.rest[j])).squaredNorm();
      }
    stats.iterations = it + 1;
    stats.energy = energy;
    if (previous >= 0.0 && std::abs(previous - energy) <= tolerance * std::max(previous, 1e-30)) break;
    if (energy <= 1e-24) break;
    previous = energy;
  }
  for (int i = 0; i < n; ++i)
    if (m.unknown_slot[i] >= 0) positions[m.verts[i]] = p[i];
  return stats;
}

}  // namespace s2c::edit
