// Liepa's hole filling: minimum-weight triangulation, refinement, fairing (see liepa.h).
#include "fill/liepa.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <unordered_map>
#include <unordered_set>

#include <Eigen/LU>
#include <Eigen/Sparse>
#include <Eigen/SparseCholesky>
#include <Eigen/SparseLU>

#include "fill/local_ids.h"

namespace s2c::repair::fill {
namespace {

// ---------------------------------------------------------------------------------------------
// Triangulation

// Liepa's weight: the largest dihedral angle first, then the area. The angle is kept as
// 1 - cos (monotone in the angle, no acos in the O(n³) loop). Angles closer than kAngleTie are
// treated as equal so that rounding noise on a flat hole (all angles ~1e-16) does not override
// the area term, which would pick slivers.
struct Weight {
  double angle = std::numeric_limits<double>::infinity();
  double area = 0;
  bool valid() const { return std::isfinite(angle); }
};
constexpr double kAngleTie = 1e-9;
bool better(const Weight& a, const Weight& b) {
  if (!b.valid()) return a.valid();
  if (!a.valid()) return false;
  if (std::abs(a.angle - b.angle) > kAngleTie) return a.angle < b.angle;
  return a.area < b.area;
}
double bend(const Eigen::Vector3d& n, const Eigen::Vector3d& m) {
  return m.squaredNorm() == 0 ? 0.0 : 1.0 - n.dot(m);  // no neighbour known: no penalty
}

// One polygon for the dynamic program: local patch indices in loop order, and per polygon edge
// (poly[e], poly[e+1], the last one closing) the unit normal of the mesh face across it.
struct Polygon {
  std::vector<int> corners;
  std::vector<Eigen::Vector3d> across;
};

// A triangle is usable when its three soup vertices differ and it is not a sliver: twice its
// area must exceed 1e-12 of its longest edge squared (exact zero area included).
bool usable(const Patch& p, int a, int b, int c, Eigen::Vector3d& normal, double& area) {
  if (p.global(a) == p.global(b) || p.global(b) == p.global(c) || p.global(a) == p.global(c)) return false;
  const Eigen::Vector3d &A = p.points[a], &B = p.points[b], &C = p.points[c];
  const Eigen::Vector3d n = (B - A).cross(C - A);
  const double twice = n.norm();
  const double longest = std::max({(B - A).squaredNorm(), (C - B).squaredNorm(), (A - C).squaredNorm()});
  if (!(twice > 1e-12 * longest)) return false;
  normal = n / twice;
  area = 0.5 * twice;
  return true;
}

bool triangulate_dp(const MeshIndex& index, const Polygon& poly, Patch& patch, std::string& why) {
  const int m = static_cast<int>(poly.corners.size());
  const auto at = [m](int i, int j) { return static_cast<std::size_t>(i) * m + j; };
  std::vector<Weight> w(static_cast<std::size_t>(m) * m);
  std::vector<int> apex(static_cast<std::size_t>(m) * m, -1);
  std::vector<Eigen::Vector3d> best_normal(static_cast<std::size_t>(m) * m, Eigen::Vector3d::Zero());
  for (int i = 0; i + 1 < m; ++i) w[at(i, i + 1)] = Weight{0, 0};
  const auto g = [&](int i) { return patch.global(poly.corners[i]); };
  // Normal of the triangle across the sub-polygon edge (i, k): the mesh face for a polygon edge,
  // else the best triangle of the sub-polygon i..k.
  const auto across = [&](int i, int k) { return k == i + 1 ? poly.across[i] : best_normal[at(i, k)]; };
  for (int len = 2; len < m; ++len) {
    for (int i = 0; i + len < m; ++i) {
      const int j = i + len;
      // (i, j) becomes an interior edge unless it is the closing polygon edge.
      if (len < m - 1 && (g(i) == g(j) || index.has_edge(g(i), g(j)))) continue;
      Weight best;
      int best_k = -1;
      Eigen::Vector3d best_n = Eigen::Vector3d::Zero();
      for (int k = i + 1; k < j; ++k) {
        const Weight &a = w[at(i, k)], &b = w[at(k, j)];
        if (!a.valid() || !b.valid()) continue;
        // The angle term only grows and decides first: a split already worse than the best
        // one cannot win, whatever its triangle (skips most of the O(m³) triangle work).
        if (best.valid() && std::max(a.angle, b.angle) > best.angle + kAngleTie) continue;
        Eigen::Vector3d n;
        double area;
        if (!usable(patch, poly.corners[i], poly.corners[k], poly.corners[j], n, area)) continue;
        Weight c{std::max({a.angle, b.angle, bend(n, across(i, k)), bend(n, across(k, j))}), a.area + b.area + area};
        if (len == m - 1) c.angle = std::max(c.angle, bend(n, poly.across[m - 1]));
        if (better(c, best)) {
          best = c;
          best_k = k;
          best_n = n;
        }
      }
      w[at(i, j)] = best;
      apex[at(i, j)] = best_k;
      best_normal[at(i, j)] = best_n;
    }
  }
  if (apex[at(0, m - 1)] < 0) {
    why = "no triangulation of the hole polygon without degenerate or duplicate elements";
    return false;
  }
  std::vector<std::pair<int, int>> stack{{0, m - 1}};
  while (!stack.empty()) {
    const auto [i, j] = stack.back();
    stack.pop_back();
    if (j - i < 2) continue;
    const int k = apex[at(i, j)];
    patch.faces.push_back({poly.corners[i], poly.corners[k], poly.corners[j]});
    stack.push_back({i, k});
    stack.push_back({k, j});
  }
  return true;
}

// Cuts a polygon larger than the limit at the shortest chord that leaves at least a quarter of
// the corners on each side and is a legal new edge; recurses on both halves. The chord's
// neighbour normal is unknown to each half (no dihedral term there).
bool triangulate_large(const MeshIndex& index, const Polygon& poly, Patch& patch, std::size_t limit,
                       std::string& why, int depth) {
  const int m = static_cast<int>(poly.corners.size());
  if (static_cast<std::size_t>(m) <= limit) return triangulate_dp(index, poly, patch, why);
  if (depth > 64) {
    why = "hole polygon could not be cut into pieces";
    return false;
  }
  const int quarter = std::max(2, m / 4);
  double best = std::numeric_limits<double>::infinity();
  int ba = -1, bb = -1;
  for (int a = 0; a < m; ++a) {
    const int ga = patch.global(poly.corners[a]);
    for (int b = a + quarter; b <= a + m - quarter && b < m; ++b) {
      const int gb = patch.global(poly.corners[b]);
      const double d = (patch.points[poly.corners[a]] - patch.points[poly.corners[b]]).squaredNorm();
      if (d < best && ga != gb && !index.has_edge(ga, gb)) {
        best = d;
        ba = a;
        bb = b;
      }
    }
  }
  if (ba < 0) {
    why = "no chord to split the large hole polygon";
    return false;
  }
  Polygon first, second;
  for (int i = ba; i <= bb; ++i) {
    first.corners.push_back(poly.corners[i]);
    first.across.push_back(i < bb ? poly.across[i] : Eigen::Vector3d::Zero());
  }
  for (int s = 0; s <= m - (bb - ba); ++s) {
    const int i = (bb + s) % m;
    second.corners.push_back(poly.corners[i]);
    second.across.push_back(i != ba ? poly.across[i] : Eigen::Vector3d::Zero());
  }
  return triangulate_large(index, first, patch, limit, why, depth + 1) &&
         triangulate_large(index, second, patch, limit, why, depth + 1);
}

// ---------------------------------------------------------------------------------------------
// Refinement: a small edge-based structure over the patch's local indices.

class PatchTopology {
 public:
  PatchTopology(const MeshIndex& index, Patch& patch) : index_(index), p_(patch) {
    for (int f = 0; f < static_cast<int>(p_.faces.size()); ++f) link_face(f);
  }

