// fill_holes: per hole, choose a method, build the patch, validate it, fall back to the other
// method when it is invalid, and append it to the soup (see s2c/repair/fill.h).
#include "s2c/repair/fill.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <unordered_set>

#include <Eigen/Eigenvalues>

#include "fill/liepa.h"
#include "fill/patch.h"
#include "fill/patch_check.h"
#include "fill/rbf.h"

namespace s2c::repair {

const char* to_string(FillMethod m) {
  switch (m) {
    case FillMethod::automatic: return "auto";
    case FillMethod::rbf: return "rbf";
    case FillMethod::liepa: return "liepa";
  }
  return "?";
}

namespace {

using fill::HoleShape;
using fill::MeshIndex;
using fill::Patch;

constexpr double kPi = 3.14159265358979323846;

// The rim's plane, size and surroundings: everything the method choice looks at.
HoleShape analyse(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& loop,
                  const FillOptions& options) {
  HoleShape s;
  const int n = static_cast<int>(loop.size());
  double perimeter = 0;
  Eigen::Vector3d area = Eigen::Vector3d::Zero();  // vector area: its direction is the patch side
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d &a = soup.vertices[loop[i]], &b = soup.vertices[loop[(i + 1) % n]];
    perimeter += (b - a).norm();
    s.centroid += a / n;
    area += a.cross(b);
  }
  s.edge = options.edge_length > 0 ? options.edge_length : perimeter / n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int g : loop) {
    const Eigen::Vector3d d = soup.vertices[g] - s.centroid;
    cov += d * d.transpose();
    for (int h : loop) s.diameter = std::max(s.diameter, (soup.vertices[g] - soup.vertices[h]).squaredNorm());
  }
  s.diameter = std::sqrt(s.diameter);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d normal = eig.eigenvectors().col(0);
  if (normal.dot(area) < 0) normal = -normal;
  s.normal = normal;
  double worst = 0;
  for (int g : loop) worst = std::max(worst, std::abs((soup.vertices[g] - s.centroid).dot(normal)));
  s.planarity = s.diameter > 0 ? worst / s.diameter : 0;
  s.planar = s.planarity <= options.planar_tolerance;
  // Angle between the mesh faces on the rim and the rim plane (0°: flat ground, 90°: a wall).
  double sum = 0;
  int count = 0;
  for (int i = 0; i < n; ++i) {
    const int f = index.face_with(loop[(i + 1) % n], loop[i]);
    if (f < 0) continue;
    const auto& t = soup.faces[f];
    const Eigen::Vector3d nf = fill::unit_normal(soup.vertices[t[0]], soup.vertices[t[1]], soup.vertices[t[2]]);
    if (nf.squaredNorm() == 0) continue;
    sum += std::acos(std::clamp(nf.dot(normal), -1.0, 1.0)) * 180 / kPi;
    ++count;
  }
  s.wall_angle_deg = count ? sum / count : 0;
  s.flat_fill = s.planar && (s.wall_angle_deg < 10 || s.wall_angle_deg > 60);
  return s;
}

// Liepa's candidates, best first: the faired patch, then the refined one before fairing (its
// vertices are centroids of valid triangles, so it survives where fairing folds a patch).
bool build_liepa(const TriangleSoup& soup, const MeshIndex& index, Patch& p, const HoleShape& shape,
                 const FillOptions& options, std::vector<Patch>& out, std::string& why) {
  if (!fill::triangulate(soup, index, p, why) || !fill::refine(index, p, options.max_patch_vertices, why)) return false;
  Patch faired = p;
  if (fill::fair(soup, index, faired, !shape.flat_fill, why)) out.push_back(std::move(faired));
  out.push_back(std::move(p));
  if (shape.flat_fill) {
    // The flat fill is by definition in the rim plane; the sparse solve leaves ~1e-13 noise.
    for (auto& c : out)
      for (int l = c.rim_size(); l < c.size(); ++l)
        c.points[l] -= (c.points[l] - shape.centroid).dot(shape.normal) * shape.normal;
  }
  return true;
}

void commit(TriangleSoup& soup, MeshIndex& index, const Patch& p, FillResult& r) {
  const std::size_t first_face = soup.faces.size();
  const bool normals = !soup.normals.empty() && soup.normals.size() == soup.vertices.size();
  for (int l = p.rim_size(); l < p.size(); ++l) soup.vertices.push_back(p.points[l]);
  for (const auto& t : p.faces) soup.faces.push_back({p.global(t[0]), p.global(t[1]), p.global(t[2])});
  if (normals) {
    std::vector<Eigen::Vector3d> acc(static_cast<std::size_t>(p.size() - p.rim_size()), Eigen::Vector3d::Zero());
    for (const auto& t : p.faces) {
      const Eigen::Vector3d n = (p.points[t[1]] - p.points[t[0]]).cross(p.points[t[2]] - p.points[t[0]]);
      for (int c : t)
        if (c >= p.rim_size()) acc[c - p.rim_size()] += n;
    }
    for (auto& n : acc) soup.normals.push_back(n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : n);
  }
  index.add_faces(soup, first_face);
  r.filled = true;
  r.new_vertices = static_cast<std::size_t>(p.size() - p.rim_size());
  r.new_faces = p.faces.size();
}

