// Constraint analysis (paper §3.3): every pair of fitted features is tested for the constraint
// kinds; the result is stated once, in the least redundant form a CAD designer would write.
//
// What takes part: patches of at least `min_patch_area` and, when that is set, lines touching
// no patch that is smaller or freeform (see ConstraintOptions) unless they are a whole edge of two
// patches they touch of 5 × that area or more (kEdgeFaceArea: a straight line from corner to
// corner, both ends on planes next to both patches; a closed circle), whose shape is not freeform
// and whose numbers are usable
// (finite, a non-zero direction, radius / length > 0, cone half angle in (0°, 90°)); with
// min_patch_area set, not a line (straight, arc or circle) within the position tolerance long,
// nor a straight one touching planes only, two or more, in the direction of none of their edges.
// Feature order is patches then lines, each in file order; members are listed in that order.
//
// Tolerances: angles `angle_tol_deg` (parallel: |cos| ≥ cos tol, perpendicular: |cos| ≤ sin tol);
// positions `length_tol` or, when 0, 0.5 % of `diagonal`; radii `radius_rel_tol` relative;
// lengths the larger of `radius_rel_tol` relative and the position tolerance.
//
// Equivalence kinds become one group per class (all members, ≥ 2 of them). Classes are built
// from pairwise tests with union-find, but two classes merge only when their leaders (first
// members) also pass the test, so chains of near misses cannot drift beyond one tolerance.
//   parallel       plane normals (±), cylinder/cone axes, straight lines: one family each.
//                  An axis class is stated only when it holds ≥ 2 distinct coaxial classes (else
//                  coaxial says it); a line class only when it holds ≥ 2 distinct collinear
//                  classes and is not implied by the planes: a line whose adjacent planes p, q are
//                  both parallel to it (and not to each other) has its direction fixed by the
//                  plane classes of p and q; a class whose members all share such a pair of
//                  plane classes adds nothing to the planes' parallel groups.
//   coaxial        cylinders/cones whose axes are parallel and within the position tolerance of
//                  each other; a sphere joins when its centre is on the axis of exactly one class.
//   concentric     circles/arcs: centres within the position tolerance, normals parallel (±).
//   equal_radius   cylinders+spheres as one family, circles+arcs as another.
//   equal_length   straight lines longer than the position tolerance.
//   collinear      straight lines: parallel, each one's ends on the other's infinite line.
//   equal_angle    fixed_angle constraints whose angles agree within the angle tolerance: members
//                  are those groups' ids (groups of groups), value = their mean, rounded to 0.1°.
// Pair kinds (members sorted):
//   perpendicular  same family only, and only between neighbours, so the output stays linear:
//                  planes in `adjacency` (on noisy meshes, min_patch_area > 0, also two planes
//                  that both touch one small or shapeless patch: a scan's rounded edge);
//                  straight lines sharing an end vertex (dropped when both lines' directions
//                  are fixed by planes, see parallel); axes in `adjacency`. Axes
//                  are few and a hole's axis is seldom adjacent to the axis it is square to, so
//                  for every two perpendicular axis parallel classes A, B the pairs
//                  {A₀}×B ∪ A×{B₀} (A₀, B₀ their first members) are stated as well: with the
//                  parallel groups they imply every cross pair.
//   connected      two curves (not closed) whose vertex chains share an end vertex.
//   fixed_angle    patches in `adjacency` whose normals meet at a constant angle along their
//                  common edge that is neither ~0° (tangent) nor ~90° (perpendicular's job, or a
//                  square edge between different families). Value = the acute angle between the
//                  normal lines, degrees, rounded to 0.1°. Computed where the angle is constant:
//                  plane–plane; plane–cylinder (plane parallel to the axis: acos(d/R)); plane–sphere
//                  (acos(d/R)); plane–cone (plane square to the axis: 90° − half angle);
//                  parallel cylinders and sphere–sphere (law of cosines on the radii and centre
//                  distance); coaxial cylinder–cone (half angle), cylinder–sphere (acos(r/R)),
//                  cone–sphere, cone–cone. Other pairs (oblique cuts) are left out.
//   symmetric      patches A, B of one type that are mirror images about a candidate plane:
//                  the mid-planes of pairs of parallel plane patches (largest areas first, at most
//                  `max_mirror_planes`) and the planes through the centroid of the curves along the
//                  principal axes whose variance stands apart. Conservative: A's mirror image must
//                  equal B's shape within the tolerances, the areas agree within `area_rel_tol`,
//                  the match is unique both ways, A is not its own mirror image, and the plane
//                  must have at least two such pairs. Attribute "mirror" = {"point","normal"}.
//                  Curves are not tested (they follow their patches).
// The paper keeps line constraints over patch constraints; here the patch constraints CAD
// designers state (planes parallel/perpendicular, cylinders coaxial/equal_radius) are always kept
// and line constraints are dropped only where the planes already imply them (see above).
// Groups are appended by kind (enum order) and then by member order, with ids "G<n>" after the
// highest existing "G<n>". Adjacency entries naming unknown features are ignored. Existing
// constraint groups are not consulted: calling twice appends the constraints twice.
#include "s2c/features/constraints.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <iterator>
#include <limits>
#include <map>
#include <numeric>
#include <optional>
#include <set>
#include <string>
#include <tuple>
#include <unordered_map>
#include <utility>
#include <vector>

#include <Eigen/Eigenvalues>
#include <nlohmann/json.hpp>

#include "s2c/core/disjoint_sets.h"

