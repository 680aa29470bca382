#include "common/sampling.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <thread>

#include "s2c/core/errors.h"

namespace s2c::bench {

using Eigen::Vector3d;

// `n` points uniformly distributed by area over the soup's triangles.
Samples sample_surface(const TriangleSoup& soup, std::size_t n, std::uint64_t seed) {
  Samples out;
  std::vector<double> cdf(soup.faces.size());
  double total = 0;
  for (std::size_t f = 0; f < soup.faces.size(); ++f) {
    const auto& t = soup.faces[f];
    const Vector3d &a = soup.vertices[t[0]], &b = soup.vertices[t[1]], &c = soup.vertices[t[2]];
    total += 0.5 * (b - a).cross(c - a).norm();
    cdf[f] = total;
  }
  out.area = total;
  if (total <= 0) throw InvalidInput("the mesh has zero area");
  Rng rng{seed};
  out.points.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const double r = rng.uniform() * total;
    std::size_t f = static_cast<std::size_t>(std::upper_bound(cdf.begin(), cdf.end(), r) - cdf.begin());
    f = std::min(f, cdf.size() - 1);
    const auto& t = soup.faces[f];
    const double s = std::sqrt(rng.uniform()), u = rng.uniform();
    const Vector3d &a = soup.vertices[t[0]], &b = soup.vertices[t[1]], &c = soup.vertices[t[2]];
    out.points.push_back((1 - s) * a + s * (1 - u) * b + s * u * c);
  }
  return out;
}

// Distance of every point to the surface (unbounded queries), on all cores.
// Also returns the closest points (on the queried surface).
std::vector<double> distances(const SurfaceQuery& q, const std::vector<Vector3d>& pts,
                              std::vector<Vector3d>* closest) {
  std::vector<double> d(pts.size(), 0.0);
  if (closest) closest->assign(pts.size(), Vector3d::Zero());
  const unsigned nt = std::max(1u, std::thread::hardware_concurrency());
  std::vector<std::thread> threads;
  for (unsigned t = 0; t < nt; ++t)
    threads.emplace_back([&, t] {
      for (std::size_t i = t; i < pts.size(); i += nt) {
        const auto hit = q.closest(pts[i]);
        d[i] = hit ? hit->distance : std::numeric_limits<double>::infinity();
        if (closest && hit) (*closest)[i] = hit->point;
      }
    });
  for (auto& th : threads) th.join();
  return d;
}


SurfaceDistance surface_distance(const TriangleSoup& a, const TriangleSoup& b, std::size_t n, std::uint64_t seed) {
  const Samples sa = sample_surface(a, n, seed), sb = sample_surface(b, n, seed + 1);
  const SurfaceQuery qa(a), qb(b);
  const std::vector<double> dab = distances(qb, sa.points), dba = distances(qa, sb.points);
  SurfaceDistance r;
  for (double d : dab) r.mean_ab += d / double(dab.size());
  for (double d : dba) r.mean_ba += d / double(dba.size());
  r.chamfer = 0.5 * (r.mean_ab + r.mean_ba);
  r.hausdorff = std::max(*std::max_element(dab.begin(), dab.end()), *std::max_element(dba.begin(), dba.end()));
  return r;
}

}  // namespace s2c::bench