  void split(int f, const Eigen::Vector3d& c, double sigma) {
    const int v = p_.size();
    p_.points.push_back(c);
    p_.sigma.push_back(sigma);
    const auto [i, j, k] = p_.faces[f];
    const int g1 = static_cast<int>(p_.faces.size()), g2 = g1 + 1;
    p_.faces[f] = {i, j, v};
    p_.faces.push_back({j, k, v});
    p_.faces.push_back({k, i, v});
    replace(j, k, f, g1);
    replace(k, i, f, g2);
    edges_[edge_key(i, v)] = {f, g2};
    edges_[edge_key(j, v)] = {f, g1};
    edges_[edge_key(k, v)] = {g1, g2};
    for (int a : {i, j, k}) ++global_edges_[edge_key(p_.global(a), p_.global(v))];
  }

  // Flips edge (a, b) when the two opposite angles sum to more than π (not locally Delaunay)
  // and the flip is legal: the new edge is new in the mesh and the patch, and the two new
  // triangles are neither slivers nor folded onto each other.
  bool relax(int a, int b) {
    const auto it = edges_.find(edge_key(a, b));
    if (it == edges_.end() || it->second[1] < 0) return false;  // rim edge
    int f1 = it->second[0], f2 = it->second[1];
    if (corner_after(f1, a) != b) std::swap(f1, f2);  // f1 holds a→b
    if (corner_after(f1, a) != b || corner_after(f2, b) != a) return false;
    const int c = corner_after(f1, b), d = corner_after(f2, a);
    const Eigen::Vector3d &A = p_.points[a], &B = p_.points[b], &C = p_.points[c], &D = p_.points[d];
    if (!opposite_angles_exceed_pi(A - C, B - C, A - D, B - D)) return false;
    const int gc = p_.global(c), gd = p_.global(d);
    if (gc == gd || index_.has_edge(gc, gd) || global_edges_.count(edge_key(gc, gd))) return false;
    const Eigen::Vector3d n1 = (A - C).cross(D - C), n2 = (B - D).cross(C - D);
    const double l1 = n1.norm(), l2 = n2.norm();
    if (!(l1 > 1e-12 * (C - D).squaredNorm()) || !(l2 > 1e-12 * (C - D).squaredNorm())) return false;
    if (n1.dot(n2) <= 0.5 * l1 * l2) return false;  // would fold by more than 60°
    p_.faces[f1] = {c, a, d};
    p_.faces[f2] = {d, b, c};
    edges_.erase(it);
    edges_[edge_key(c, d)] = {f1, f2};
    replace(a, d, f2, f1);
    replace(b, c, f1, f2);
    auto ge = global_edges_.find(edge_key(p_.global(a), p_.global(b)));
    if (ge != global_edges_.end() && --ge->second == 0) global_edges_.erase(ge);
    ++global_edges_[edge_key(gc, gd)];
    queue_.insert(queue_.end(), {{a, d}, {d, b}, {b, c}, {c, a}});
    return true;
  }