namespace s2c::features {
namespace {

using Eigen::Vector3d;
constexpr double kDeg = M_PI / 180.0;
constexpr int kKinds = static_cast<int>(ConstraintKind::equal_radius) + 1;
/// A line touching a small or shapeless patch takes part when it is the edge of two patches of at
/// least this many times min_patch_area (a scan's edge along the band its rounding left). Planes
/// the noise splits off a hole's wall are smaller: at σ = 0.3h with any two patches the chance
/// constraints of their lines took the plate's precision from 0.267 to 0.211 and the pocket's from
/// 0.784 to 0.684 (bench/README, "one edge, one line"); with 5 neither moved below 0.775.
constexpr double kEdgeFaceArea = 5.0;

/// The shape with a unit direction, or nothing when it cannot take part.
std::optional<Shape> usable(const Shape& s) {
  if (s.type == ShapeType::freeform) return std::nullopt;
  if (!s.point.allFinite() || !s.dir.allFinite() || !std::isfinite(s.radius) || !std::isfinite(s.length) ||
      !std::isfinite(s.half_angle_deg))
    return std::nullopt;
  Shape u = s;
  if (s.type != ShapeType::sphere) {
    const double n = s.dir.norm();
    if (!(n > 1e-9)) return std::nullopt;
    u.dir /= n;
  }
  switch (s.type) {
    case ShapeType::cylinder:
    case ShapeType::sphere:
    case ShapeType::circle:
      if (!(s.radius > 0)) return std::nullopt;
      break;
    case ShapeType::arc:
      if (!(s.radius > 0) || !s.start.allFinite() || !s.end.allFinite()) return std::nullopt;
      break;
    case ShapeType::cone:
      if (!(s.half_angle_deg > 0 && s.half_angle_deg < 90)) return std::nullopt;
      break;
    case ShapeType::line:
      if (!(s.length > 0)) return std::nullopt;
      break;
    default: break;
  }
  return u;
}

double distance_to_line(const Vector3d& p, const Vector3d& q, const Vector3d& d) {
  const Vector3d v = p - q;
  return (v - v.dot(d) * d).norm();
}

/// Acute angle between two normal lines, degrees.
double fold_deg(double cosine) { return std::acos(std::min(1.0, std::abs(cosine))) / kDeg; }

/// Equivalence classes of `items` (ascending) under `same`; two classes merge only when their
/// leaders pass `same` too. Classes in leader order, members ascending, singletons included.
template <class Same>
std::vector<std::vector<int>> classes(const std::vector<int>& items, Same same) {
  const int n = static_cast<int>(items.size());
  DisjointSets sets(items.size());
  std::vector<int> leader(items.size());
  std::iota(leader.begin(), leader.end(), 0);
  for (int i = 0; i < n; ++i)
    for (int j = i + 1; j < n; ++j) {
      const int ri = sets.find(i), rj = sets.find(j);
      if (ri == rj || !same(items[i], items[j])) continue;
      if (!same(items[leader[ri]], items[leader[rj]])) continue;
      const int l = std::min(leader[ri], leader[rj]);
      sets.unite(i, j);
      leader[sets.find(i)] = l;
    }
  std::map<int, std::vector<int>> by_leader;
  for (int i = 0; i < n; ++i) by_leader[leader[sets.find(i)]].push_back(items[i]);
  std::vector<std::vector<int>> out;
  for (auto& [l, members] : by_leader) out.push_back(std::move(members));
  return out;
}

/// Position of each item's class in `cls`.
std::map<int, int> class_index(const std::vector<std::vector<int>>& cls) {
  std::map<int, int> index;
  for (std::size_t c = 0; c < cls.size(); ++c)
    for (int i : cls[c]) index[i] = static_cast<int>(c);
  return index;
}

/// How many distinct classes (by `index`) the members of `c` fall in.
std::size_t distinct_classes(const std::vector<int>& c, const std::map<int, int>& index) {
  std::set<int> distinct;
  for (int i : c) distinct.insert(index.at(i));
  return distinct.size();
}

struct Found {
  ConstraintKind kind;
  std::vector<int> members;  ///< feature indices (equal_angle: positions in the sorted fixed_angle list)
  std::optional<double> value;
  double measured = 0.0;     ///< fixed_angle: the unrounded angle
  Attributes attributes;
};

struct MirrorPlane {
  Vector3d point, normal;
  double weight = 0.0;
};

class Detector {
 public:
  Detector(const FeatureSet& f, const ConstraintOptions& o) : o_(o) {
    len_tol_ = o.length_tol > 0 ? o.length_tol : 0.005 * o.diagonal;
    cos_tol_ = std::cos(o.angle_tol_deg * kDeg);
    sin_tol_ = std::sin(o.angle_tol_deg * kDeg);
    np_ = static_cast<int>(f.patches.size());
    const int n = np_ + static_cast<int>(f.lines.size());
    shape_.resize(n);
    area_.assign(n, 0.0);
    line_.assign(n, nullptr);
    nbr_.resize(n);
    std::unordered_map<std::string, int> index;
    doubtful_.assign(np_, 0);  // patches whose lines take no part either
    doubtful_of_.resize(np_);
    for (int i = 0; i < np_; ++i) {
      shape_[i] = usable(f.patches[i].shape);
      if (shape_[i] && !is_surface(shape_[i]->type)) shape_[i].reset();
      if (f.patches[i].area < o.min_patch_area) shape_[i].reset();
      // With a minimum area (noisy meshes), a patch without a usable shape disqualifies its lines
      // just like a small one: its borders are where fitting gave up, not CAD edges.
      doubtful_[i] = o.min_patch_area > 0 && !shape_[i];
      area_[i] = f.patches[i].area;
      index.emplace(f.patches[i].id, i);
    }
    for (int l = 0; l < static_cast<int>(f.lines.size()); ++l) {
      const int i = np_ + l;
      shape_[i] = usable(f.lines[l].shape);
      if (shape_[i] && is_surface(shape_[i]->type)) shape_[i].reset();
      line_[i] = &f.lines[l];
      index.emplace(f.lines[l].id, i);
    }
    std::set<std::pair<int, int>> pairs;
    for (const auto& [a, b] : f.adjacency) {
      auto ia = index.find(a), ib = index.find(b);
      if (ia == index.end() || ib == index.end() || ia->second == ib->second) continue;
      pairs.emplace(std::min(ia->second, ib->second), std::max(ia->second, ib->second));
    }
    adjacent_.assign(pairs.begin(), pairs.end());
    for (auto [a, b] : adjacent_) {
      nbr_[a].push_back(b);
      nbr_[b].push_back(a);
    }
    // A line touching such a patch is as doubtful as the patch, unless it is a whole edge of two
    // large patches it touches: a straight line from corner to corner, a closed circle, a CAD
    // edge, which a scan rounds into a band or crumbs. A piece (the edge traced with gaps too wide
    // to bridge, a corner's crumb) would state its own length and ends.
    std::vector<int> doubtful_lines;
    for (auto [a, b] : adjacent_)
      if (a < np_ && b >= np_ && doubtful_[a]) doubtful_lines.push_back(b);
    std::sort(doubtful_lines.begin(), doubtful_lines.end());
    doubtful_lines.erase(std::unique(doubtful_lines.begin(), doubtful_lines.end()), doubtful_lines.end());
    const double large_area = kEdgeFaceArea * o.min_patch_area;
    for (int i = 0; i < np_; ++i)
      if (shape_[i] && area_[i] >= large_area) {
        if (type(i) == ShapeType::plane) large_planes_.push_back(i);
        for (int k : nbr_[i])
          if (k < np_ && doubtful_[k]) doubtful_of_[i].push_back(k);
        std::sort(doubtful_of_[i].begin(), doubtful_of_[i].end());
      }
    // On a scan two kinds of line are no CAD edge:
    // - one no longer than the position tolerance, whatever its shape, is a corner's stub (a face
    //   of one patch poking past the corner, a mesh edge or two; an arc of a few edges round a
    //   rounded corner, its radius a tenth of a millimetre): its direction, centre and radius are
    //   the zigzag of those edges and its ends are the corner's, give or take the tolerance;
    // - a straight one between planes only that runs in the direction of no two of them cuts
    //   across a rounded corner (the pocket's top corners: 0.6 mm diagonals from the corner down
    //   into the rounding), its ends on the edges it cuts.
    if (o.min_patch_area > 0)
      for (int l = np_; l < n; ++l)
        if (shape_[l] && (!(curve_length(s(l)) > len_tol_) || (type(l) == ShapeType::line && across_planes(l))))
          shape_[l].reset();
    for (int l : doubtful_lines) {
      std::pair<int, int> edge;
      if (!shape_[l]) continue;
      const bool whole = edge_of_two(l, edge) && area_[edge.first] >= large_area &&
                         area_[edge.second] >= large_area &&
                         (type(l) == ShapeType::line ? ends_at_corners(l, edge) : type(l) == ShapeType::circle);
      if (!whole) shape_[l].reset();
    }
  }

