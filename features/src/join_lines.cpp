#include "join_lines.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <map>

#include <Eigen/Geometry>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include "fit_util.h"

namespace s2c::features {
namespace {

using Eigen::Vector3d;

bool shaped(const Segmentation& seg, int r) { return r >= 0 && seg.regions[r].fit.shape.type != ShapeType::freeform; }

/// A large shaped patch: one whose edges are CAD edges, not a crumb's or a band's.
bool large(const Segmentation& seg, int r, double min_area) {
  return shaped(seg, r) && seg.regions[r].area >= min_area;
}

/// Where a point lies along an edge: the distance along a line from its point, the angle about a
/// circle's normal.
class Along {
 public:
  explicit Along(const Shape& s) : s_(s), uv_(fit::perpendicular_frame(s.dir)) {}
  bool circular() const { return s_.type != ShapeType::line; }
  double operator()(const Vector3d& p) const {
    const Vector3d w = p - s_.point;
    return circular() ? std::atan2(w.dot(uv_.col(1)), w.dot(uv_.col(0))) : w.dot(s_.dir);
  }
  /// mm per unit of the parameter.
  double scale() const { return circular() ? s_.radius : 1.0; }

 private:
  const Shape& s_;
  Eigen::Matrix<double, 3, 2> uv_;
};

/// A piece's span [lo, hi] along the edge and the vertices there. Angles are unwrapped along the
/// chain, then moved so that lo is in [0, 2π).
struct Span {
  double lo, hi;
  int v_lo, v_hi;
  int line;
};

Span span_of(const MeshArrays& m, const TracedLine& line, int index, const Along& along) {
  const int first = line.vertices.front();
  double raw = along(m.pos[first]), t = raw;
  Span s{t, t, first, first, index};
  for (std::size_t k = 1; k < line.vertices.size(); ++k) {
    const int v = line.vertices[k];
    const double next = along(m.pos[v]);
    t = along.circular() ? t + std::remainder(next - raw, 2 * M_PI) : next;
    raw = next;
    if (t < s.lo) s.lo = t, s.v_lo = v;
    if (t > s.hi) s.hi = t, s.v_hi = v;
  }
  if (along.circular()) {
    const double shift = std::floor(s.lo / (2 * M_PI)) * 2 * M_PI;
    s.lo -= shift, s.hi -= shift;
  }
  return s;
}

/// Whether a gap of `length` mm along the edge, from vertex `from` to vertex `to`, is bridged.
using Bridge = std::function<bool(double length, int from, int to)>;

/// The spans of one edge's pieces in runs across the gaps `bridge` accepts (`scale`: mm per unit
/// of the spans' parameter); on a circle the last run may continue into the first. `full` is set
/// when one run goes all the way round.
std::vector<std::vector<Span>> runs_of(std::vector<Span> spans, double scale, bool circular, const Bridge& bridge,
                                       bool& full) {
  full = false;
  if (spans.empty()) return {};
  std::sort(spans.begin(), spans.end(), [](const Span& a, const Span& b) { return a.lo < b.lo; });
  std::vector<std::vector<Span>> runs;
  double reach = 0;
  int reach_v = -1;
  for (const Span& s : spans) {
    if (runs.empty() || (s.lo > reach && !bridge((s.lo - reach) * scale, reach_v, s.v_lo))) runs.emplace_back();
    runs.back().push_back(s);
    if (runs.back().size() == 1 || s.hi > reach) reach = s.hi, reach_v = s.v_hi;
  }
  const Span& first = runs.front().front();
  const bool wraps =
      circular && (reach >= first.lo + 2 * M_PI || bridge((first.lo + 2 * M_PI - reach) * scale, reach_v, first.v_lo));
  full = wraps && runs.size() == 1;
  if (wraps && runs.size() > 1) {
    for (Span& s : runs.front()) s.lo += 2 * M_PI, s.hi += 2 * M_PI;
    runs.back().insert(runs.back().end(), runs.front().begin(), runs.front().end());
    runs.erase(runs.begin());
  }
  return runs;
}

}  // namespace

RegionNeighbours::RegionNeighbours(const Segmentation& seg, const std::vector<TracedLine>& lines)
    : nbr_(seg.regions.size()) {
  std::vector<std::vector<int>> band_sides(seg.regions.size());
  auto link = [&](int a, int b) {
    if (a == b) return;
    nbr_[a].push_back(b);
    nbr_[b].push_back(a);
  };
  for (const auto& l : lines) {
    if (l.region_b < 0) continue;
    link(l.region_a, l.region_b);
    if (shaped(seg, l.region_a) != shaped(seg, l.region_b)) {
      const bool a_band = !shaped(seg, l.region_a);
      band_sides[a_band ? l.region_a : l.region_b].push_back(a_band ? l.region_b : l.region_a);
    }
  }
  for (auto& sides : band_sides) {
    std::sort(sides.begin(), sides.end());
    sides.erase(std::unique(sides.begin(), sides.end()), sides.end());
    for (std::size_t i = 0; i < sides.size(); ++i)
      for (std::size_t j = i + 1; j < sides.size(); ++j) link(sides[i], sides[j]);
  }
  for (auto& n : nbr_) {
    std::sort(n.begin(), n.end());
    n.erase(std::unique(n.begin(), n.end()), n.end());
  }
}

bool RegionNeighbours::adjacent(int a, int b) const {
  return a >= 0 && b >= 0 && std::binary_search(nbr_[a].begin(), nbr_[a].end(), b);
}

void identify_edges(const MeshArrays& m, const Segmentation& seg, const RegionNeighbours& neighbours, double min_area,
                    double tolerance, std::vector<TracedLine>& lines) {
  std::vector<int> candidates;
  for (TracedLine& line : lines) {
    if (line.region_b < 0 || line.vertices.size() < 2 ||
        (large(seg, line.edge_a, min_area) && large(seg, line.edge_b, min_area)))
      continue;
    Samples s;
    for (int v : line.vertices) s.points.push_back(m.pos[v]);
    // Only shapes that pass near the piece can meet along it (a band along every rounded edge of
    // a part has them all as neighbours): the pairs stay few.
    const Vector3d& middle = s.points[s.points.size() / 2];
    candidates.clear();
    for (int r : {line.region_a, line.region_b}) {
      if (large(seg, r, min_area)) candidates.push_back(r);
      for (int n : neighbours.of(r))
        if (large(seg, n, min_area) && distance(seg.regions[n].fit.shape, middle) <= 2 * tolerance)
          candidates.push_back(n);
    }
    std::sort(candidates.begin(), candidates.end());
    candidates.erase(std::unique(candidates.begin(), candidates.end()), candidates.end());
    Fit best;
    best.rms = tolerance;
    int best_a = -1, best_b = -1;
    for (std::size_t i = 0; i < candidates.size(); ++i)
      for (std::size_t j = i + 1; j < candidates.size(); ++j) {
        const int a = candidates[i], b = candidates[j];
        if (!neighbours.adjacent(a, b)) continue;
        Fit c;
        if (!intersection_curve(seg.regions[a].fit.shape, seg.regions[b].fit.shape, s.points, line.closed, c.shape))
          continue;
        fit::finish(c, s);
        if (c.rms <= best.rms) best = c, best_a = a, best_b = b;
      }
    if (best_a < 0) continue;
    line.fit = best;
    line.edge_a = best_a, line.edge_b = best_b;
  }
}

void join_edge_pieces(const MeshArrays& m, const Segmentation& seg, double min_area, double max_gap, double tolerance,
                      std::vector<TracedLine>& lines) {
  std::map<std::pair<int, int>, std::vector<int>> pieces;  // edge → its open pieces
  for (int l = 0; l < static_cast<int>(lines.size()); ++l) {
    const TracedLine& line = lines[l];
    const ShapeType type = line.fit.shape.type;
    if (line.edge_a >= 0 && !line.closed && type != ShapeType::circle)
      pieces[{line.edge_a, line.edge_b}].push_back(l);
  }
  std::vector<char> gone(lines.size(), 0);
  for (const auto& entry : pieces) {
    // (Not a structured binding: the bridge below captures it, which C++17 does not allow.)
    const std::pair<int, int>& edge = entry.first;
    const std::vector<int>& ids = entry.second;
    if (ids.size() < 2) continue;
    const Shape& first = lines[ids.front()].fit.shape;
    const Along along(first);
    std::vector<Span> spans;
    for (int l : ids) {
      // Pieces of a circle and pieces of a straight edge of the same two patches (a plane that
      // cuts a cylinder twice) are told apart by type.
      const bool circular = lines[l].fit.shape.type != ShapeType::line;
      if (circular == along.circular()) spans.push_back(span_of(m, lines[l], l, along));
    }
    // A gap is bridged when a walk over the mesh from one piece's end straight towards the next
    // one's start meets no large patch but the edge's two: a cut across the edge (a slot) does.
    const Bridge bridge = [&](double length, int from, int to) {
      if (length > max_gap) return false;
      const Eigen::Vector3d target = m.pos[to];
      const int max_steps = 4 * static_cast<int>(length / std::max(m.median_edge, 1e-12)) + 8;
      int v = from;
      double d = (m.pos[v] - target).norm();
      for (int step = 0; step <= max_steps; ++step) {
        int next = -1;
        for (int k = m.vf_start[v]; k < m.vf_start[v + 1]; ++k) {
          const int f = m.vf[k], r = seg.face_region[f];
          if (r != edge.first && r != edge.second && large(seg, r, min_area)) return false;
          for (int u : m.tri[f])
            if (const double du = (m.pos[u] - target).norm(); du < d) d = du, next = u;
        }
        if (v == to) return true;
        if (next < 0) return false;
        v = next;
      }
      return false;
    };
    bool full = false;
    for (const auto& run : runs_of(spans, along.scale(), along.circular(), bridge, full)) {
      if (run.size() < 2) continue;
      std::vector<std::pair<double, int>> order;  // (parameter, vertex)
      for (const Span& s : run)
        for (int v : lines[s.line].vertices) {
          double t = along(m.pos[v]);
          // The turn of the span's own angles ([lo, lo + 2π), rounding aside).
          if (along.circular()) t += std::ceil((s.lo - 1e-9 - t) / (2 * M_PI)) * 2 * M_PI;
          order.emplace_back(t, v);
        }
      std::sort(order.begin(), order.end());
      TracedLine joined;
      for (const auto& [t, v] : order)
        if (joined.vertices.empty() || joined.vertices.back() != v) joined.vertices.push_back(v);
      Samples s;
      for (int v : joined.vertices) s.points.push_back(m.pos[v]);
      joined.closed = full;
      if (joined.vertices.size() < 2 ||
          !intersection_curve(seg.regions[edge.first].fit.shape, seg.regions[edge.second].fit.shape, s.points,
                              joined.closed, joined.fit.shape))
        continue;
      fit::finish(joined.fit, s);
      if (!(joined.fit.rms <= tolerance)) continue;
      joined.region_a = joined.edge_a = edge.first;
      joined.region_b = joined.edge_b = edge.second;
      for (std::size_t k = 1; k < run.size(); ++k) gone[run[k].line] = 1;
      lines[run.front().line] = std::move(joined);
    }
  }
  std::size_t kept = 0;
  for (std::size_t l = 0; l < lines.size(); ++l)
    if (!gone[l]) {
      if (kept != l) lines[kept] = std::move(lines[l]);
      ++kept;
    }
  lines.resize(kept);
}

void end_at_corners(const MeshArrays& m, const Segmentation& seg, const RegionNeighbours& neighbours, double min_area,
                    double reach, std::vector<TracedLine>& lines) {
  // A plane nearly along the edge cuts it at a glancing angle, far from where it crosses.
  constexpr double kMinCrossing = 0.5;
  // The corner must be near the cutting patch itself, not only on its plane: a band joins the
  // walls of a pocket to the outer edges too. Every patch's box, `reach` wider, when first asked,
  // in one pass over the vertices, each read once for the patches of its faces (at a million
  // vertices each patch's faces one list after another took 0.03 s, the faces in one pass 0.04 s
  // of CPU: three reads of a scattered position per face).
  std::vector<Eigen::AlignedBox3d> boxes;
  auto box = [&](int r) -> const Eigen::AlignedBox3d& {
    if (boxes.empty()) {
      tbb::combinable<std::vector<Eigen::AlignedBox3d>> partial(
          [&] { return std::vector<Eigen::AlignedBox3d>(seg.regions.size()); });
      tbb::parallel_for(tbb::blocked_range<int>(0, m.vertices(), 1 << 14), [&](const tbb::blocked_range<int>& range) {
        std::vector<Eigen::AlignedBox3d>& mine = partial.local();
        for (int v = range.begin(); v < range.end(); ++v) {
          int last = -1;
          for (int k = m.vf_start[v]; k < m.vf_start[v + 1]; ++k)
            if (const int p = seg.face_region[m.vf[k]]; p != last) mine[p].extend(m.pos[v]), last = p;
        }
      });
      boxes.resize(seg.regions.size());
      partial.combine_each([&](const std::vector<Eigen::AlignedBox3d>& b) {
        for (std::size_t k = 0; k < b.size(); ++k) boxes[k].extend(b[k]);
      });
      for (auto& b : boxes) b.min().array() -= reach, b.max().array() += reach;
    }
    return boxes[r];
  };
  for (TracedLine& line : lines) {
    Shape& s = line.fit.shape;
    if (s.type != ShapeType::line || line.edge_a < 0) continue;
    const Shape& a = seg.regions[line.edge_a].fit.shape;
    const Shape& b = seg.regions[line.edge_b].fit.shape;
    if (a.type != ShapeType::plane || b.type != ShapeType::plane) continue;
    double lo = 0, hi = s.length, best_lo = reach, best_hi = reach;
    for (int c : neighbours.of(line.edge_a)) {
      const Shape& p = seg.regions[c].fit.shape;
      if (c == line.edge_b || p.type != ShapeType::plane || !large(seg, c, min_area) ||
          !neighbours.adjacent(c, line.edge_b))
        continue;
      const double crossing = p.dir.dot(s.dir);
      if (std::abs(crossing) < kMinCrossing) continue;
      const double t = p.dir.dot(p.point - s.point) / crossing;
      const bool at_start = std::abs(t) <= best_lo, at_end = std::abs(t - s.length) <= best_hi;
      if (!(at_start || at_end) || !box(c).contains(s.point + t * s.dir)) continue;
      if (at_start) best_lo = std::abs(t), lo = t;
      if (at_end) best_hi = std::abs(t - s.length), hi = t;
    }
    if (!(hi - lo > 0)) continue;
    s.point += lo * s.dir;
    s.length = hi - lo;
  }
}

}  // namespace s2c::features
