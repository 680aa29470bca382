#pragma once
/// \file Distances from points to a triangle surface (Embree BVH point queries), and a ray caster.
#include <memory>
#include <optional>
#include <vector>

#include <Eigen/Core>

#include "s2c/core/mesh.h"

namespace s2c {

/// Closest point on a triangle (Ericson, Real-Time Collision Detection 5.1.5).
Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a,
                                          const Eigen::Vector3d& b, const Eigen::Vector3d& c);

struct SurfacePoint {
  Eigen::Vector3d point;  ///< closest point on the surface
  int face = -1;          ///< the face it lies on
  double distance = 0;    ///< mm
};

/// A BVH over a triangle surface, built once, queried many times (thread-safe queries).
class SurfaceQuery {
 public:
  explicit SurfaceQuery(const TriangleSoup& soup);
  ~SurfaceQuery();
  SurfaceQuery(const SurfaceQuery&) = delete;
  SurfaceQuery& operator=(const SurfaceQuery&) = delete;

  /// Closest surface point within `max_distance` (mm); nullopt if none is that close.
  /// A bounded radius is much faster than an unbounded query.
  std::optional<SurfacePoint> closest(const Eigen::Vector3d& p, double max_distance = 1e30) const;

  /// Every face with a point within `radius` of p (unordered).
  std::vector<int> faces_within(const Eigen::Vector3d& p, double radius) const;

  struct Hit {
    double t = 0;  ///< distance along the (unit) direction, mm
    int face = -1;
    Eigen::Vector3d normal;  ///< unit geometric normal of the hit face (as stored, not flipped)
  };
  /// First hit of the ray origin + t·dir, t in [t_min, t_max]; `dir` must be unit length.
  std::optional<Hit> raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir, double t_min = 0,
                             double t_max = 1e30) const;

  const TriangleSoup& soup() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace s2c