  std::array<std::vector<Found>, kKinds> run() {
    collect();
    planes();
    axes();
    lines();
    curves();
    radii();
    fixed_angles();
    std::array<std::vector<Found>, kKinds> out;
    for (auto& c : found_) out[static_cast<int>(c.kind)].push_back(std::move(c));
    for (auto& list : out)
      std::stable_sort(list.begin(), list.end(), [](const Found& a, const Found& b) { return a.members < b.members; });
    equal_angles(out[static_cast<int>(ConstraintKind::fixed_angle)], out[static_cast<int>(ConstraintKind::equal_angle)]);
    std::vector<Found> sym = symmetric();
    std::stable_sort(sym.begin(), sym.end(), [](const Found& a, const Found& b) { return a.members < b.members; });
    out[static_cast<int>(ConstraintKind::symmetric)] = std::move(sym);
    return out;
  }

 private:
  ShapeType type(int i) const { return shape_[i] ? shape_[i]->type : ShapeType::freeform; }
  const Shape& s(int i) const { return *shape_[i]; }
  bool parallel(const Vector3d& a, const Vector3d& b) const { return std::abs(a.dot(b)) >= cos_tol_; }
  bool perpendicular(const Vector3d& a, const Vector3d& b) const { return std::abs(a.dot(b)) <= sin_tol_; }
  bool equal_radius(double a, double b) const { return std::abs(a - b) <= o_.radius_rel_tol * std::max(a, b); }
  Vector3d line_end(int i) const { return s(i).point + s(i).length * s(i).dir; }

  /// Axes (cylinder / cone) on one line.
  bool coaxial(int a, int b) const {
    const Shape &x = s(a), &y = s(b);
    return parallel(x.dir, y.dir) && distance_to_line(x.point, y.point, y.dir) <= len_tol_ &&
           distance_to_line(y.point, x.point, x.dir) <= len_tol_;
  }
  bool collinear(int a, int b) const {
    const Shape &x = s(a), &y = s(b);
    return parallel(x.dir, y.dir) && distance_to_line(x.point, y.point, y.dir) <= len_tol_ &&
           distance_to_line(line_end(a), y.point, y.dir) <= len_tol_ &&
           distance_to_line(y.point, x.point, x.dir) <= len_tol_ &&
           distance_to_line(line_end(b), x.point, x.dir) <= len_tol_;
  }

  /// Whether curve l is where two of its adjacent patches meet: two planes it runs along (not
  /// parallel to each other; they are put in `planes`), or a circle on a plane square to a cylinder
  /// or cone with its radius there.
  bool edge_of_two(int l, std::pair<int, int>& edge) const {
    const Shape& c = s(l);
    std::vector<int> planes, axes;
    for (int p : nbr_[l]) {
      if (p >= np_ || !shape_[p]) continue;
      (type(p) == ShapeType::plane ? planes : axes).push_back(p);
    }
    auto on_plane = [&](int p, const Vector3d& x) { return std::abs(s(p).dir.dot(x - s(p).point)) <= len_tol_; };
    if (c.type == ShapeType::line) {
      const Vector3d mid = c.point + 0.5 * c.length * c.dir;
      for (std::size_t i = 0; i < planes.size(); ++i)
        for (std::size_t j = i + 1; j < planes.size(); ++j) {
          const int p = planes[i], q = planes[j];
          if (perpendicular(c.dir, s(p).dir) && perpendicular(c.dir, s(q).dir) && !parallel(s(p).dir, s(q).dir) &&
              on_plane(p, mid) && on_plane(q, mid)) {
            edge = {p, q};
            return true;
          }
        }
      return false;
    }
    for (int p : planes) {
      if (!parallel(s(p).dir, c.dir) || !on_plane(p, c.point)) continue;
      for (int q : axes) {
        const Shape& a = s(q);
        if (!parallel(a.dir, c.dir) || distance_to_line(c.point, a.point, a.dir) > len_tol_) continue;
        const double r = type(q) == ShapeType::cylinder ? a.radius
                       : type(q) == ShapeType::cone     ? std::abs(a.dir.dot(c.point - a.point)) *
                                                          std::tan(a.half_angle_deg * kDeg)
                                                        : -1.0;
        if (r > 0 && std::abs(r - c.radius) <= std::max(o_.radius_rel_tol * r, len_tol_)) {
          edge = {p, q};
          return true;
        }
      }
    }
    return false;
  }