  // Relaxes until no edge flips (bounded: Delaunay flips terminate on a plane; the cap guards
  // against cycling on curved patches).
  void relax_all(std::vector<std::pair<int, int>> seeds) {
    queue_.assign(seeds.begin(), seeds.end());
    std::size_t budget = 50 * (p_.faces.size() + 10);
    while (!queue_.empty() && budget-- > 0) {
      const auto [a, b] = queue_.front();
      queue_.pop_front();
      relax(a, b);
    }
    queue_.clear();
  }

  std::vector<std::pair<int, int>> interior_edges() const {
    std::vector<std::pair<int, int>> out;
    for (const auto& [key, faces] : edges_)
      if (faces[1] >= 0) out.push_back({int(key >> 32), int(key & 0xffffffffu)});
    return out;
  }

 private:
  // Whether the angle between u and v plus the one between u2 and v2 exceeds π (by more than
  // 1e-9): both lie in [0, π], so their sum does exactly when its sine is negative, and
  // sin(α + β) = sin α cos β + cos α sin β needs no arc tangent (this test runs for every edge
  // of every refinement pass).
  static bool opposite_angles_exceed_pi(const Eigen::Vector3d& u, const Eigen::Vector3d& v, const Eigen::Vector3d& u2,
                                        const Eigen::Vector3d& v2) {
    const double sin_sum = u.cross(v).norm() * u2.dot(v2) + u.dot(v) * u2.cross(v2).norm();  // × |u||v||u2||v2|
    const double scale = std::sqrt(u.squaredNorm() * v.squaredNorm() * u2.squaredNorm() * v2.squaredNorm());
    return sin_sum < -1e-9 * scale;
  }
  int corner_after(int f, int a) const {
    const auto& t = p_.faces[f];
    for (int k = 0; k < 3; ++k)
      if (t[k] == a) return t[(k + 1) % 3];
    return -1;
  }
  void link_face(int f) {
    const auto& t = p_.faces[f];
    for (int k = 0; k < 3; ++k) {
      auto [it, inserted] = edges_.try_emplace(edge_key(t[k], t[(k + 1) % 3]), std::array<int, 2>{f, -1});
      if (!inserted) it->second[1] = f;
      if (inserted) ++global_edges_[edge_key(p_.global(t[k]), p_.global(t[(k + 1) % 3]))];
    }
  }
  void replace(int a, int b, int from, int to) {
    auto& fs = edges_[edge_key(a, b)];
    for (int& x : fs)
      if (x == from) {
        x = to;
        return;
      }
  }