// One hole: never throws (a failure leaves the hole open with the reason).
FillResult fill_one(TriangleSoup& soup, MeshIndex& index, const Hole& hole, const FillOptions& options) {
  FillResult r;
  const auto& loop = hole.loop;
  const int nv = static_cast<int>(soup.vertices.size());
  if (loop.size() < 3) {
    r.reason = "hole has fewer than 3 rim vertices";
    return r;
  }
  if (options.max_hole_vertices && loop.size() > options.max_hole_vertices) {
    r.reason = "hole has " + std::to_string(loop.size()) + " rim vertices, more than max_hole_vertices";
    return r;
  }
  for (std::size_t i = 0; i < loop.size(); ++i) {
    if (loop[i] < 0 || loop[i] >= nv) {
      r.reason = "rim vertex index " + std::to_string(loop[i]) + " out of range";
      return r;
    }
    if (loop[i] == loop[(i + 1) % loop.size()]) {
      r.reason = "rim repeats vertex " + std::to_string(loop[i]) + " on consecutive positions";
      return r;
    }
    if (!soup.vertices[loop[i]].allFinite()) {
      r.reason = "rim vertex " + std::to_string(loop[i]) + " has non-finite coordinates";
      return r;
    }
  }
  const auto make_patch = [&] {
    Patch p;
    p.rim = loop;
    p.base = nv;
    for (int g : loop) p.points.push_back(soup.vertices[g]);
    return p;
  };
  if (loop.size() == 3) {
    Patch p = make_patch();
    p.faces.push_back({0, 1, 2});
    r.method = FillMethod::liepa;
    r.choice = "3-vertex hole: one triangle";
    r.reason = fill::check_patch(soup, index, p);
    if (r.reason.empty()) commit(soup, index, p, r);
    return r;
  }
  const HoleShape shape = analyse(soup, index, loop, options);
  FillMethod first = options.method;
  if (first == FillMethod::automatic) {
    if (shape.flat_fill) {
      first = FillMethod::liepa;
      r.choice = "auto: planar rim (" + std::to_string(shape.planarity) + " of diameter), faces " +
                 std::to_string(int(std::lround(shape.wall_angle_deg))) + "° off its plane → liepa, flat";
    } else {
      first = FillMethod::rbf;
      r.choice = shape.planar ? "auto: planar rim on a curved surface → rbf" : "auto: curved rim → rbf";
    }
  } else {
    r.choice = std::string("requested ") + to_string(first);
  }
  const FillMethod second = first == FillMethod::rbf ? FillMethod::liepa : FillMethod::rbf;
  std::string reasons;
  for (const FillMethod m : {first, second}) {
    Patch p = make_patch();
    p.sigma.assign(loop.size(), shape.edge);
    std::string why;
    std::vector<Patch> candidates;
    try {
      if (m == FillMethod::liepa) {
        build_liepa(soup, index, p, shape, options, candidates, why);
      } else {
        fill::RbfStats stats;
        if (fill::rbf_fill(soup, index, p, shape, options, stats, why)) candidates.push_back(std::move(p));
        r.rbf_constraints = stats.constraints;
        r.rbf_solve_seconds = stats.solve_seconds;
      }
    } catch (const std::exception& e) {  // e.g. bad_alloc on an enormous hole
      why = e.what();
    }
    for (const Patch& c : candidates) {
      why = fill::check_patch(soup, index, c);
      if (!why.empty()) continue;
      r.method = m;
      if (m != first) r.choice += "; " + std::string(to_string(first)) + " failed (" + reasons + ") → " + to_string(m);
      if (&c != &candidates.front()) r.choice += " (unfaired: the faired patch was invalid)";
      r.reason.clear();
      commit(soup, index, c, r);
      return r;
    }
    reasons += (reasons.empty() ? "" : "; ") + std::string(to_string(m)) + ": " + why;
  }
  r.method = first;
  r.reason = reasons;
  return r;
}

}  // namespace

std::vector<FillResult> fill_holes(TriangleSoup& soup, const std::vector<Hole>& holes, const FillOptions& options) {
  MeshIndex index(soup);
  std::vector<FillResult> results;
  results.reserve(holes.size());
  for (const Hole& hole : holes) {
    const auto t0 = std::chrono::steady_clock::now();
    FillResult r = fill_one(soup, index, hole, options);
    r.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    results.push_back(std::move(r));
  }
  return results;
}

}  // namespace s2c::repair