  /// Whether large patches a and b touch, or touch one doubtful patch (a scan's rounded edge
  /// between them).
  bool near(int a, int b) const {
    if (std::find(nbr_[a].begin(), nbr_[a].end(), b) != nbr_[a].end()) return true;
    const std::vector<int>&x = doubtful_of_[a], &y = doubtful_of_[b];
    for (std::size_t i = 0, j = 0; i < x.size() && j < y.size();) {
      if (x[i] == y[j]) return true;
      x[i] < y[j] ? ++i : ++j;
    }
    return false;
  }

  /// The length of a line's curve: a straight line's, an arc's (radius × swept angle), a circle's
  /// circumference; infinite for the other shapes (a freeform line has none to state).
  static double curve_length(const Shape& c) {
    switch (c.type) {
      case ShapeType::line: return c.length;
      case ShapeType::arc: return c.radius * c.angle_deg * M_PI / 180.0;
      case ShapeType::circle: return 2 * M_PI * c.radius;
      default: return std::numeric_limits<double>::infinity();
    }
  }

  /// Does straight line `l` touch usable planes only, at least two, and run in the direction of
  /// no two of them (square to both normals, the planes not parallel)?
  bool across_planes(int l) const {
    std::vector<int> planes;
    for (int p : nbr_[l]) {
      if (p >= np_ || !shape_[p]) continue;
      if (type(p) != ShapeType::plane) return false;
      planes.push_back(p);
    }
    if (planes.size() < 2) return false;
    const Vector3d& d = s(l).dir;
    for (std::size_t i = 0; i < planes.size(); ++i)
      for (std::size_t j = i + 1; j < planes.size(); ++j) {
        const Vector3d &n = s(planes[i]).dir, &m = s(planes[j]).dir;
        if (perpendicular(d, n) && perpendicular(d, m) && !parallel(n, m)) return false;
      }
    return true;
  }

  /// Whether both ends of straight line l, the edge of large planes `edge`, lie on a large plane
  /// that cuts it and is near both (a corner).
  bool ends_at_corners(int l, std::pair<int, int> edge) const {
    const Shape& c = s(l);
    constexpr double kMinCrossing = 0.5;  // a plane nearly along the line does not end it
    bool start = false, end = false;
    for (int p : large_planes_) {
      if (p == edge.first || p == edge.second || std::abs(s(p).dir.dot(c.dir)) < kMinCrossing ||
          !near(p, edge.first) || !near(p, edge.second))
        continue;
      start = start || std::abs(s(p).dir.dot(c.point - s(p).point)) <= len_tol_;
      end = end || std::abs(s(p).dir.dot(line_end(l) - s(p).point)) <= len_tol_;
    }
    return start && end;
  }

  /// End vertices of a non-closed curve that takes part.
  std::vector<int> ends(int i) const {
    if (!shape_[i] || !line_[i] || line_[i]->closed || line_[i]->vertices.empty()) return {};
    const int a = line_[i]->vertices.front(), b = line_[i]->vertices.back();
    if (a == b) return {};
    return {a, b};
  }

  void collect() {
    for (int i = 0; i < static_cast<int>(shape_.size()); ++i) {
      switch (type(i)) {
        case ShapeType::plane: planes_.push_back(i); break;
        case ShapeType::cylinder: axes_.push_back(i); radial_.push_back(i); break;
        case ShapeType::cone: axes_.push_back(i); break;
        case ShapeType::sphere: spheres_.push_back(i); radial_.push_back(i); break;
        case ShapeType::line: straight_.push_back(i); break;
        case ShapeType::circle:
        case ShapeType::arc: circles_.push_back(i); break;
        case ShapeType::freeform: break;
      }
    }
    // Curves meeting at an end vertex, in feature order.
    std::map<int, std::vector<int>> at;
    for (int i = np_; i < static_cast<int>(shape_.size()); ++i)
      for (int v : ends(i)) at[v].push_back(i);
    std::set<std::pair<int, int>> seen;
    for (auto& [v, ls] : at)
      for (std::size_t a = 0; a < ls.size(); ++a)
        for (std::size_t b = a + 1; b < ls.size(); ++b)
          if (ls[a] != ls[b] && seen.emplace(std::min(ls[a], ls[b]), std::max(ls[a], ls[b])).second)
            connected_.emplace_back(std::min(ls[a], ls[b]), std::max(ls[a], ls[b]));
    std::sort(connected_.begin(), connected_.end());
  }

  void add(ConstraintKind kind, std::vector<int> members, std::optional<double> value = std::nullopt) {
    std::sort(members.begin(), members.end());
    Found c{kind, std::move(members), value, value.value_or(0.0), {}};
    found_.push_back(std::move(c));
  }
  void add_classes(ConstraintKind kind, const std::vector<std::vector<int>>& cls) {
    for (const auto& c : cls)
      if (c.size() >= 2) add(kind, c);
  }

