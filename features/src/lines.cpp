#include "lines.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <tbb/parallel_for.h>

#include "fit_util.h"
#include "join_lines.h"

namespace s2c::features {
namespace {

Eigen::Vector3d oriented_normal(const Region& r, const Eigen::Vector3d& p, const Eigen::Vector3d& face_normal) {
  if (r.fit.shape.type == ShapeType::freeform) return face_normal;
  Eigen::Vector3d n = surface_normal(r.fit.shape, p);
  if (n.squaredNorm() == 0) return face_normal;
  return n.dot(face_normal) < 0 ? Eigen::Vector3d(-n) : n;
}

}  // namespace

bool intersection_curve(const Shape& a, const Shape& b, const std::vector<Eigen::Vector3d>& pts, bool closed,
                        Shape& out) {
  const Shape* plane = a.type == ShapeType::plane ? &a : b.type == ShapeType::plane ? &b : nullptr;
  const Shape* other = plane == &a ? &b : &a;
  if (!plane) return false;
  const Eigen::Vector3d& n = plane->dir;
  if (other->type == ShapeType::plane) {
    const Eigen::Vector3d dir = n.cross(other->dir);
    if (dir.norm() < 0.05 || closed) return false;  // (nearly) parallel planes meet nowhere sensible
    // The point of both planes closest to the chain's centroid.
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (const auto& p : pts) c += p;
    c /= pts.size();
    Eigen::Matrix3d A;
    A.row(0) = n.transpose();
    A.row(1) = other->dir.transpose();
    A.row(2) = dir.normalized().transpose();
    const Eigen::Vector3d rhs(n.dot(plane->point), other->dir.dot(other->point), dir.normalized().dot(c));
    out = fit::clipped_line(A.colPivHouseholderQr().solve(rhs), dir.normalized(), pts);
    return true;
  }
  if (other->type != ShapeType::cylinder && other->type != ShapeType::cone) return false;
  const Eigen::Vector3d& axis = other->dir;
  if (std::abs(axis.dot(n)) < std::cos(2.0 * M_PI / 180.0)) return false;  // an ellipse: fitted generically
  const double t = n.dot(plane->point - other->point) / axis.dot(n);
  const Eigen::Vector3d center = other->point + t * axis;
  const double radius =
      other->type == ShapeType::cylinder ? other->radius : std::abs(t) * std::tan(other->half_angle_deg * M_PI / 180.0);
  if (!(radius > 0)) return false;
  out = Shape{};
  out.point = center;
  out.dir = n.normalized();
  out.radius = radius;
  fit::circle_or_arc(out, pts, closed, false);
  return true;
}

std::vector<TracedLine> trace_lines(const MeshArrays& m, const FaceNormal& normal, const Segmentation& seg,
                                    double min_crease_deg, double tolerance, bool noisy, double border_edge) {
  const int ne = static_cast<int>(m.edges.size()), nv = m.vertices();
  const double cos_min = std::cos(min_crease_deg * M_PI / 180.0);
  // Line edges and the (sorted) pair of patches each one separates, decided per edge in parallel
  // (a million-vertex mesh has millions of edges and a few thousand line edges).
  std::vector<std::pair<int, int>> pair(ne, {-2, -2});
  tbb::parallel_for(tbb::blocked_range<int>(0, ne, 8192), [&](const tbb::blocked_range<int>& range) {
    for (int e = range.begin(); e < range.end(); ++e) {
      const auto& E = m.edges[e];
      const int a = seg.face_region[E.f0];
      const int b = E.f1 < 0 ? -1 : seg.face_region[E.f1];
      if (a == b) continue;
      if (b >= 0) {
        const Eigen::Vector3d mid = 0.5 * (m.pos[E.v0] + m.pos[E.v1]);
        const Eigen::Vector3d na = oriented_normal(seg.regions[a], mid, normal(E.f0));
        const Eigen::Vector3d nb = oriented_normal(seg.regions[b], mid, normal(E.f1));
        if (na.dot(nb) > cos_min) continue;  // a smooth (tangent) junction of two patches is no line
      }
      pair[e] = {std::min(a, b), std::max(a, b)};
    }
  });
  // The line edges at each vertex in increasing edge order (CSR: at_start[v] .. at_start[v + 1]).
  std::vector<int> line_edges;
  for (int e = 0; e < ne; ++e)
    if (pair[e].first != -2) line_edges.push_back(e);
  std::vector<int> at_start(nv + 1, 0), at(2 * line_edges.size());
  for (int e : line_edges) ++at_start[m.edges[e].v0 + 1], ++at_start[m.edges[e].v1 + 1];
  for (int v = 0; v < nv; ++v) at_start[v + 1] += at_start[v];
  {
    std::vector<int> fill(at_start.begin(), at_start.end() - 1);
    for (int e : line_edges) at[fill[m.edges[e].v0]++] = e, at[fill[m.edges[e].v1]++] = e;
  }
  auto degree = [&](int v) { return at_start[v + 1] - at_start[v]; };
  auto junction = [&](int v) {
    return degree(v) != 2 || pair[at[at_start[v]]] != pair[at[at_start[v] + 1]];
  };
  std::vector<char> used(ne, 0);
  std::vector<TracedLine> lines;
  auto walk = [&](int start, int e) {
    TracedLine line;
    line.vertices.push_back(start);
    int v = start;
    while (true) {
      used[e] = 1;
      const auto& E = m.edges[e];
      v = E.v0 == v ? E.v1 : E.v0;
      if (v == start) {
        line.closed = true;
        break;
      }
      line.vertices.push_back(v);
      if (junction(v)) break;
      const int* ends = &at[at_start[v]];
      e = ends[0] == e ? ends[1] : ends[0];
      if (used[e]) break;
    }
    const auto [lo, hi] = pair[e];
    line.region_a = lo == -1 ? hi : lo;
    line.region_b = lo == -1 ? -1 : hi;
    lines.push_back(std::move(line));
  };
  for (int v = 0; v < nv; ++v)
    if (degree(v) > 0 && junction(v))
      for (int k = at_start[v]; k < at_start[v + 1]; ++k)
        if (!used[at[k]]) walk(v, at[k]);
  for (int e : line_edges)  // closed loops without junctions (a hole's rim)
    if (!used[e]) walk(m.edges[e].v0, e);

  // A chain of mesh edges along a worn crease zigzags by up to half an edge on top of the noise.
  // On a noisy mesh the edge is the one the borders were drawn to: a segmentation made on a
  // coarser working mesh and mapped back follows the crease only to within a working edge (the
  // mapping moves a border by up to one), however fine the mesh is. With the fine mesh's edge the
  // scans reconstructed at Poisson depth 9 (0.11 mm edges, the working mesh's 0.24 mm) had the
  // chains along their rounded hole rims 0.2 mm off the plane ∩ cylinder circle, beyond twice the
  // line tolerance: the bracket's rims fell into arcs of 2.9-5.2 mm for a 5 mm hole.
  const double border = border_edge > 0 ? border_edge : m.median_edge;
  const double line_tol =
      noisy ? std::hypot(tolerance, 0.5 * border) : std::max(tolerance, 0.25 * m.median_edge);
  // The two patches' intersection is the CAD edge itself; on a reconstructed scan the crease is
  // rounded, and the traced chain follows the rounding's crest, which lies about 0.41 ρ off the
  // edge for a right angle with fillet radius ρ. The fixture scans' Poisson meshes round their
  // edges over ρ ≈ 1.2 median edges (plate: the hole rims' chains lie 0.128–0.136 mm off the
  // plane ∩ cylinder circles, line_tol 0.133): the intersection is taken within twice line_tol.
  const double exact_tol = noisy ? 2 * line_tol : line_tol;
  // On a noisy mesh a rounded edge no seed's shape grew over stays a freeform band between the two
  // faces it joins, and a chain along the band meets one of them only: the edge it follows is that
  // face's intersection with a shape on the band's far side, one of the band's neighbours. (The
  // chains' pairs of patches are the line edges' pairs, so the neighbours are known now; the
  // splits below add no pair.)
  auto shapeless = [&](int r) { return seg.regions[r].fit.shape.type == ShapeType::freeform; };
  const RegionNeighbours neighbours(seg, lines);
  // The nearest such curve to a chain between shaped patch `shaped` and band `band` (rms
  // infinite when there is none). The chain lies within a band's width of the shape across it:
  // the others (a band along every rounded edge of a part touches them all) are passed over on
  // one distance.
  auto across = [&](int shaped, int band, const Samples& s, bool closed, int& best_other) {
    Fit best;
    best.rms = std::numeric_limits<double>::infinity();
    const Eigen::Vector3d& middle = s.points[s.points.size() / 2];
    for (int other : neighbours.of(band)) {
      Fit c;
      if (other == shaped || !(distance(seg.regions[other].fit.shape, middle) <= 4 * exact_tol) ||
          !intersection_curve(seg.regions[shaped].fit.shape, seg.regions[other].fit.shape, s.points, closed, c.shape))
        continue;
      fit::finish(c, s);
      if (c.rms < best.rms) best = c, best_other = other;
    }
    return best;
  };
  auto fit_chain = [&](TracedLine& line) {
    Samples s;
    for (int v : line.vertices) s.points.push_back(m.pos[v]);
    const std::vector<Eigen::Vector3d>& pts = s.points;
    Fit& fit = line.fit;
    fit = Fit{};
    line.edge_a = line.edge_b = -1;
    if (pts.size() < 2) return;
    Fit exact;
    if (line.region_b >= 0 &&
        intersection_curve(seg.regions[line.region_a].fit.shape, seg.regions[line.region_b].fit.shape, pts,
                           line.closed, exact.shape)) {
      fit::finish(exact, s);
      if (exact.rms <= exact_tol) {
        fit = exact;
        line.edge_a = line.region_a, line.edge_b = line.region_b;
        return;
      }
    }
    if (noisy && line.region_b >= 0 && shapeless(line.region_a) != shapeless(line.region_b)) {
      const bool a_band = shapeless(line.region_a);
      const int shaped = a_band ? line.region_b : line.region_a;
      int other = -1;
      const Fit curve = across(shaped, a_band ? line.region_a : line.region_b, s, line.closed, other);
      if (curve.rms <= exact_tol) {
        fit = curve;
        line.edge_a = std::min(shaped, other), line.edge_b = std::max(shaped, other);
        return;
      }
    }
    if (!line.closed) {
      Fit l = fit_line(s);
      if (l.ok && l.rms <= line_tol) {
        fit = l;
        return;
      }
    }
    if (pts.size() >= 4) {
      Fit c = fit_circle(s, line.closed);
      if (c.ok && c.rms <= line_tol) {
        fit = c;
        return;
      }
    }
  };
  // On a noisy mesh a chain along a band may turn a corner without a junction (from a top edge
  // down a side edge, one patch on either side all the way): a chain that fits no curve is split
  // at its sharpest point, the vertex farthest from its chord, where its two sides turn by more
  // than kCornerTurnDeg, and the sides are fitted on their own. The split stands when a side is
  // an edge of two shapes: a freeform rim cut into straight pieces would be neither.
  constexpr double kCornerTurnDeg = 30.0;
  const double cos_turn = std::cos(kCornerTurnDeg * M_PI / 180.0);
  // The vertex to split `line` at, or 0 for none.
  auto corner_of = [&](const TracedLine& line) -> std::size_t {
    if (!noisy || line.closed || line.fit.shape.type != ShapeType::freeform || line.vertices.size() < 5) return 0;
    const std::vector<int>& vs = line.vertices;
    const Eigen::Vector3d a = m.pos[vs.front()], b = m.pos[vs.back()];
    const Eigen::Vector3d chord = (b - a).normalized();
    std::size_t corner = 0;
    double farthest = 0;
    for (std::size_t k = 2; k + 2 < vs.size(); ++k) {
      const Eigen::Vector3d w = m.pos[vs[k]] - a;
      const double d = (w - chord * chord.dot(w)).norm();
      if (d > farthest) farthest = d, corner = k;
    }
    if (corner == 0) return 0;
    const Eigen::Vector3d c = m.pos[vs[corner]];
    return (c - a).normalized().dot((b - c).normalized()) > cos_turn ? 0 : corner;
  };
  for (std::size_t i = 0; i < lines.size(); ++i) {
    fit_chain(lines[i]);
    while (const std::size_t corner = corner_of(lines[i])) {
      TracedLine head = lines[i], tail = lines[i];
      head.vertices.resize(corner + 1);
      tail.vertices.erase(tail.vertices.begin(), tail.vertices.begin() + static_cast<std::ptrdiff_t>(corner));
      fit_chain(head);
      fit_chain(tail);
      if (head.edge_a < 0 && tail.edge_a < 0) break;
      lines[i] = std::move(head);
      lines.push_back(std::move(tail));  // looked at again in its turn
    }
  }
  if (noisy) {
    // One CAD edge, traced in pieces along a band or crumbs, becomes one line (join_lines.h).
    // Tracing misses a crease where its angle stays under min_crease_deg: the pieces of the
    // fixture scans' straight edges lie up to 7 edges apart (the pocket: 0.2-2.2 mm at a 0.31
    // mm median edge), and their ends stop short of the corners by as much.
    const double reach = kMaxEdgeGap * m.median_edge;
    double total = 0;
    for (const auto& r : seg.regions) total += r.area;
    const double min_area = kMinorAreaShare * total;
    identify_edges(m, seg, neighbours, min_area, exact_tol, lines);
    join_edge_pieces(m, seg, min_area, reach, exact_tol, lines);
    end_at_corners(m, seg, neighbours, min_area, reach, lines);
  }
  return lines;
}

}  // namespace s2c::features
