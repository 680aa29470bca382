// fill_holes: per hole, choose a method, build the patch, validate it, fall back to the other
// method when it is invalid, and append it to the soup (see s2c/repair/fill.h).
#include "s2c/repair/fill.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <numeric>
#include <string>
#include <unordered_map>
#include <unordered_set>

#include <Eigen/Eigenvalues>

#include "fill/liepa.h"
#include "fill/patch.h"
#include "fill/patch_check.h"
#include "fill/rbf.h"
#include "s2c/core/clock.h"

namespace s2c::repair {

const char* to_string(FillMethod m) {
  switch (m) {
    case FillMethod::automatic: return "auto";
    case FillMethod::rbf: return "rbf";
    case FillMethod::liepa: return "liepa";
  }
  return "?";
}

namespace {

using fill::HoleShape;
using fill::MeshIndex;
using fill::Patch;

constexpr double kPi = 3.14159265358979323846;

// The rim's plane, size and surroundings: everything the method choice looks at.
HoleShape analyse(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& loop,
                  const FillOptions& options) {
  HoleShape s;
  const int n = static_cast<int>(loop.size());
  double perimeter = 0;
  Eigen::Vector3d area = Eigen::Vector3d::Zero();  // vector area: its direction is the patch side
  for (int i = 0; i < n; ++i) {
    const Eigen::Vector3d &a = soup.vertices[loop[i]], &b = soup.vertices[loop[(i + 1) % n]];
    perimeter += (b - a).norm();
    s.centroid += a / n;
    area += a.cross(b);
  }
  s.edge = options.edge_length > 0 ? options.edge_length : perimeter / n;
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (int g : loop) {
    const Eigen::Vector3d d = soup.vertices[g] - s.centroid;
    cov += d * d.transpose();
    for (int h : loop) s.diameter = std::max(s.diameter, (soup.vertices[g] - soup.vertices[h]).squaredNorm());
  }
  s.diameter = std::sqrt(s.diameter);
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
  Eigen::Vector3d normal = eig.eigenvectors().col(0);
  if (normal.dot(area) < 0) normal = -normal;
  s.normal = normal;
  double worst = 0;
  for (int g : loop) worst = std::max(worst, std::abs((soup.vertices[g] - s.centroid).dot(normal)));
  s.planarity = s.diameter > 0 ? worst / s.diameter : 0;
  s.planar = s.planarity <= options.planar_tolerance;
  // Angle between the mesh faces on the rim and the rim plane (0°: flat ground, 90°: a wall).
  double sum = 0;
  int count = 0;
  for (int i = 0; i < n; ++i) {
    const int f = index.face_with(loop[(i + 1) % n], loop[i]);
    if (f < 0) continue;
    const auto& t = soup.faces[f];
    const Eigen::Vector3d nf = fill::unit_normal(soup.vertices[t[0]], soup.vertices[t[1]], soup.vertices[t[2]]);
    if (nf.squaredNorm() == 0) continue;
    sum += std::acos(std::clamp(nf.dot(normal), -1.0, 1.0)) * 180 / kPi;
    ++count;
  }
  s.wall_angle_deg = count ? sum / count : 0;
  s.flat_fill = s.planar && (s.wall_angle_deg < 10 || s.wall_angle_deg > 60);
  return s;
}

// Liepa's candidates, best first: the faired patch, then the refined one before fairing (its
// vertices are centroids of valid triangles, so it survives where fairing folds a patch).
bool build_liepa(const TriangleSoup& soup, const MeshIndex& index, Patch& p, const HoleShape& shape,
                 const FillOptions& options, std::vector<Patch>& out, std::string& why) {
  if (!fill::triangulate(soup, index, p, why) || !fill::refine(index, p, options.max_patch_vertices, why)) return false;
  Patch faired = p;
  if (fill::fair(soup, index, faired, !shape.flat_fill, why)) out.push_back(std::move(faired));
  out.push_back(std::move(p));
  if (shape.flat_fill) {
    // The flat fill is by definition in the rim plane; the sparse solve leaves ~1e-13 noise.
    for (auto& c : out)
      for (int l = c.rim_size(); l < c.size(); ++l)
        c.points[l] -= (c.points[l] - shape.centroid).dot(shape.normal) * shape.normal;
  }
  return true;
}

void commit(TriangleSoup& soup, MeshIndex& index, const Patch& p, FillResult& r) {
  const std::size_t first_face = soup.faces.size();
  const bool normals = !soup.normals.empty() && soup.normals.size() == soup.vertices.size();
  for (int l = p.rim_size(); l < p.size(); ++l) soup.vertices.push_back(p.points[l]);
  for (const auto& t : p.faces) soup.faces.push_back({p.global(t[0]), p.global(t[1]), p.global(t[2])});
  if (normals) {
    std::vector<Eigen::Vector3d> acc(static_cast<std::size_t>(p.size() - p.rim_size()), Eigen::Vector3d::Zero());
    for (const auto& t : p.faces) {
      const Eigen::Vector3d n = (p.points[t[1]] - p.points[t[0]]).cross(p.points[t[2]] - p.points[t[0]]);
      for (int c : t)
        if (c >= p.rim_size()) acc[c - p.rim_size()] += n;
    }
    for (auto& n : acc) soup.normals.push_back(n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : n);
  }
  index.add_faces(soup, first_face);
  r.filled = true;
  r.new_vertices = static_cast<std::size_t>(p.size() - p.rim_size());
  r.new_faces = p.faces.size();
}

// One hole: never throws (a failure leaves the hole open with the reason).
FillResult fill_one(TriangleSoup& soup, MeshIndex& index, const Hole& hole, const FillOptions& options) {
  FillResult r;
  const auto& loop = hole.loop;
  const int nv = static_cast<int>(soup.vertices.size());
  if (loop.size() < 3) {
    r.reason = "hole has fewer than 3 rim vertices";
    return r;
  }
  if (options.max_hole_vertices && loop.size() > options.max_hole_vertices) {
    r.reason = "hole has " + std::to_string(loop.size()) + " rim vertices, more than max_hole_vertices";
    return r;
  }
  for (std::size_t i = 0; i < loop.size(); ++i) {
    if (loop[i] < 0 || loop[i] >= nv) {
      r.reason = "rim vertex index " + std::to_string(loop[i]) + " out of range";
      return r;
    }
    if (loop[i] == loop[(i + 1) % loop.size()]) {
      r.reason = "rim repeats vertex " + std::to_string(loop[i]) + " on consecutive positions";
      return r;
    }
    if (!soup.vertices[loop[i]].allFinite()) {
      r.reason = "rim vertex " + std::to_string(loop[i]) + " has non-finite coordinates";
      return r;
    }
  }
  const auto make_patch = [&] {
    Patch p;
    p.rim = loop;
    p.base = nv;
    for (int g : loop) p.points.push_back(soup.vertices[g]);
    return p;
  };
  if (loop.size() == 3) {
    Patch p = make_patch();
    p.faces.push_back({0, 1, 2});
    r.method = FillMethod::liepa;
    r.choice = "3-vertex hole: one triangle";
    r.reason = fill::check_patch(soup, index, p);
    if (r.reason.empty()) commit(soup, index, p, r);
    return r;
  }
  const HoleShape shape = analyse(soup, index, loop, options);
  FillMethod first = options.method;
  if (first == FillMethod::automatic) {
    if (shape.flat_fill) {
      first = FillMethod::liepa;
      r.choice = "auto: planar rim (" + std::to_string(shape.planarity) + " of diameter), faces " +
                 std::to_string(int(std::lround(shape.wall_angle_deg))) + "° off its plane → liepa, flat";
    } else {
      first = FillMethod::rbf;
      r.choice = shape.planar ? "auto: planar rim on a curved surface → rbf" : "auto: curved rim → rbf";
    }
  } else {
    r.choice = std::string("requested ") + to_string(first);
  }
  const FillMethod second = first == FillMethod::rbf ? FillMethod::liepa : FillMethod::rbf;
  std::string reasons;
  for (const FillMethod m : {first, second}) {
    Patch p = make_patch();
    p.sigma.assign(loop.size(), shape.edge);
    std::string why;
    std::vector<Patch> candidates;
    try {
      if (m == FillMethod::liepa) {
        build_liepa(soup, index, p, shape, options, candidates, why);
      } else {
        fill::RbfStats stats;
        if (fill::rbf_fill(soup, index, p, shape, options, stats, why)) candidates.push_back(std::move(p));
        r.rbf_constraints = stats.constraints;
        r.rbf_solve_seconds = stats.solve_seconds;
      }
    } catch (const std::exception& e) {  // e.g. bad_alloc on an enormous hole
      why = e.what();
    }
    for (const Patch& c : candidates) {
      why = fill::check_patch(soup, index, c);
      if (!why.empty()) continue;
      r.method = m;
      if (m != first) r.choice += "; " + std::string(to_string(first)) + " failed (" + reasons + ") → " + to_string(m);
      if (&c != &candidates.front()) r.choice += " (unfaired: the faired patch was invalid)";
      r.reason.clear();
      commit(soup, index, c, r);
      return r;
    }
    reasons += (reasons.empty() ? "" : "; ") + std::string(to_string(m)) + ": " + why;
  }
  r.method = first;
  r.reason = reasons;
  return r;
}

// ---------------------------------------------------------------------------------------------
// Pairing at shared rim vertices. A rim vertex with several open fans of faces (a nested hole, or
// holes touching at a vertex) ends up manifold only when each hole side's patch joins the end of
// one fan to the start of *another*, so that all fans close into one disc around the vertex. The
// loops handed in fix that pairing (each occurrence of the vertex pairs its incoming rim edge
// with its outgoing one). Where that would close a fan on itself (the vertex would be left with
// several closed fans: a pinch), the outgoing edges of two occurrences are swapped, which merges
// the two fan cycles at the vertex; it splits the loop in two (occurrences in one loop) or
// merges two loops (occurrences in different loops).

struct Loop {
  std::vector<int> loop;
  std::vector<int> sources;  ///< input holes it holds edges of, primary (smallest) first
  std::string note;          ///< how it was re-paired, empty when it is an input loop unchanged
};

std::vector<Loop> repair_pairing(const TriangleSoup& soup, const MeshIndex& index, const std::vector<Hole>& holes) {
  // Occurrence o: a position of a loop; succ[o]: the next occurrence along its loop.
  std::vector<int> vert, hole_of, succ, prev;
  std::vector<std::size_t> first(holes.size() + 1, 0);
  for (std::size_t h = 0; h < holes.size(); ++h) {
    const int n = static_cast<int>(holes[h].loop.size()), b = static_cast<int>(vert.size());
    first[h] = static_cast<std::size_t>(b);
    for (int i = 0; i < n; ++i) {
      vert.push_back(holes[h].loop[i]);
      hole_of.push_back(static_cast<int>(h));
      succ.push_back(b + (i + 1) % n);
      prev.push_back(b + (i + n - 1) % n);
    }
  }
  first[holes.size()] = vert.size();
  const int nv = static_cast<int>(soup.vertices.size());
  std::unordered_map<int, std::vector<int>> at;  // vertex → its occurrences
  for (int o = 0; o < static_cast<int>(vert.size()); ++o)
    if (vert[o] >= 0 && vert[o] < nv) at[vert[o]].push_back(o);
  // Length of the loop through o (bounded walk).
  const auto loop_length = [&](int o) {
    int len = 1;
    for (int x = succ[o]; x != o && len <= static_cast<int>(vert.size()); x = succ[x]) ++len;
    return len;
  };
  bool changed = false;
  std::vector<int> candidates;
  for (const auto& [v, occ] : at)
    if (occ.size() > 1) candidates.push_back(v);
  std::sort(candidates.begin(), candidates.end());  // deterministic
  for (int v : candidates) {
    const auto& occ = at[v];
    // Fans at v: union-find over the faces of v joined through edges at v.
    const std::vector<int> faces = index.faces_of(v);
    std::vector<std::array<int, 3>> corners;
    std::unordered_map<int, int> local;
    for (int f = 0; f < static_cast<int>(faces.size()); ++f) {
      local[faces[f]] = f;
      corners.push_back(soup.faces[faces[f]]);
    }
    DisjointSets fan;
    fill::fans_at(v, corners, fan);
    // Fan of each occurrence's incoming and outgoing rim edge (the mesh face holds it reversed).
    const auto fan_of_face = [&](int f) {
      const auto it = local.find(f);
      return it == local.end() ? -1 : fan.find(it->second);
    };
    std::vector<int> fin(occ.size()), fout(occ.size());
    bool known = true;
    for (std::size_t k = 0; k < occ.size(); ++k) {
      fin[k] = fan_of_face(index.face_with(v, vert[prev[occ[k]]]));
      fout[k] = fan_of_face(index.face_with(vert[succ[occ[k]]], v));
      known &= fin[k] >= 0 && fout[k] >= 0;
    }
    if (!known) continue;
    // Cycles of the fan pairing: a union-find over fans joined by each occurrence.
    DisjointSets cyc(faces.size());
    for (std::size_t k = 0; k < occ.size(); ++k) cyc.unite(fin[k], fout[k]);
    for (std::size_t a = 0; a < occ.size(); ++a)
      for (std::size_t b = a + 1; b < occ.size(); ++b) {
        if (cyc.find(fin[a]) == cyc.find(fin[b])) continue;
        const int oa = occ[a], ob = occ[b];
        std::swap(succ[oa], succ[ob]);
        // A split must not leave a loop of fewer than 3 edges (two edges between the same two
        // vertices are a gap to stitch, not a hole to fill).
        if (loop_length(oa) < 3 || loop_length(ob) < 3) {
          std::swap(succ[oa], succ[ob]);
          continue;
        }
        prev[succ[oa]] = oa;
        prev[succ[ob]] = ob;
        std::swap(fout[a], fout[b]);
        cyc.unite(fin[a], fin[b]);
        changed = true;
      }
  }
  std::vector<Loop> out;
  if (!changed) {
    for (std::size_t h = 0; h < holes.size(); ++h) out.push_back({holes[h].loop, {static_cast<int>(h)}, {}});
    return out;
  }
  // Walk the cycles of succ, each from its smallest occurrence (an unchanged input loop keeps its
  // start and order).
  std::vector<char> done(vert.size(), 0);
  for (int o = 0; o < static_cast<int>(vert.size()); ++o) {
    if (done[o]) continue;
    Loop l;
    std::vector<int> sources;
    int x = o;
    do {
      done[x] = 1;
      l.loop.push_back(vert[x]);
      sources.push_back(hole_of[x]);
      x = succ[x];
    } while (x != o && l.loop.size() <= vert.size());
    std::sort(sources.begin(), sources.end());
    sources.erase(std::unique(sources.begin(), sources.end()), sources.end());
    l.sources = sources;
    const std::size_t whole = first[static_cast<std::size_t>(hole_of[o]) + 1] - first[static_cast<std::size_t>(hole_of[o])];
    if (sources.size() > 1 || l.loop.size() != whole) {
      l.note = "re-paired at shared rim vertices so that each closes to one fan (" + std::to_string(l.loop.size()) +
               " of " + std::to_string(whole) + " rim positions";
      if (sources.size() > 1) l.note += ", merged with " + std::to_string(sources.size() - 1) + " other hole(s)";
      l.note += ")";
    }
    out.push_back(std::move(l));
  }
  return out;
}

// fill_one, and when that fails on a loop that passes a vertex twice: the loop split at that
// vertex into two loops, each filled alone (the vertex is then left with two fans, a pinch, but
// the hole is closed; check_patch allows a vertex that already had several fans to keep them).
FillResult fill_loop(TriangleSoup& soup, MeshIndex& index, const Hole& hole, const FillOptions& options, int depth) {
  FillResult r = fill_one(soup, index, hole, options);
  if (r.filled || depth > 8) return r;
  const auto& loop = hole.loop;
  const int n = static_cast<int>(loop.size());
  std::unordered_map<int, int> seen;
  for (int j = 0; j < n; ++j) {
    const auto [it, inserted] = seen.try_emplace(loop[j], j);
    if (inserted) continue;
    const int i = it->second;
    if (j - i < 3 || n - (j - i) < 3) continue;
    Hole a = hole, b = hole;
    a.loop.assign(loop.begin() + i, loop.begin() + j);
    b.loop.assign(loop.begin() + j, loop.end());
    b.loop.insert(b.loop.end(), loop.begin(), loop.begin() + i);
    FillResult ra = fill_loop(soup, index, a, options, depth + 1);
    FillResult rb = fill_loop(soup, index, b, options, depth + 1);
    FillResult m = ra;
    m.filled = ra.filled && rb.filled;
    m.new_vertices += rb.new_vertices;
    m.new_faces += rb.new_faces;
    m.choice = "split at repeated rim vertex " + std::to_string(loop[i]) + " (" + r.reason + "): " + ra.choice +
               " | " + rb.choice;
    m.reason = ra.reason;
    if (!rb.reason.empty()) m.reason += (m.reason.empty() ? "" : " | ") + rb.reason;
    if (!m.filled && m.reason.empty()) m.reason = r.reason;
    return m;
  }
  return r;
}

}  // namespace

std::vector<FillResult> fill_holes(TriangleSoup& soup, const std::vector<Hole>& holes, const FillOptions& options) {
  MeshIndex index(soup);
  std::vector<FillResult> results(holes.size());
  std::vector<double> seconds(holes.size(), 0);
  const auto t_pair = std::chrono::steady_clock::now();
  const std::vector<Loop> loops = repair_pairing(soup, index, holes);
  const double pair_seconds = seconds_since(t_pair);
  // Per input hole: the loops it is the primary source of (normally exactly its own loop).
  std::vector<std::vector<const Loop*>> by_hole(holes.size());
  for (const Loop& l : loops) by_hole[static_cast<std::size_t>(l.sources.front())].push_back(&l);
  for (std::size_t h = 0; h < holes.size(); ++h) {
    if (by_hole[h].empty()) continue;  // merged into an earlier hole, reported below
    const auto t0 = std::chrono::steady_clock::now();
    FillResult& r = results[h];
    bool first = true;
    for (const Loop* l : by_hole[h]) {
      Hole piece = holes[h];
      piece.loop = l->loop;
      FillResult part = fill_loop(soup, index, piece, options, 0);
      if (!l->note.empty()) part.choice = l->note + "; " + part.choice;
      if (first) {
        r = std::move(part);
        first = false;
        continue;
      }
      // A hole re-paired into several loops: filled when every piece is.
      r.filled = r.filled && part.filled;
      r.new_vertices += part.new_vertices;
      r.new_faces += part.new_faces;
      r.choice += " | " + part.choice;
      if (!part.reason.empty()) r.reason += (r.reason.empty() ? "" : " | ") + part.reason;
    }
    seconds[h] = seconds_since(t0);
  }
  for (const Loop& l : loops)
    for (std::size_t k = 1; k < l.sources.size(); ++k) {
      const auto h = static_cast<std::size_t>(l.sources[k]), into = static_cast<std::size_t>(l.sources.front());
      if (!by_hole[h].empty()) continue;  // also primary of another loop: reported there
      FillResult& r = results[h];
      r.method = results[into].method;
      r.filled = results[into].filled;
      r.choice = "merged into hole " + std::to_string(into) + " at a shared rim vertex";
      if (!r.filled) r.reason = "filled with hole " + std::to_string(into) + ", which failed";
    }
  for (std::size_t h = 0; h < holes.size(); ++h) results[h].seconds = seconds[h] + pair_seconds / double(holes.size());
  return results;
}

}  // namespace s2c::repair
