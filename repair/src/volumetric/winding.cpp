#include "volumetric/winding.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

namespace s2c::repair {

double triangle_winding(const Eigen::Vector3d& q, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                        const Eigen::Vector3d& c) {
  const Eigen::Vector3d x = a - q, y = b - q, z = c - q;
  const double lx = x.norm(), ly = y.norm(), lz = z.norm();
  const double num = x.dot(y.cross(z));
  const double den = lx * ly * lz + x.dot(y) * lz + y.dot(z) * lx + z.dot(x) * ly;
  return std::atan2(num, den) / (2 * M_PI);  // Ω = 2·atan2(num, den); w = Ω / 4π
}

struct WindingNumber::Tree {
  struct Node {
    Eigen::Vector3d center = Eigen::Vector3d::Zero();  // area-weighted centroid of its triangles
    Eigen::Vector3d dipole = Eigen::Vector3d::Zero();  // Σ area·normal
    double radius = 0;                                 // farthest corner from `center`
    int first = 0, count = 0;                          // triangle range (leaves)
    int left = -1, right = -1;
  };
  const TriangleSoup* soup = nullptr;
  std::vector<int> order;  // triangle ids, leaves reference contiguous ranges
  std::vector<Node> nodes;
  std::vector<Eigen::Vector3d> centroid;
  double beta = 2;

  int build(int first, int count) {
    const int id = static_cast<int>(nodes.size());
    nodes.emplace_back();
    Node node;
    node.first = first;
    node.count = count;
    double area_sum = 0;
    Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
    for (int i = first; i < first + count; ++i) {
      const auto& f = soup->faces[order[i]];
      const Eigen::Vector3d n2 = (soup->vertices[f[1]] - soup->vertices[f[0]])
                                     .cross(soup->vertices[f[2]] - soup->vertices[f[0]]);
      const double area = 0.5 * n2.norm();
      node.dipole += 0.5 * n2;
      node.center += area * centroid[order[i]];
      area_sum += area;
      lo = lo.cwiseMin(centroid[order[i]]);
      hi = hi.cwiseMax(centroid[order[i]]);
    }
    node.center = area_sum > 0 ? Eigen::Vector3d(node.center / area_sum) : Eigen::Vector3d(0.5 * (lo + hi));
    for (int i = first; i < first + count; ++i)
      for (int k = 0; k < 3; ++k)
        node.radius = std::max(node.radius, (soup->vertices[soup->faces[order[i]][k]] - node.center).norm());
    if (count > 8) {
      int axis;
      (hi - lo).maxCoeff(&axis);
      const int mid = first + count / 2;
      std::nth_element(order.begin() + first, order.begin() + mid, order.begin() + first + count,
                       [&](int a, int b) { return centroid[a][axis] < centroid[b][axis]; });
      node.left = build(first, mid - first);
      node.right = build(mid, first + count - mid);
    }
    nodes[id] = node;
    return id;
  }

  double eval(int id, const Eigen::Vector3d& q) const {
    const Node& node = nodes[id];
    const Eigen::Vector3d r = node.center - q;
    const double d = r.norm();
    if (d > beta * node.radius) return node.dipole.dot(r) / (4 * M_PI * d * d * d);
    if (node.left < 0) {
      double w = 0;
      for (int i = node.first; i < node.first + node.count; ++i) {
        const auto& f = soup->faces[order[i]];
        w += triangle_winding(q, soup->vertices[f[0]], soup->vertices[f[1]], soup->vertices[f[2]]);
      }
      return w;
    }
    return eval(node.left, q) + eval(node.right, q);
  }
};

WindingNumber::WindingNumber(const TriangleSoup& soup, double beta) : tree_(std::make_unique<Tree>()) {
  auto& t = *tree_;
  t.soup = &soup;
  t.beta = beta;
  t.order.resize(soup.faces.size());
  std::iota(t.order.begin(), t.order.end(), 0);
  t.centroid.resize(soup.faces.size());
  for (std::size_t i = 0; i < soup.faces.size(); ++i) {
    const auto& f = soup.faces[i];
    t.centroid[i] = (soup.vertices[f[0]] + soup.vertices[f[1]] + soup.vertices[f[2]]) / 3.0;
  }
  t.nodes.reserve(2 * soup.faces.size() / 4 + 1);
  if (!soup.faces.empty()) t.build(0, static_cast<int>(soup.faces.size()));
}

WindingNumber::~WindingNumber() = default;

double WindingNumber::operator()(const Eigen::Vector3d& q) const {
  return tree_->nodes.empty() ? 0.0 : tree_->eval(0, q);
}

}  // namespace s2c::repair
