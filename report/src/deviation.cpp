#include "s2c/report/deviation.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

#include <tbb/parallel_for.h>

#include "s2c/core/distance.h"
#include "s2c/core/errors.h"
#include "soup_util.h"

namespace s2c::report {
namespace {

/// Angle-weighted vertex normals, summed edge normals and face normals of the reference: the
/// pseudo-normal of a closest point is the one of the feature (face, edge, vertex) it lies on.
struct PseudoNormals {
  std::vector<Eigen::Vector3d> face, vertex;
  std::unordered_map<std::uint64_t, Eigen::Vector3d> edge;

  explicit PseudoNormals(const TriangleSoup& s) : face(s.faces.size()), vertex(s.vertices.size(), Eigen::Vector3d::Zero()) {
    for (std::size_t f = 0; f < s.faces.size(); ++f) {
      const auto& t = s.faces[f];
      const Eigen::Vector3d n = (s.vertices[t[1]] - s.vertices[t[0]]).cross(s.vertices[t[2]] - s.vertices[t[0]]);
      face[f] = n.norm() > 0 ? n.normalized() : Eigen::Vector3d::Zero();
      for (int k = 0; k < 3; ++k) {
        const Eigen::Vector3d e1 = s.vertices[t[(k + 1) % 3]] - s.vertices[t[k]];
        const Eigen::Vector3d e2 = s.vertices[t[(k + 2) % 3]] - s.vertices[t[k]];
        const double denom = e1.norm() * e2.norm();
        const double angle = denom > 0 ? std::acos(std::clamp(e1.dot(e2) / denom, -1.0, 1.0)) : 0.0;
        vertex[t[k]] += angle * face[f];
        auto [it, fresh] = edge.try_emplace(undirected_edge_key(t[k], t[(k + 1) % 3]), Eigen::Vector3d::Zero());
        it->second += face[f];
      }
    }
  }