  void planes() {
    plane_classes_ = classes(planes_, [&](int a, int b) { return parallel(s(a).dir, s(b).dir); });
    add_classes(ConstraintKind::parallel, plane_classes_);
    plane_class_ = class_index(plane_classes_);
    std::set<std::pair<int, int>> perp;
    auto try_pair = [&](int a, int b) {
      if (type(a) == ShapeType::plane && type(b) == ShapeType::plane && perpendicular(s(a).dir, s(b).dir))
        perp.emplace(std::min(a, b), std::max(a, b));
    };
    for (auto [a, b] : adjacent_) try_pair(a, b);
    // Noisy meshes: a scan's sharp edge comes out rounded, a strip that no shape fits, so the
    // two planes it joins do not touch; planes bordering one such doubtful patch are neighbours.
    for (int c = 0; c < np_; ++c)
      if (doubtful_[c])
        for (std::size_t i = 0; i < nbr_[c].size(); ++i)
          for (std::size_t j = i + 1; j < nbr_[c].size(); ++j) try_pair(nbr_[c][i], nbr_[c][j]);
    for (auto [a, b] : perp) add(ConstraintKind::perpendicular, {a, b});
  }

  void axes() {
    std::vector<std::vector<int>> lines_of = classes(axes_, [&](int a, int b) { return coaxial(a, b); });
    for (int sp : spheres_) {
      int on = -1, count = 0;
      for (std::size_t c = 0; c < lines_of.size(); ++c) {
        const Shape& lead = s(lines_of[c].front());
        if (distance_to_line(s(sp).point, lead.point, lead.dir) <= len_tol_) on = static_cast<int>(c), ++count;
      }
      if (count == 1) lines_of[on].push_back(sp);
    }
    add_classes(ConstraintKind::coaxial, lines_of);
    const std::map<int, int> line_of = class_index(lines_of);

    const auto dirs = classes(axes_, [&](int a, int b) { return parallel(s(a).dir, s(b).dir); });
    for (const auto& c : dirs)
      if (distinct_classes(c, line_of) >= 2) add(ConstraintKind::parallel, c);
    std::set<std::pair<int, int>> perp;
    for (auto [a, b] : adjacent_)
      if ((type(a) == ShapeType::cylinder || type(a) == ShapeType::cone) &&
          (type(b) == ShapeType::cylinder || type(b) == ShapeType::cone) && perpendicular(s(a).dir, s(b).dir))
        perp.emplace(a, b);
    for (std::size_t ca = 0; ca < dirs.size(); ++ca)
      for (std::size_t cb = ca + 1; cb < dirs.size(); ++cb) {
        const auto &A = dirs[ca], &B = dirs[cb];
        if (!perpendicular(s(A.front()).dir, s(B.front()).dir)) continue;
        auto try_pair = [&](int a, int b) {
          if (perpendicular(s(a).dir, s(b).dir)) perp.emplace(std::min(a, b), std::max(a, b));
        };
        for (int b : B) try_pair(A.front(), b);
        for (int a : A) try_pair(a, B.front());
      }
    for (auto [a, b] : perp) add(ConstraintKind::perpendicular, {a, b});
  }

  void lines() {
    // Pairs of plane classes that fix each straight line's direction (see the file comment).
    std::map<int, std::set<std::pair<int, int>>> keys;
    for (int l : straight_) {
      std::vector<int> around;
      for (int p : nbr_[l])
        if (type(p) == ShapeType::plane && perpendicular(s(p).dir, s(l).dir)) around.push_back(p);
      for (std::size_t i = 0; i < around.size(); ++i)
        for (std::size_t j = i + 1; j < around.size(); ++j)
          if (!parallel(s(around[i]).dir, s(around[j]).dir)) {
            const int ci = plane_class_.at(around[i]), cj = plane_class_.at(around[j]);
            keys[l].emplace(std::min(ci, cj), std::max(ci, cj));
          }
    }
    const auto on_line = classes(straight_, [&](int a, int b) { return collinear(a, b); });
    add_classes(ConstraintKind::collinear, on_line);
    const std::map<int, int> line_of = class_index(on_line);
    const auto dirs = classes(straight_, [&](int a, int b) { return parallel(s(a).dir, s(b).dir); });
    for (const auto& c : dirs) {
      if (distinct_classes(c, line_of) < 2) continue;
      std::set<std::pair<int, int>> common = keys[c.front()];
      for (int i : c) {
        std::set<std::pair<int, int>> both;
        std::set_intersection(common.begin(), common.end(), keys[i].begin(), keys[i].end(),
                              std::inserter(both, both.end()));
        common = std::move(both);
      }
      if (common.empty()) add(ConstraintKind::parallel, c);
    }
    for (auto [a, b] : connected_)
      if (type(a) == ShapeType::line && type(b) == ShapeType::line && perpendicular(s(a).dir, s(b).dir) &&
          (keys[a].empty() || keys[b].empty()))
        add(ConstraintKind::perpendicular, {a, b});
    // Lengths within the tolerance of zero are equal by the tolerance whatever they are.
    std::vector<int> measurable;
    for (int l : straight_)
      if (s(l).length > len_tol_) measurable.push_back(l);
    add_classes(ConstraintKind::equal_length, classes(measurable, [&](int a, int b) {
                  const double la = s(a).length, lb = s(b).length;
                  return std::abs(la - lb) <= std::max(o_.radius_rel_tol * std::max(la, lb), len_tol_);
                }));
  }

  void curves() {
    for (auto [a, b] : connected_) add(ConstraintKind::connected, {a, b});
    add_classes(ConstraintKind::concentric, classes(circles_, [&](int a, int b) {
                  return (s(a).point - s(b).point).norm() <= len_tol_ && parallel(s(a).dir, s(b).dir);
                }));
  }

  void radii() {
    auto same = [&](int a, int b) { return equal_radius(s(a).radius, s(b).radius); };
    add_classes(ConstraintKind::equal_radius, classes(radial_, same));
    add_classes(ConstraintKind::equal_radius, classes(circles_, same));
  }