  const MeshIndex& index_;
  Patch& p_;
  std::unordered_map<std::uint64_t, std::array<int, 2>> edges_;  // local edge → its two faces (-1: rim)
  std::unordered_map<std::uint64_t, int> global_edges_;          // patch edges by soup index, counted
  std::deque<std::pair<int, int>> queue_;
};

}  // namespace

bool triangulate(const TriangleSoup& soup, const MeshIndex& index, Patch& patch, std::string& why,
                 std::size_t dp_limit) {
  const int n = patch.rim_size();
  Polygon poly;
  for (int i = 0; i < n; ++i) {
    poly.corners.push_back(i);
    // The mesh face across rim edge (i, i+1) holds it the other way round.
    const int a = patch.rim[i], b = patch.rim[(i + 1) % n];
    const int f = index.face_with(b, a);
    Eigen::Vector3d nf = Eigen::Vector3d::Zero();
    if (f >= 0) {
      const auto& t = soup.faces[f];
      nf = unit_normal(soup.vertices[t[0]], soup.vertices[t[1]], soup.vertices[t[2]]);
    }
    poly.across.push_back(nf);
  }
  patch.faces.clear();
  if (triangulate_large(index, poly, patch, std::max<std::size_t>(dp_limit, 8), why, 0)) return true;
  // No triangulation from the rim vertices alone (every diagonal already exists in the mesh,
  // e.g. a 4-vertex hole whose both diagonals are mesh edges): a fan around one new vertex at
  // the rim's centroid, possible when the rim passes every vertex once.
  std::unordered_set<int> distinct(patch.rim.begin(), patch.rim.end());
  if (static_cast<int>(distinct.size()) != n || patch.size() != n) return false;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  double sigma = 0;
  for (int i = 0; i < n; ++i) {
    c += patch.points[i] / n;
    sigma += (patch.sigma.size() == static_cast<std::size_t>(n) ? patch.sigma[i] : 0) / n;
  }
  patch.faces.clear();
  patch.points.push_back(c);
  if (patch.sigma.size() == static_cast<std::size_t>(n)) patch.sigma.push_back(sigma);
  for (int i = 0; i < n; ++i) patch.faces.push_back({i, (i + 1) % n, n});
  return true;
}

bool refine(const MeshIndex& index, Patch& patch, std::size_t max_vertices, std::string& why) {
  constexpr double kAlpha = 1.4142135623730951;  // Liepa's density factor sqrt(2)
  PatchTopology topo(index, patch);
  for (int pass = 0; pass < 200; ++pass) {
    bool split_any = false;
    const int count = static_cast<int>(patch.faces.size());
    std::vector<std::pair<int, int>> touched;
    for (int f = 0; f < count; ++f) {
      const auto [i, j, k] = patch.faces[f];
      const Eigen::Vector3d c = (patch.points[i] + patch.points[j] + patch.points[k]) / 3.0;
      const double sc = (patch.sigma[i] + patch.sigma[j] + patch.sigma[k]) / 3.0;
      bool dense_enough = false;
      for (int m : {i, j, k}) {
        const double d = kAlpha * (c - patch.points[m]).norm();
        if (!(d > sc && d > patch.sigma[m])) dense_enough = true;
      }
      if (dense_enough) continue;
      if (static_cast<std::size_t>(patch.size()) >= max_vertices) {
        why = "patch would exceed " + std::to_string(max_vertices) + " vertices";
        return false;
      }
      topo.split(f, c, sc);
      touched.insert(touched.end(), {{i, j}, {j, k}, {k, i}});
      split_any = true;
    }
    if (!split_any) break;
    topo.relax_all(std::move(touched));
    topo.relax_all(topo.interior_edges());
  }
  return true;
}

// Up to this many new vertices the k = 2 fairing system is solved dense (measured crossover:
// SparseLU's analysis dominates below a few hundred unknowns).
constexpr int kDenseFairing = 200;

bool fair(const TriangleSoup& soup, const MeshIndex& index, Patch& patch, bool tangent_continuous,
          std::string& why) {
  const int n = patch.rim_size();
  const int unknowns = patch.size() - n;
  if (unknowns == 0) return true;
  // Nodes by soup index (a repeated rim vertex is one node with the union of its fans): the
  // (node, neighbour) pairs, unique and ascending, by a counting sort over the nodes (rim
  // vertices ascending, then the new ones) and a sort of each node's few neighbours; small
  // tables rather than sorts of everything or hash maps (this runs for every hole).
  std::vector<int> rim_nodes;
  if (tangent_continuous) {
    rim_nodes = patch.rim;
    std::sort(rim_nodes.begin(), rim_nodes.end());
    rim_nodes.erase(std::unique(rim_nodes.begin(), rim_nodes.end()), rim_nodes.end());
  }
  const LocalIds rim_id(rim_nodes);
  const auto node_of = [&](int g) {  // -1: not a node (a rim vertex without the C1 join)
    return g >= patch.base ? static_cast<int>(rim_nodes.size()) + (g - patch.base) : rim_id.find(g);
  };
  std::vector<std::pair<int, int>> pairs;  // (node number, neighbour)
  pairs.reserve(6 * patch.faces.size());
  for (const auto& t : patch.faces)
    for (int k = 0; k < 3; ++k) {
      const int node = node_of(patch.global(t[k]));
      if (node < 0) continue;  // rows for the new vertices only
      for (int o : {t[(k + 1) % 3], t[(k + 2) % 3]}) pairs.emplace_back(node, patch.global(o));
    }
  for (std::size_t r = 0; r < rim_nodes.size(); ++r)
    index.for_each_face_of(rim_nodes[r], [&](int f) {
      for (int c : soup.faces[static_cast<std::size_t>(f)])
        if (c != rim_nodes[r]) pairs.emplace_back(static_cast<int>(r), c);
    });
  const std::size_t nodes = rim_nodes.size() + static_cast<std::size_t>(unknowns);
  std::vector<int> first_link(nodes + 1, 0);
  for (const auto& pr : pairs) ++first_link[static_cast<std::size_t>(pr.first) + 1];
  for (std::size_t k = 1; k <= nodes; ++k) first_link[k] += first_link[k - 1];
  std::vector<std::pair<int, int>> links(pairs.size());  // (node, neighbour) by soup index
  {
    std::vector<int> next(first_link.begin(), first_link.end() - 1);
    for (const auto& [node, other] : pairs) {
      const int g = static_cast<std::size_t>(node) < rim_nodes.size() ? rim_nodes[static_cast<std::size_t>(node)]
                                                                      : patch.base + node - static_cast<int>(rim_nodes.size());
      links[static_cast<std::size_t>(next[static_cast<std::size_t>(node)]++)] = {g, other};
    }
    std::size_t kept = 0;
    for (std::size_t k = 0; k < nodes; ++k) {
      const auto from = links.begin() + first_link[k], to = links.begin() + first_link[k + 1];
      std::sort(from, to);
      kept = static_cast<std::size_t>(std::unique_copy(from, to, links.begin() + static_cast<std::ptrdiff_t>(kept)) - links.begin());
    }
    links.resize(kept);
  }
  const auto position = [&](int g) -> const Eigen::Vector3d& {
    return g >= patch.base ? patch.points[static_cast<std::size_t>(g - patch.base + n)] : soup.vertices[g];
  };
  // Cotangent weights (as CGAL's fairing): cot of the angles opposite each edge, over the patch
  // faces and, for the rim nodes of the C1 join, the mesh faces around them; taken on the
  // refined patch before fairing. A weight is clamped to a small positive floor: obtuse
  // triangles give negative cotangents that would let the solve fold the patch.
  SmallTable<std::uint64_t, double> cot(3 * patch.faces.size());  // edge → sum of half cotangents
  const auto add_triangle = [&](int a, int b, int c) {
    const std::array<int, 3> t{a, b, c};
    for (int k = 0; k < 3; ++k) {
      const int o = t[k], u = t[(k + 1) % 3], w = t[(k + 2) % 3];
      const Eigen::Vector3d e1 = position(u) - position(o), e2 = position(w) - position(o);
      const double sn = e1.cross(e2).norm();
      if (!(sn > 0)) continue;
      const double half = 0.5 * e1.dot(e2) / sn;
      const auto [sum, added] = cot.insert(edge_key(u, w), half);  // summed in the order faces come
      if (!added) *sum += half;
    }
  };
  for (const auto& t : patch.faces) add_triangle(patch.global(t[0]), patch.global(t[1]), patch.global(t[2]));
  if (tangent_continuous) {
    std::vector<int> mesh_faces;
    for (int g : rim_nodes) index.for_each_face_of(g, [&](int f) { mesh_faces.push_back(f); });
    std::sort(mesh_faces.begin(), mesh_faces.end());
    mesh_faces.erase(std::unique(mesh_faces.begin(), mesh_faces.end()), mesh_faces.end());
    for (int f : mesh_faces) add_triangle(soup.faces[f][0], soup.faces[f][1], soup.faces[f][2]);
  }
  const auto cot_of = [&](int a, int b) {
    const double* sum = cot.find(edge_key(a, b));
    return sum ? *sum : 0.0;
  };
  constexpr double kMinCot = 0.05;
  std::vector<Eigen::Triplet<double>> trip;
  std::vector<Eigen::Vector3d> rhs;
  int row = 0;
  std::vector<double> weights;
  std::vector<std::pair<int, int>> row_of;  // (node, its row of A), ascending by node
  struct Term {
    int center, other;
    double w;
  };
  std::vector<Term> umbrella;
  for (std::size_t next = 0; next < links.size();) {
    const std::size_t first = next;
    const int center = links[first].first;
    while (next < links.size() && links[next].first == center) ++next;
    const auto list = [&](std::size_t k) { return links[first + k].second; };
    const std::size_t size = next - first;
    Eigen::Vector3d b = Eigen::Vector3d::Zero();
    weights.assign(size, 0);
    double total = 0;
    for (std::size_t k = 0; k < size; ++k) {
      weights[k] = std::max(cot_of(center, list(k)), kMinCot);
      total += weights[k];
    }
    bool has_unknown = center >= patch.base;
    for (std::size_t k = 0; k < size; ++k) has_unknown |= list(k) >= patch.base;
    if (!has_unknown) continue;  // a rim node with no new neighbour: constant row, no information
    const auto add = [&](int g, double c) {
      if (g >= patch.base) trip.emplace_back(row, g - patch.base, c);
      else b += c * position(g);
    };
    add(center, -1.0);
    for (std::size_t k = 0; k < size; ++k) add(list(k), weights[k] / total);
    rhs.push_back(b);
    row_of.emplace_back(center, row);
    for (std::size_t k = 0; k < size; ++k) umbrella.push_back({center, list(k), weights[k] / total});
    ++row;
  }
  Eigen::SparseMatrix<double> A(row, unknowns);
  A.setFromTriplets(trip.begin(), trip.end());
  Eigen::MatrixXd B(row, 3);
  for (int r = 0; r < row; ++r) B.row(r) = rhs[r].transpose();
  if (tangent_continuous) {
    // CGAL's k = 2 fairing: U(U(x)) = 0 at every new vertex, U at the rim including its mesh
    // ring (fixed). With W the umbrella rows of the new vertices over the rows of A:
    // W (A x + B) = 0, a square nonsymmetric system (sparse LU).
    std::vector<Eigen::Triplet<double>> wt;
    VertexTable row_table(row_of.size());
    for (const auto& [center, r] : row_of) row_table.insert(center, r);
    for (const auto& [center, r] : row_of)
      if (center >= patch.base) wt.emplace_back(center - patch.base, r, -1.0);
    for (const Term& t : umbrella) {
      if (t.center < patch.base) continue;
      if (const int r = row_table.find(t.other); r >= 0) wt.emplace_back(t.center - patch.base, r, t.w);
    }
    Eigen::SparseMatrix<double> W(unknowns, row);
    W.setFromTriplets(wt.begin(), wt.end());
    const Eigen::SparseMatrix<double> M = W * A;
    const Eigen::MatrixXd rhs_x = -(W * B);
    const auto accept = [&](const Eigen::MatrixXd& X) {
      for (int u = 0; u < unknowns; ++u) patch.points[n + u] = X.row(u).transpose();
      return true;
    };
    if (unknowns <= kDenseFairing) {
      // Small patches (most holes): dense LU is several times faster than the sparse LU's
      // ordering and symbolic analysis. It reports no singularity: check the residual.
      const Eigen::MatrixXd Md(M);
      const Eigen::MatrixXd X = Md.partialPivLu().solve(rhs_x);
      if (X.allFinite() && (Md * X - rhs_x).norm() <= 1e-9 * (rhs_x.norm() + 1)) return accept(X);
    } else {
      Eigen::SparseLU<Eigen::SparseMatrix<double>> lu;
      lu.analyzePattern(M);
      lu.factorize(M);
      if (lu.info() == Eigen::Success) {
        const Eigen::MatrixXd X = lu.solve(rhs_x);
        if (lu.info() == Eigen::Success && X.allFinite()) return accept(X);
      }
    }
    // Singular (should not happen on a connected patch): the least-squares form below.
  }
  const Eigen::SparseMatrix<double> AtA = A.transpose() * A;
  // AᵀA is symmetric positive definite: every new vertex is connected to the fixed rim, so A has
  // full column rank (the harmonic A is square and nonsingular, the bi-Laplacian adds rows).
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> solver(AtA);
  if (solver.info() != Eigen::Success) {
    why = "fairing system could not be factorised";
    return false;
  }
  const Eigen::MatrixXd X = solver.solve(-(A.transpose() * B));
  if (solver.info() != Eigen::Success || !X.allFinite()) {
    why = "fairing solve failed";
    return false;
  }
  for (int u = 0; u < unknowns; ++u) patch.points[n + u] = X.row(u).transpose();
  return true;
}

}  // namespace s2c::repair::fill
