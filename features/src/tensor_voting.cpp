#include "tensor_voting.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdint>
#include <limits>

#include <Eigen/Eigenvalues>
#include <tbb/task_arena.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/parallel_sort.h>

#include "s2c/core/distance.h"
#include "s2c/core/errors.h"
#include "vector_math.h"

namespace s2c::features {

VotingThresholds voting_thresholds(double min_crease_deg, double noise, double edge) {
  const double half = 0.5 * min_crease_deg * M_PI / 180.0;
  const double slope = edge > 0 ? noise / edge : 0.0;
  VotingThresholds t;
  t.crease = 0.5 * std::tan(half) * std::tan(half) + 2.0 * slope * slope;
  t.corner = 0.5 * t.crease + 2.0 * slope * slope;
  return t;
}

namespace {

/// Largest angle (radians) between two faces of a plane group: small enough that the vote of
/// faces all within it of one another is plainly a face vote (λ2/λ1, λ3/λ1 ≤ tan²) with a
/// hundredfold margin under the thresholds, and wide enough for coplanar faces whose vertices were
/// rounded to float (a PLY or STL export: about 1e-5 rad at a 2 µm edge).
double plane_group_angle(const VotingThresholds& t) {
  const double bound = std::min(t.crease, t.corner);
  return bound > 0 ? std::min(1e-3, std::atan(std::sqrt(0.01 * bound))) : 0.0;
}

/// Plane group of each face: the cube of side angle / 2 its unit normal falls in, cubes centred
/// on the axes (so a face of an axis-aligned plane is not split from its neighbours by rounding).
/// Two unit normals in one cube are less than `angle` apart (their chord is at most √3 / 2 of
/// it). -1 for a face without a normal; empty when the angle is too small for the keys.
/// (Until stop 41 these were faces connected across edges within the angle of the group's first
/// face: the same bound, but a sequential walk over every face, 0.1 s at 1.9 M faces.)
std::vector<std::int64_t> plane_groups(const std::vector<Eigen::Vector3d>& normals, double angle) {
  const double inv = 2.0 / angle;
  if (!(inv < (1 << 19))) return {};  // (the keys, up to side³, then stay far below 2^63)
  const std::int64_t half = static_cast<std::int64_t>(std::ceil(inv)) + 2, side = 2 * half + 1;
  std::vector<std::int64_t> group(normals.size());
  tbb::parallel_for(std::size_t{0}, normals.size(), [&](std::size_t f) {
    const Eigen::Vector3d& n = normals[f];
    if (!(n.squaredNorm() > 0) || !n.allFinite()) {
      group[f] = -1;
      return;
    }
    const Eigen::Array3d c = (n.normalized().array() * inv).round() + static_cast<double>(half);
    group[f] = (static_cast<std::int64_t>(c[0]) * side + static_cast<std::int64_t>(c[1])) * side +
               static_cast<std::int64_t>(c[2]);
  });
  return group;
}

}  // namespace

namespace {

/// face_balls into `ball` (m.faces() long).
void fill_face_balls(const MeshArrays& m, std::vector<Eigen::Vector4f>& ball) {
  tbb::parallel_for(tbb::blocked_range<int>(0, m.faces(), 4096), [&](const tbb::blocked_range<int>& range) {
    for (int f = range.begin(); f < range.end(); ++f) {
      const Eigen::Vector3d c = m.centroid(f);
      double r2 = 0;
      for (int u : m.tri[f]) r2 = std::max(r2, (m.pos[u] - c).squaredNorm());
      // The centre rounded to float is off by up to half a float step: the radius grows by that
      // much and is rounded up, so the ball about the rounded centre still holds the triangle.
      // Out of float's range (or not finite) the radius is infinite: the ball rejects nothing.
      const Eigen::Vector3f cf = c.cast<float>();
      const double r = std::sqrt(r2) + (c - cf.cast<double>()).norm();
      float rf = static_cast<float>(r);
      if (rf < r) rf = std::nextafter(rf, std::numeric_limits<float>::infinity());
      if (!cf.allFinite() || !std::isfinite(rf)) rf = std::numeric_limits<float>::infinity();
      ball[f] = Eigen::Vector4f(cf.x(), cf.y(), cf.z(), rf);
    }
  });
}

}  // namespace

std::vector<Eigen::Vector4f> face_balls(const MeshArrays& m) {
  std::vector<Eigen::Vector4f> ball(m.faces());
  fill_face_balls(m, ball);
  return ball;
}

namespace {

/// Vertices in the order the faces first reach them: neighbours come one after the other and
/// share their faces in cache (vertex numbering often follows refinement levels instead).
std::vector<int> vertex_order(const MeshArrays& m) {
  const int nv = m.vertices();
  std::vector<int> order;
  order.reserve(nv);
  std::vector<char> seen(nv, 0);
  for (const auto& tri : m.tri)
    for (int u : tri)
      if (!seen[u]) seen[u] = 1, order.push_back(u);
  for (int u = 0; u < nv; ++u)
    if (!seen[u]) order.push_back(u);
  return order;
}

/// Squared distance from p to face f, or infinity when the ball about the face's centroid that
/// holds it (ball[f]) already lies beyond `far` of p. Compared squared, with a margin that keeps
/// every face within reach: no square root on the path of every face tested. The walk of vote()
/// and plainly_flat both test faces with it, so a face one counts as within reach the other does.
double squared_distance_within(const MeshArrays& m, const std::vector<Eigen::Vector4f>& ball, int f,
                               const Eigen::Vector3d& p, double far) {
  const Eigen::Vector4f& b = ball[f];
  const double beyond = (static_cast<double>(b[3]) + far) * (1.0 + 1e-9);
  if ((b.head<3>().cast<double>() - p).squaredNorm() > beyond * beyond) return std::numeric_limits<double>::infinity();
  const auto& tri = m.tri[f];
  return (closest_point_on_triangle(p, m.pos[tri[0]], m.pos[tri[1]], m.pos[tri[2]]) - p).squaredNorm();
}

/// A face of the grid of plainly_flat: the cell's key, the face and its plane group.
struct CellEntry {
  std::uint64_t key;
  std::int64_t group;
  int face;
};

/// plainly_flat, with the balls of face_balls(m) and the order of vertex_order(m).
std::vector<char> plainly_flat(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals,
                               const std::vector<Eigen::Vector4f>& ball, double radius, const VotingThresholds& t,
                               const std::vector<int>& order) {
  const int nv = m.vertices(), nf = m.faces();
  std::vector<char> flat(nv, 0);
  const double angle = plane_group_angle(t);
  if (!(angle > 0) || !(radius > 0) || !m.box.min.allFinite() || !m.box.max.allFinite()) return flat;
  // A flat vertex: all its faces in one plane group. The vote of a flat vertex v walks from v's
  // faces (all in v's group G) over faces within the radius that share a vertex; the first face
  // of another group it reaches shares a vertex with a face of G, a vertex that is not flat. So
  // v's vote is all of G (a face vote) unless some face that touches a vertex that is not flat
  // (a rim face), of a group other than G, lies within the radius of v: v is plainly flat when
  // none does. (Faces within the radius but not reached by the walk only make the test stricter.)
  const std::vector<std::int64_t> group = plane_groups(normals, angle);
  if (group.empty()) return flat;
  tbb::parallel_for(0, nv, [&](int v) {
    const int begin = m.vf_start[v], end = m.vf_start[v + 1];
    bool one = begin < end && m.pos[v].allFinite();
    for (int k = begin; one && k < end; ++k) {
      const int f = m.vf[k];
      one = group[f] >= 0 && group[f] == group[m.vf[begin]];
    }
    flat[v] = one;
  });
  const auto flats = static_cast<std::size_t>(std::count(flat.begin(), flat.end(), 1));
  if (flats == 0) return flat;  // (a noisy scan's filtered normals: no plane groups to speak of)
  // Rim faces enter every cell of a grid (cells four radii wide) that their bounding box, widened
  // by the radius, overlaps; a flat vertex then tests only the rim faces of its own cell, of
  // other groups, by its distance to them. Sorted (cell, face) pairs rather than a dense grid:
  // most cells of the box are empty. Narrower cells enter each face more often, wider ones give a
  // vertex more faces to skip (two, three, four and five radii: the anchor of `s2c-bench-features
  // voting` fastest at three to four). The same margins as vote(): a face this rejects is
  // certainly beyond the radius.
  const double far = radius * (1.0 + 1e-9), far2 = far * far * (1.0 + 1e-9), cell = 4.0 * far;
  const Eigen::Vector3d lo = m.box.min.array() - cell;
  constexpr int kAxisBits = 21;  // cells per axis below 2^21: three of them fit one 64-bit key
  if (!(((m.box.max - lo).array() / cell).maxCoeff() < (1 << kAxisBits) - 2)) return std::vector<char>(nv, 0);
  auto cell_of = [&](const Eigen::Vector3d& q) { return ((q - lo).array() / cell).floor().cast<std::int64_t>().eval(); };
  auto key_of = [&](std::int64_t x, std::int64_t y, std::int64_t z) {
    return (static_cast<std::uint64_t>(x) << (2 * kAxisBits)) | (static_cast<std::uint64_t>(y) << kAxisBits) |
           static_cast<std::uint64_t>(z);
  };
  // Cell range of each rim face (empty for the others): counted first, then filled in place.
  std::vector<std::size_t> first(nf + 1, 0);
  std::atomic<bool> bad{false};  // a rim face with a vertex that is not finite
  auto range_of = [&](int f, Eigen::Array<std::int64_t, 3, 1>& a, Eigen::Array<std::int64_t, 3, 1>& b) {
    const auto& tri = m.tri[f];
    Eigen::Vector3d mn = m.pos[tri[0]], mx = mn;
    for (int u : tri) mn = mn.cwiseMin(m.pos[u]), mx = mx.cwiseMax(m.pos[u]);
    a = cell_of(mn.array() - far);
    b = cell_of(mx.array() + far);
  };
  auto rim = [&](int f) {
    for (int u : m.tri[f])
      if (!flat[u]) return true;
    return false;
  };
  tbb::parallel_for(0, nf, [&](int f) {
    if (!rim(f)) return;
    const auto& tri = m.tri[f];
    if (!(m.pos[tri[0]].allFinite() && m.pos[tri[1]].allFinite() && m.pos[tri[2]].allFinite())) {
      bad = true;
      return;
    }
    Eigen::Array<std::int64_t, 3, 1> a, b;
    range_of(f, a, b);
    first[f + 1] = static_cast<std::size_t>((b - a + 1).prod());
  });
  if (bad) return std::vector<char>(nv, 0);
  for (int f = 0; f < nf; ++f) first[f + 1] += first[f];
  // An entry costs a few per cent of a vertex's vote (sorting it, testing it): when there are
  // many more entries than flat vertices (few planes, or faces much longer than the radius), the
  // flat vertices are voted on as they are.
  if (first[nf] > 16 * flats + 65536) return std::vector<char>(nv, 0);
  std::vector<CellEntry> entries(first[nf]);
  tbb::parallel_for(0, nf, [&](int f) {
    if (first[f] == first[f + 1]) return;
    Eigen::Array<std::int64_t, 3, 1> a, b;
    range_of(f, a, b);
    std::size_t k = first[f];
    for (std::int64_t x = a[0]; x <= b[0]; ++x)
      for (std::int64_t y = a[1]; y <= b[1]; ++y)
        for (std::int64_t z = a[2]; z <= b[2]; ++z) entries[k++] = {key_of(x, y, z), group[f], f};
  });
  tbb::parallel_sort(entries.begin(), entries.end(), [](const CellEntry& x, const CellEntry& y) { return x.key < y.key; });
  // Each cell's entries: the cells in key order and where their entries begin.
  std::vector<std::uint64_t> cells;
  std::vector<std::size_t> cell_begin;
  for (std::size_t k = 0; k < entries.size(); ++k)
    if (k == 0 || entries[k].key != entries[k - 1].key) cells.push_back(entries[k].key), cell_begin.push_back(k);
  cell_begin.push_back(entries.size());
  // The flat vertices against the rim faces of their cells, in face order: neighbours, mostly in
  // the same cell, look it up once.
  tbb::parallel_for(tbb::blocked_range<int>(0, nv, 4096), [&](const tbb::blocked_range<int>& r) {
    std::uint64_t last = ~std::uint64_t{0};
    std::size_t begin = 0, end = 0;  // entries of the cell `last`
    for (int i = r.begin(); i < r.end(); ++i) {
      const int v = order[i];
      if (!flat[v]) continue;
      const Eigen::Vector3d& p = m.pos[v];
      const auto c = cell_of(p);
      const std::uint64_t key = key_of(c[0], c[1], c[2]);
      if (key != last) {
        last = key;
        const auto at = std::lower_bound(cells.begin(), cells.end(), key);
        const std::size_t slot = static_cast<std::size_t>(at - cells.begin());
        begin = end = 0;
        if (at != cells.end() && *at == key) begin = cell_begin[slot], end = cell_begin[slot + 1];
      }
      const std::int64_t own = group[m.vf[m.vf_start[v]]];
      for (std::size_t k = begin; k < end; ++k) {
        const CellEntry& e = entries[k];
        if (e.group != own && squared_distance_within(m, ball, e.face, p, far) <= far2) {
          flat[v] = 0;
          break;
        }
      }
    }
  });
  return flat;
}

}  // namespace

std::vector<char> plainly_flat(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals, double radius,
                               const VotingThresholds& t) {
  return plainly_flat(m, normals, face_balls(m), radius, t, vertex_order(m));
}

std::vector<VertexTensor> vote(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals, double radius,
                               const VotingThresholds& t) {
  const int nv = m.vertices(), nf = m.faces();
  // μ_f = (A_f / A_max) exp(−d / (σ/3)) with σ the voting radius. Two deviations from the paper,
  // both for CAD tessellations with long skinny triangles: d is the distance from the vertex to
  // the triangle (not to its centroid, which can be far away for a face touching the vertex), and
  // the area is capped at the area of the voting disc so one huge face cannot outvote the rest.
  const double disc = M_PI * radius * radius;
  // Bounds with a margin over the radius for tests on squared distances: a face they reject is
  // farther than the radius whatever the rounding, so the faces voting are exactly those within it.
  const double far = radius * (1.0 + 1e-9), far2 = far * far * (1.0 + 1e-9);
  struct alignas(128) Scratch {  // (a cache line pair of its own: threads write their vectors' ends)
    // Which faces and vertices the current vertex's walk has queued: stamp[x] == the walk's
    // number. 16-bit numbers, the arrays cleared when they wrap (every 65,535 walks): half the
    // memory of vertex numbers, and half the cache lines to miss.
    std::vector<std::uint16_t> mark;      // face f queued
    std::vector<std::uint16_t> expanded;  // vertex u's faces queued
    std::uint16_t walk = 0;
    /// The number of a new walk.
    std::uint16_t next_walk() {
      if (++walk == 0) {
        std::fill(mark.begin(), mark.end(), 0);
        std::fill(expanded.begin(), expanded.end(), 0);
        walk = 1;
      }
      return walk;
    }
    std::vector<int> queue;
    std::vector<int> voters;      // faces within the radius, in queue order
    std::vector<double> weights;  // their exp(−3d/r), computed together (vector_math.h)
  };
  // Per face its centroid and the radius of the ball about it holding the triangle, side by
  // side: the test that rejects most queued faces then reads one cache line, not two arrays.
  // In float: 31 MB instead of 62 at two million faces, for a test that only has to be sure.
  // (Allocated here, on the caller's thread: a worker would take them from its own malloc arena,
  // fresh pages, where the caller's heap holds pages the reading already faulted in.)
  std::vector<Eigen::Vector4f> ball(nf);
  std::vector<int> order;  // (a walk over every face on one core, beside the balls on all)
  tbb::parallel_invoke([&] { fill_face_balls(m, ball); }, [&] { order = vertex_order(m); });
  // Vertices amid a plane (most of a CAD part's) are face vertices whatever the exact weights.
  const std::vector<char> flat = plainly_flat(m, normals, ball, radius, t, order);
  // (Taken after plainly_flat's grid is freed: the two at once were the analysis' peak.)
  std::vector<VertexTensor> out(nv);
  // One scratch per thread of the arena, allocated here for the same reason as the balls.
  std::vector<Scratch> scratch(static_cast<std::size_t>(tbb::this_task_arena::max_concurrency()));
  for (Scratch& s : scratch) s.mark.assign(nf, 0), s.expanded.assign(nv, 0);
  tbb::parallel_for(tbb::blocked_range<int>(0, nv, 256), [&](const tbb::blocked_range<int>& range) {
    Scratch& s = scratch[static_cast<std::size_t>(tbb::this_task_arena::current_thread_index())];
    for (int i = range.begin(); i < range.end(); ++i) {
      const int v = order[i];
      if (flat[v]) {
        VertexTensor& out_v = out[v];
        out_v.lambda = Eigen::Vector3f(1.0f, 0.0f, 0.0f);
        out_v.e3 = normals[m.vf[m.vf_start[v]]].unitOrthogonal().cast<float>();
        out_v.cls = VertexClass::face;
        continue;
      }
      const Eigen::Vector3d p = m.pos[v];
      Eigen::Matrix3d T = Eigen::Matrix3d::Zero();
      s.queue.clear();
      const std::uint16_t walk = s.next_walk();
      s.expanded[v] = walk;
      for (int k = m.vf_start[v]; k < m.vf_start[v + 1]; ++k) {
        s.mark[m.vf[k]] = walk;
        s.queue.push_back(m.vf[k]);
      }
      const std::size_t incident_faces = s.queue.size();  // v's own faces come first
      s.voters.clear();
      s.weights.clear();
      for (std::size_t q = 0; q < s.queue.size(); ++q) {
        const int f = s.queue[q];
        const bool incident = q < incident_faces;
        double d = 0.0;
        if (!incident) {
          // Most faces of the search's outer ring are out of reach by their ball alone, without
          // the closest point.
          const double d2 = squared_distance_within(m, ball, f, p, far);
          if (d2 > far2) continue;  // certainly beyond the radius: no square root either
          d = std::sqrt(d2);
          if (d > radius) continue;
        }
        s.voters.push_back(f);
        s.weights.push_back(-3.0 * d / radius);
        // A vertex's faces are queued once: after that every one of them is marked, so a second
        // pass over its list (up to three per vertex otherwise) would queue nothing.
        for (int u : m.tri[f]) {
          if (s.expanded[u] == walk) continue;
          s.expanded[u] = walk;
          for (int k = m.vf_start[u]; k < m.vf_start[u + 1]; ++k)
            if (s.mark[m.vf[k]] != walk) {
              s.mark[m.vf[k]] = walk;
              s.queue.push_back(m.vf[k]);
            }
        }
      }
      // The decay weights in one call: the vectorised exp does two at a time, and v's own faces
      // (the first voters: an incident face always votes) weigh 1.
      exp_in_place(s.weights.data() + incident_faces, s.weights.size() - incident_faces);
      for (std::size_t k = 0; k < s.voters.size(); ++k) {
        const int f = s.voters[k];
        const double mu = std::min(m.farea[f], disc) / disc * (k < incident_faces ? 1.0 : s.weights[k]);
        const Eigen::Vector3d& n = normals[f];
        T.noalias() += mu * n * n.transpose();
      }
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
      es.computeDirect(T);
      const Eigen::Vector3d ev = es.eigenvalues();  // ascending
      VertexTensor& out_v = out[v];
      if (!(ev[2] > 0)) continue;  // isolated vertex or only degenerate faces: a face vertex
      const Eigen::Vector3d lambda(1.0, std::max(ev[1], 0.0) / ev[2], std::max(ev[0], 0.0) / ev[2]);
      out_v.lambda = lambda.cast<float>();
      out_v.e3 = es.eigenvectors().col(0).cast<float>();
      out_v.cls = lambda[2] > t.corner   ? VertexClass::corner
                  : lambda[1] > t.crease ? VertexClass::crease
                                         : VertexClass::face;
    }
  });
  return out;
}

}  // namespace s2c::features