  /// Angle (degrees, acute, between the normal lines) along the common edge of two surfaces when
  /// it is constant, nothing otherwise.
  std::optional<double> surface_angle(int a, int b) const {
    if (type(b) < type(a)) std::swap(a, b);  // enum order: plane < cylinder < sphere < cone
    const Shape &x = s(a), &y = s(b);
    const ShapeType ta = x.type, tb = y.type;
    auto offset = [&](const Shape& plane, const Vector3d& p) { return std::abs(plane.dir.dot(p - plane.point)); };
    auto law_of_cosines = [&](double r1, double r2, double d) -> std::optional<double> {
      const double c = (r1 * r1 + r2 * r2 - d * d) / (2 * r1 * r2);
      if (std::abs(c) > 1 + len_tol_ / std::min(r1, r2)) return std::nullopt;  // they do not meet
      return fold_deg(c);
    };
    if (ta == ShapeType::plane) {
      switch (tb) {
        case ShapeType::plane: return fold_deg(x.dir.dot(y.dir));
        case ShapeType::cylinder:
          if (parallel(x.dir, y.dir)) return 90.0;
          if (!perpendicular(x.dir, y.dir)) return std::nullopt;
          [[fallthrough]];
        case ShapeType::sphere: {
          const double d = offset(x, y.point);
          if (d > y.radius + len_tol_) return std::nullopt;
          return fold_deg(std::min(1.0, d / y.radius));
        }
        case ShapeType::cone:
          if (!parallel(x.dir, y.dir)) return std::nullopt;
          return 90.0 - y.half_angle_deg;
        default: return std::nullopt;
      }
    }
    const bool on_axis = (tb == ShapeType::sphere || ta == ShapeType::sphere)
                             ? false
                             : coaxial(a, b);
    if (ta == ShapeType::cylinder && tb == ShapeType::cylinder) {
      if (!parallel(x.dir, y.dir)) return std::nullopt;
      return law_of_cosines(x.radius, y.radius, distance_to_line(y.point, x.point, x.dir));
    }
    if (ta == ShapeType::cylinder && tb == ShapeType::sphere) {
      if (distance_to_line(y.point, x.point, x.dir) > len_tol_ || x.radius > y.radius + len_tol_) return std::nullopt;
      return fold_deg(std::min(1.0, x.radius / y.radius));
    }
    if (ta == ShapeType::cylinder && tb == ShapeType::cone) {
      if (!on_axis) return std::nullopt;
      return y.half_angle_deg;
    }
    if (ta == ShapeType::sphere && tb == ShapeType::sphere)
      return law_of_cosines(x.radius, y.radius, (x.point - y.point).norm());
    if (ta == ShapeType::sphere && tb == ShapeType::cone) {
      // Centre on the cone's axis at height h above the apex: the normals meet at cos = h·sin α / R
      // on every intersection circle (the t of the circle cancels).
      if (distance_to_line(x.point, y.point, y.dir) > len_tol_) return std::nullopt;
      const double h = y.dir.dot(x.point - y.point), sa = std::sin(y.half_angle_deg * kDeg);
      const double disc = x.radius * x.radius - h * h * sa * sa;
      if (disc < 0) return std::nullopt;
      const double t = h * std::cos(y.half_angle_deg * kDeg) + std::sqrt(disc);
      if (t <= 0) return std::nullopt;
      return fold_deg(h * sa / x.radius);
    }
    if (ta == ShapeType::cone && tb == ShapeType::cone) {
      if (!on_axis) return std::nullopt;
      const double a1 = x.half_angle_deg * kDeg, a2 = y.half_angle_deg * kDeg;
      const double sign = x.dir.dot(y.dir) > 0 ? 1.0 : -1.0;
      return fold_deg(std::cos(a1) * std::cos(a2) - sign * std::sin(a1) * std::sin(a2));
    }
    return std::nullopt;
  }

  void fixed_angles() {
    for (auto [a, b] : adjacent_) {
      if (!shape_[a] || !shape_[b] || !is_surface(type(a)) || !is_surface(type(b))) continue;
      const std::optional<double> angle = surface_angle(a, b);
      if (!angle || *angle <= std::max(o_.angle_tol_deg, o_.min_fixed_angle_deg) ||
          *angle >= 90.0 - o_.angle_tol_deg)
        continue;
      add(ConstraintKind::fixed_angle, {a, b}, std::round(*angle * 10.0) / 10.0);
      found_.back().measured = *angle;
    }
  }

  void equal_angles(const std::vector<Found>& fixed, std::vector<Found>& out) const {
    std::vector<int> all(fixed.size());
    std::iota(all.begin(), all.end(), 0);
    const auto cls = classes(all, [&](int a, int b) {
      return std::abs(fixed[a].measured - fixed[b].measured) <= o_.angle_tol_deg;
    });
    for (const auto& c : cls) {
      if (c.size() < 2) continue;
      double sum = 0;
      for (int i : c) sum += fixed[i].measured;
      out.push_back(Found{ConstraintKind::equal_angle, c, std::round(sum / c.size() * 10.0) / 10.0, 0.0, {}});
    }
  }

  // ---- symmetric ----------------------------------------------------------------------------

  /// Same infinite surface (and radius / half angle) within the tolerances.
  bool same_surface(const Shape& x, const Shape& y) const {
    if (x.type != y.type) return false;
    switch (x.type) {
      case ShapeType::plane:
        return parallel(x.dir, y.dir) && std::abs(y.dir.dot(x.point - y.point)) <= len_tol_ &&
               std::abs(x.dir.dot(y.point - x.point)) <= len_tol_;
      case ShapeType::cylinder:
        return parallel(x.dir, y.dir) && distance_to_line(x.point, y.point, y.dir) <= len_tol_ &&
               distance_to_line(y.point, x.point, x.dir) <= len_tol_ && equal_radius(x.radius, y.radius);
      case ShapeType::cone:
        return (x.point - y.point).norm() <= len_tol_ && x.dir.dot(y.dir) >= cos_tol_ &&
               std::abs(x.half_angle_deg - y.half_angle_deg) <= o_.angle_tol_deg;
      case ShapeType::sphere:
        return (x.point - y.point).norm() <= len_tol_ && equal_radius(x.radius, y.radius);
      default: return false;
    }
  }