  /// The pseudo-normal at closest point q on face f.
  Eigen::Vector3d at(const TriangleSoup& s, int f, const Eigen::Vector3d& q) const {
    const auto& t = s.faces[f];
    const Eigen::Vector3d a = s.vertices[t[0]], b = s.vertices[t[1]], c = s.vertices[t[2]];
    // Barycentric coordinates of q; a coordinate near 0 puts q on the opposite edge.
    const Eigen::Vector3d v0 = b - a, v1 = c - a, v2 = q - a;
    const double d00 = v0.dot(v0), d01 = v0.dot(v1), d11 = v1.dot(v1), d20 = v2.dot(v0), d21 = v2.dot(v1);
    const double denom = d00 * d11 - d01 * d01;
    if (!(denom > 0)) return face[f];
    const double w1 = (d11 * d20 - d01 * d21) / denom, w2 = (d00 * d21 - d01 * d20) / denom;
    const double w[3] = {1 - w1 - w2, w1, w2};
    constexpr double eps = 1e-7;
    const int zeros = (w[0] < eps) + (w[1] < eps) + (w[2] < eps);
    if (zeros >= 2) {  // a corner: the one coordinate that is not 0
      for (int k = 0; k < 3; ++k)
        if (w[k] >= eps) return vertex[t[k]];
    }
    if (zeros == 1) {
      for (int k = 0; k < 3; ++k)
        if (w[k] < eps) {
          auto it = edge.find(undirected_edge_key(t[(k + 1) % 3], t[(k + 2) % 3]));
          if (it != edge.end()) return it->second;
        }
    }
    return face[f];
  }
};

}  // namespace

Deviation signed_deviation(const TriangleSoup& measured, const TriangleSoup& reference) {
  if (reference.faces.empty()) throw InvalidInput("the reference part has no faces");
  const SurfaceQuery query(reference);
  const PseudoNormals normals(reference);
  Deviation d;
  const std::size_t n = measured.vertices.size();
  d.distance.assign(n, std::numeric_limits<double>::quiet_NaN());
  d.weight.assign(n, 0.0);
  std::vector<char> used(n, 0);
  for (std::size_t f = 0; f < measured.faces.size(); ++f) {
    const double area = face_area(measured, f);
    for (int v : measured.faces[f]) {
      d.weight[v] += area / 3;
      used[v] = 1;
    }
  }
  // An inward-oriented reference (some exports are) would flip every sign: "outside" follows
  // the enclosed volume's sign instead of the file's winding.
  const double orientation = signed_volume6(reference) < 0 ? -1.0 : 1.0;
  tbb::parallel_for(std::size_t(0), n, [&](std::size_t v) {
    if (!used[v]) return;
    const auto hit = query.closest(measured.vertices[v]);
    if (!hit) return;
    const Eigen::Vector3d offset = measured.vertices[v] - hit->point;
    const double side = orientation * offset.dot(normals.at(reference, hit->face, hit->point));
    d.distance[v] = side < 0 ? -hit->distance : hit->distance;
  });

  DeviationStats& s = d.stats;
  s.min = std::numeric_limits<double>::infinity();
  s.max = -s.min;
  std::vector<std::pair<double, double>> by_abs;  // (|distance|, weight) for the percentile
  double sum = 0, sum_abs = 0, sum_sq = 0;
  for (std::size_t v = 0; v < n; ++v) {
    if (!std::isfinite(d.distance[v])) continue;
    const double x = d.distance[v], w = d.weight[v];
    ++s.vertices;
    s.area += w;
    sum += w * x;
    sum_abs += w * std::abs(x);
    sum_sq += w * x * x;
    s.min = std::min(s.min, x);
    s.max = std::max(s.max, x);
    by_abs.emplace_back(std::abs(x), w);
  }
  if (s.vertices == 0 || !(s.area > 0)) throw InvalidInput("the measured mesh has no faces with area to compare");
  s.mean = sum / s.area;
  s.mean_abs = sum_abs / s.area;
  s.rms = std::sqrt(sum_sq / s.area);
  s.max_abs = std::max(std::abs(s.min), std::abs(s.max));
  std::sort(by_abs.begin(), by_abs.end());
  double acc = 0;
  for (const auto& [x, w] : by_abs) {
    acc += w;
    s.p95_abs = x;
    if (acc >= 0.95 * s.area) break;
  }
  return d;
}

Colour deviation_colour(double distance, double range) {
  // Stops of the scale at t = 0, .25, .5, .75, 1 (t = 0.5 is zero deviation).
  static const Colour stops[5] = {{0.10f, 0.20f, 0.95f}, {0.10f, 0.80f, 0.95f}, {0.15f, 0.80f, 0.25f},
                                  {0.98f, 0.88f, 0.10f}, {0.92f, 0.12f, 0.10f}};
  if (!std::isfinite(distance)) return Colour(0.5f, 0.5f, 0.5f);
  const double t = std::clamp(0.5 + 0.5 * distance / std::max(range, 1e-12), 0.0, 1.0);
  const double x = t * 4;
  const int i = std::min(3, int(x));
  const float f = float(x - i);
  return (1 - f) * stops[i] + f * stops[i + 1];
}

double default_range(const DeviationStats& stats) {
  const double want = std::max(1.25 * stats.p95_abs, 0.001);
  double decade = std::pow(10.0, std::floor(std::log10(want)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * decade >= want * (1 - 1e-9)) return m * decade;
  return 10 * decade;
}

std::vector<double> histogram(const Deviation& d, double range, int bins) {
  bins = std::clamp(bins, 1, 10000);
  std::vector<double> h(std::size_t(bins) + 2, 0.0);
  if (!(d.stats.area > 0) || !(std::isfinite(range) && range > 0)) return h;
  for (std::size_t v = 0; v < d.distance.size(); ++v) {
    const double x = d.distance[v];
    if (!std::isfinite(x)) continue;
    std::size_t slot;
    if (x < -range)
      slot = 0;
    else if (x > range)
      slot = std::size_t(bins) + 1;
    else
      slot = 1 + std::size_t(std::clamp((x + range) / (2 * range) * bins, 0.0, bins - 1.0));
    h[slot] += d.weight[v] / d.stats.area;
  }
  return h;
}

}  // namespace s2c::report
