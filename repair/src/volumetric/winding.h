#pragma once
// Fast generalised winding number (Barill, Dickson, Schmidt, Levin, Jacobson 2018): exact solid
// angles of nearby triangles, a dipole (first-order) expansion for far clusters of a BVH.
// w(q) is 1 inside a closed outward-oriented surface and 0 outside; across a hole it changes
// smoothly, so w >= 1/2 closes holes and tolerates overlaps, duplicates and flipped patches.
#include <memory>

#include <Eigen/Core>

#include "s2c/core/mesh.h"

namespace s2c::repair {

class WindingNumber {
 public:
  /// \param beta accuracy: a cluster is expanded when the query is farther than beta × its radius.
  explicit WindingNumber(const TriangleSoup& soup, double beta = 2.0);
  ~WindingNumber();
  WindingNumber(const WindingNumber&) = delete;
  WindingNumber& operator=(const WindingNumber&) = delete;

  double operator()(const Eigen::Vector3d& q) const;  ///< thread-safe

 private:
  struct Tree;
  std::unique_ptr<Tree> tree_;
};

/// Solid angle of triangle (a, b, c) seen from q, divided by 4π (Van Oosterom & Strackee).
double triangle_winding(const Eigen::Vector3d& q, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const Eigen::Vector3d& c);

}  // namespace s2c::repair