  static Shape reflect(const Shape& x, const MirrorPlane& m) {
    Shape r = x;
    r.point = x.point - 2.0 * m.normal.dot(x.point - m.point) * m.normal;
    r.dir = x.dir - 2.0 * m.normal.dot(x.dir) * m.normal;
    return r;
  }

  static Vector3d canonical(Vector3d n) {
    int k = 0;
    n.cwiseAbs().maxCoeff(&k);
    return n[k] < 0 ? Vector3d(-n) : n;
  }

  std::vector<MirrorPlane> mirror_planes() const {
    struct Candidate { int cls; double mid; Vector3d point, normal; double weight; };
    std::vector<Candidate> cand;
    const std::size_t cap = static_cast<std::size_t>(std::max(0, o_.max_mirror_planes));
    for (std::size_t c = 0; c < plane_classes_.size(); ++c) {
      std::vector<int> members = plane_classes_[c];
      if (members.size() < 2) continue;
      std::stable_sort(members.begin(), members.end(), [&](int a, int b) { return area_[a] > area_[b]; });
      if (members.size() > cap) members.resize(cap);
      const Vector3d n0 = canonical(s(plane_classes_[c].front()).dir);
      for (std::size_t i = 0; i < members.size(); ++i)
        for (std::size_t j = i + 1; j < members.size(); ++j) {
          const Shape &p = s(members[i]), &q = s(members[j]);
          const double op = n0.dot(p.point), oq = n0.dot(q.point);
          if (std::abs(op - oq) <= 2.0 * len_tol_) continue;
          const double mid = 0.5 * (op + oq);
          const Vector3d centre = 0.5 * (p.point + q.point);
          cand.push_back({static_cast<int>(c), mid, centre - (n0.dot(centre) - mid) * n0, n0,
                          area_[members[i]] + area_[members[j]]});
        }
    }
    std::stable_sort(cand.begin(), cand.end(),
                     [](const Candidate& a, const Candidate& b) { return std::tie(a.cls, a.mid) < std::tie(b.cls, b.mid); });
    std::vector<MirrorPlane> planes;
    for (std::size_t i = 0; i < cand.size();) {
      std::size_t j = i;
      double weight = 0;
      while (j < cand.size() && cand[j].cls == cand[i].cls && cand[j].mid - cand[i].mid <= len_tol_) weight += cand[j++].weight;
      planes.push_back({cand[i].point, cand[i].normal, weight});
      i = j;
    }
    std::stable_sort(planes.begin(), planes.end(), [](const MirrorPlane& a, const MirrorPlane& b) { return a.weight > b.weight; });
    if (planes.size() > cap) planes.resize(cap);
    for (const MirrorPlane& m : principal_planes()) {
      const bool known = std::any_of(planes.begin(), planes.end(), [&](const MirrorPlane& p) {
        return parallel(p.normal, m.normal) && std::abs(p.normal.dot(m.point - p.point)) <= len_tol_;
      });
      if (!known) planes.push_back(m);
    }
    return planes;
  }

  /// Planes through the centroid of the curves (sampled, weighted by length) normal to the
  /// principal axes whose variance differs from the other two by more than 5 %.
  std::vector<MirrorPlane> principal_planes() const {
    std::vector<std::pair<Vector3d, double>> samples;
    constexpr int kSamples = 16;
    for (int i = np_; i < static_cast<int>(shape_.size()); ++i) {
      if (!shape_[i]) continue;
      const Shape& c = s(i);
      if (c.type == ShapeType::line) {
        for (int k = 0; k < kSamples; ++k)
          samples.emplace_back(c.point + (k + 0.5) / kSamples * c.length * c.dir, c.length / kSamples);
      } else {
        // Arcs contribute their end points: a mirror-symmetric set of arcs has symmetric ends,
        // which is all the centroid and the principal axes need.
        if (c.type == ShapeType::arc) {
          samples.emplace_back(c.start, 1.0);
          samples.emplace_back(c.end, 1.0);
          continue;
        }
        const Vector3d u = c.dir.unitOrthogonal(), v = c.dir.cross(u);
        const double w = 2 * M_PI * c.radius / kSamples;
        for (int k = 0; k < kSamples; ++k) {
          const double t = 2 * M_PI * k / kSamples;
          samples.emplace_back(c.point + c.radius * (std::cos(t) * u + std::sin(t) * v), w);
        }
      }
    }
    double total = 0;
    Vector3d centroid = Vector3d::Zero();
    for (const auto& [p, w] : samples) centroid += w * p, total += w;
    if (samples.size() < 4 || !(total > 0)) return {};
    centroid /= total;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const auto& [p, w] : samples) cov += w * (p - centroid) * (p - centroid).transpose();
    cov /= total;
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    const Vector3d lambda = eig.eigenvalues();
    const double scale = std::max(lambda.maxCoeff(), 1e-12);
    std::vector<MirrorPlane> out;
    for (int k = 0; k < 3; ++k) {
      bool apart = true;
      for (int l = 0; l < 3; ++l)
        if (l != k && std::abs(lambda[k] - lambda[l]) <= 0.05 * scale) apart = false;
      if (apart) out.push_back({centroid, canonical(eig.eigenvectors().col(k).normalized()), 0.0});
    }
    return out;
  }

  /// The point of the surface (plane) or axis (cylinder) nearest to `c`, the centre (sphere) or
  /// the apex (cone): a reflection about a plane through `c` maps it to the image's own.
  Vector3d foot(const Shape& x, const Vector3d& c) const {
    switch (x.type) {
      case ShapeType::plane: return c - x.dir.dot(c - x.point) * x.dir;
      case ShapeType::cylinder: return x.point + x.dir.dot(c - x.point) * x.dir;
      default: return x.point;
    }
  }

  std::vector<Found> symmetric() const {
    std::vector<int> eligible;
    for (int i = 0; i < np_; ++i)
      if (shape_[i] && area_[i] > 0) eligible.push_back(i);
    const double at = std::clamp(o_.area_rel_tol, 0.0, 0.5);
    // Feet are hashed on a grid coarse enough for a foot moved by the angle tolerance.
    const double cell = std::max({4.0 * len_tol_, 0.01 * o_.diagonal, 1e-9});
    auto key = [&](const Eigen::Array3i& k) {
      return (static_cast<long long>(k.x()) * 73856093LL) ^ (static_cast<long long>(k.y()) * 19349663LL) ^
             (static_cast<long long>(k.z()) * 83492791LL);
    };
    auto cell_of = [&](const Vector3d& p) { return Eigen::Array3i((p / cell).array().floor().cast<int>()); };

    std::vector<Found> out;
    std::set<std::pair<int, int>> done;
    for (const MirrorPlane& m : mirror_planes()) {
      std::unordered_map<long long, std::vector<int>> grid;
      for (int i : eligible) grid[key(cell_of(foot(s(i), m.point)))].push_back(i);
      std::vector<int> match(np_, -1);
      for (int a : eligible) {
        const Shape image = reflect(s(a), m);
        if (same_surface(image, s(a))) continue;  // its own mirror image
        const Eigen::Array3i k0 = cell_of(foot(image, m.point));
        std::set<int> near;  // a hash collision may list a patch twice
        for (int dx = -1; dx <= 1; ++dx)
          for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
              auto it = grid.find(key(k0 + Eigen::Array3i(dx, dy, dz)));
              if (it != grid.end()) near.insert(it->second.begin(), it->second.end());
            }
        int found = -1, count = 0;
        for (int b : near) {
          if (b == a || type(b) != type(a) || std::abs(area_[a] - area_[b]) > at * std::max(area_[a], area_[b]))
            continue;
          if (same_surface(s(a), s(b)) || !same_surface(image, s(b))) continue;
          found = b, ++count;
        }
        if (count == 1) match[a] = found;
      }
      std::vector<std::pair<int, int>> pairs;
      for (int a = 0; a < np_; ++a)
        if (match[a] > a && match[match[a]] == a) pairs.emplace_back(a, match[a]);
      if (pairs.size() < 2) continue;
      const nlohmann::json mirror = {{"point", {m.point.x(), m.point.y(), m.point.z()}},
                                     {"normal", {m.normal.x(), m.normal.y(), m.normal.z()}}};
      for (auto [a, b] : pairs) {
        if (!done.emplace(a, b).second) continue;
        Found c{ConstraintKind::symmetric, {a, b}, std::nullopt, 0.0, {}};
        c.attributes["mirror"] = mirror.dump();
        out.push_back(std::move(c));
      }
    }
    return out;
  }

  const ConstraintOptions& o_;
  double len_tol_ = 0, cos_tol_ = 1, sin_tol_ = 0;
  int np_ = 0;
  std::vector<std::optional<Shape>> shape_;
  std::vector<double> area_;
  std::vector<const Line*> line_;
  std::vector<std::vector<int>> nbr_;
  std::vector<char> doubtful_;  ///< noisy meshes: small or shapeless patches (see the constructor)
  std::vector<std::pair<int, int>> adjacent_;  ///< unique (a < b)
  std::vector<std::pair<int, int>> connected_;  ///< curves sharing an end vertex (a < b)
  std::vector<int> planes_, axes_, spheres_, radial_, straight_, circles_;
  std::vector<int> large_planes_;                ///< usable planes of kEdgeFaceArea × min_patch_area or more
  std::vector<std::vector<int>> doubtful_of_;    ///< per large patch: its doubtful neighbours, sorted
  std::vector<std::vector<int>> plane_classes_;
  std::map<int, int> plane_class_;
  std::vector<Found> found_;
};

/// The number after "G" in ids like "G12", or -1.
long group_number(const std::string& id) {
  if (id.size() < 2 || id[0] != 'G' || id.size() > 18) return -1;
  long n = 0;
  for (std::size_t i = 1; i < id.size(); ++i) {
    if (id[i] < '0' || id[i] > '9') return -1;
    n = n * 10 + (id[i] - '0');
  }
  return n;
}

}  // namespace

struct ConstraintSearch::Result {
  std::array<std::vector<Found>, kKinds> by_kind;
};

ConstraintSearch::ConstraintSearch(const FeatureSet& features, const ConstraintOptions& options)
    : found_(std::make_unique<Result>(Result{Detector(features, options).run()})) {}
ConstraintSearch::~ConstraintSearch() = default;
ConstraintSearch::ConstraintSearch(ConstraintSearch&&) noexcept = default;
ConstraintSearch& ConstraintSearch::operator=(ConstraintSearch&&) noexcept = default;

int detect_constraints(FeatureSet& features, const ConstraintOptions& options) {
  return ConstraintSearch(features, options).add_to(features);
}

int ConstraintSearch::add_to(FeatureSet& features) const {
  const auto& found = found_->by_kind;
  long next = 0;
  for (const Group& g : features.groups) next = std::max(next, group_number(g.id) + 1);
  const int np = static_cast<int>(features.patches.size());
  auto feature_id = [&](int i) -> const std::string& {
    return i < np ? features.patches[i].id : features.lines[i - np].id;
  };
  std::vector<std::string> fixed_ids;
  int added = 0;
  for (int k = 0; k < kKinds; ++k) {
    const auto kind = static_cast<ConstraintKind>(k);
    for (const Found& c : found[k]) {
      Group g;
      g.id = "G" + std::to_string(next++);
      g.kind = "constraint";
      g.constraint = kind;
      for (int m : c.members) g.members.push_back(kind == ConstraintKind::equal_angle ? fixed_ids[m] : feature_id(m));
      g.value = c.value;
      g.attributes = c.attributes;
      if (kind == ConstraintKind::fixed_angle) fixed_ids.push_back(g.id);
      features.groups.push_back(std::move(g));
      ++added;
    }
  }
  return added;
}

}  // namespace s2c::features
