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
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

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

constexpr double kPi = 3.14159265358979323846;

namespace fill {

HoleShape analyse_rim(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& loop, double edge_length,
                      double planar_tolerance) {
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
  s.edge = edge_length > 0 ? edge_length : perimeter / n;
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
  s.planar = s.planarity <= planar_tolerance;
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
  return s;
}

}  // namespace fill

namespace {

using fill::HoleShape;
using fill::MeshIndex;
using fill::Patch;

// The median length of the edges of the faces at the rim's vertices.
double median_edge_around(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& loop) {
  std::vector<double> lengths;
  for (int v : loop)
    index.for_each_face_of(v, [&](int f) {
      const auto& t = soup.faces[static_cast<std::size_t>(f)];
      for (int i = 0; i < 3; ++i) lengths.push_back((soup.vertices[t[i]] - soup.vertices[t[(i + 1) % 3]]).norm());
    });
  if (lengths.empty()) return 0;
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
  return lengths[lengths.size() / 2];
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

// What the RBF fill did beyond the paper, for the report.
std::string rbf_detail(const fill::RbfStats& stats) {
  std::string note;
  if (stats.smoothed) note += " (noisy rings smoothed)";
  if (stats.pieces > 1) note += " (" + std::to_string(stats.pieces) + " smooth pieces across creases)";
  return note;
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
  index.add_faces(first_face);
  r.filled = true;
  r.new_vertices = static_cast<std::size_t>(p.size() - p.rim_size());
  r.new_faces = p.faces.size();
}

// One hole's fill up to the point where the soup changes: input checks, method choice and the
// first method's candidate patches, built against the soup as it is (read only, so the holes of
// one call can be planned in parallel). finish_hole validates, falls back and commits.
struct Plan {
  FillResult result;             ///< filled = false; reason set when the hole cannot be filled
  bool done = false;             ///< nothing left to try (bad input, or a 3-vertex hole)
  HoleShape shape;
  FillMethod first = FillMethod::rbf, second = FillMethod::liepa;
  std::vector<Patch> candidates;  ///< the first method's, best first
  /// check_patch of the candidates against the soup as planned (its first `checked_faces`
  /// faces), up to the first valid one, so that committing needs to test only the faces
  /// earlier holes appended since.
  std::vector<std::string> checked;
  std::size_t checked_faces = 0;
  std::string why;                ///< why the first method built nothing
  std::string rbf_note;
};

Patch make_patch(const TriangleSoup& soup, const std::vector<int>& loop) {
  Patch p;
  p.rim = loop;
  p.base = static_cast<int>(soup.vertices.size());
  for (int g : loop) p.points.push_back(soup.vertices[g]);
  return p;
}

// Builds `m`'s candidates for the hole (never throws: e.g. bad_alloc on an enormous hole).
void build(const TriangleSoup& soup, const MeshIndex& index, const std::vector<int>& loop, const HoleShape& shape,
           const FillOptions& options, FillMethod m, std::vector<Patch>& candidates, std::string& why,
           FillResult& r, std::string& rbf_note) {
  Patch p = make_patch(soup, loop);
  p.sigma.assign(loop.size(), shape.edge);
  try {
    if (m == FillMethod::liepa) {
      build_liepa(soup, index, p, shape, options, candidates, why);
    } else {
      fill::RbfStats stats;
      Patch alternative;
      if (fill::rbf_fill(soup, index, p, shape, options, stats, why, &alternative)) {
        candidates.push_back(std::move(p));
        if (!alternative.faces.empty()) candidates.push_back(std::move(alternative));
      }
      r.rbf_constraints = stats.constraints;
      r.rbf_solve_seconds = stats.solve_seconds;
      rbf_note = rbf_detail(stats);
    }
  } catch (const std::exception& e) {
    why = e.what();
  }
}

// check_patch of the plan's candidates against the soup as it is, up to the first valid one.
void validate(const TriangleSoup& soup, const MeshIndex& index, Plan& plan) {
  if (plan.done) return;
  plan.checked.clear();
  plan.checked_faces = soup.faces.size();
  for (const Patch& c : plan.candidates) {  // up to the first valid one: the one committed
    plan.checked.push_back(fill::check_patch(soup, index, c));
    if (plan.checked.back().empty()) break;
  }
}

// `checked`: validate the candidates too (needs the index's boxes; see fill_holes).
Plan plan_hole(const TriangleSoup& soup, const MeshIndex& index, const Hole& hole, const FillOptions& options,
               bool checked = true) {
  Plan plan;
  FillResult& r = plan.result;
  const auto& loop = hole.loop;
  const int nv = static_cast<int>(soup.vertices.size());
  plan.done = true;
  if (loop.size() < 3) {
    r.reason = "hole has fewer than 3 rim vertices";
    return plan;
  }
  if (options.max_hole_vertices && loop.size() > options.max_hole_vertices) {
    r.reason = "hole has " + std::to_string(loop.size()) + " rim vertices, more than max_hole_vertices";
    return plan;
  }
  for (std::size_t i = 0; i < loop.size(); ++i) {
    if (loop[i] < 0 || loop[i] >= nv) {
      r.reason = "rim vertex index " + std::to_string(loop[i]) + " out of range";
      return plan;
    }
    if (loop[i] == loop[(i + 1) % loop.size()]) {
      r.reason = "rim repeats vertex " + std::to_string(loop[i]) + " on consecutive positions";
      return plan;
    }
    if (!soup.vertices[loop[i]].allFinite()) {
      r.reason = "rim vertex " + std::to_string(loop[i]) + " has non-finite coordinates";
      return plan;
    }
  }
  if (loop.size() == 3) {
    Patch p = make_patch(soup, loop);
    p.faces.push_back({0, 1, 2});
    r.method = FillMethod::liepa;
    r.choice = "3-vertex hole: one triangle";
    plan.candidates.push_back(std::move(p));
    return plan;
  }
  plan.done = false;
  plan.shape = fill::analyse_rim(soup, index, loop, options.edge_length, options.planar_tolerance);
  plan.shape.end_cap = hole.end_cap;
  // A trimmed rim's edges are cut short where the plane crossed faces: the cap takes the edge
  // length of the mesh around it instead.
  // A mesh whose faces the plane cut into slivers (Marching Cubes, whose vertices crowd the
  // grid nodes) can have a rim median of a tenth of its edges; a cap refined to it had 1.3 M
  // faces (the imls shaft scan): half the mesh's median edge is the floor.
  if (hole.end_cap && !(options.edge_length > 0))
    plan.shape.edge = std::max(median_edge_around(soup, index, loop), 0.5 * median_edge_length(soup));
  plan.shape.flat_fill =
      hole.end_cap || (plan.shape.planar && (plan.shape.wall_angle_deg < 10 || plan.shape.wall_angle_deg > 60));
  const HoleShape& shape = plan.shape;
  plan.first = options.method;
  if (plan.first == FillMethod::automatic) {
    if (shape.end_cap) {
      plan.first = FillMethod::liepa;
      r.choice = "auto: the part's unseen end face (trimmed flush with its plane) → liepa, flat";
    } else if (shape.flat_fill) {
      plan.first = FillMethod::liepa;
      r.choice = "auto: planar rim (" + std::to_string(shape.planarity) + " of diameter), faces " +
                 std::to_string(int(std::lround(shape.wall_angle_deg))) + "° off its plane → liepa, flat";
    } else {
      plan.first = FillMethod::rbf;
      r.choice = shape.planar ? "auto: planar rim on a curved surface → rbf" : "auto: curved rim → rbf";
    }
  } else {
    r.choice = std::string("requested ") + to_string(plan.first);
  }
  plan.second = plan.first == FillMethod::rbf ? FillMethod::liepa : FillMethod::rbf;
  build(soup, index, loop, shape, options, plan.first, plan.candidates, plan.why, r, plan.rbf_note);
  if (checked) validate(soup, index, plan);  // against the soup as it is (read only)
  return plan;
}

// The first valid candidate is committed; the second method is tried when none is. Never throws.
FillResult finish_hole(TriangleSoup& soup, MeshIndex& index, const Hole& hole, const FillOptions& options, Plan plan) {
  FillResult& r = plan.result;
  const int nv = static_cast<int>(soup.vertices.size());
  if (plan.done) {  // bad input (no candidate) or the single triangle
    for (Patch& c : plan.candidates) {
      c.base = nv;
      r.reason = fill::check_patch(soup, index, c);
      if (r.reason.empty()) commit(soup, index, c, r);
    }
    return r;
  }
  std::string reasons;
  for (const FillMethod m : {plan.first, plan.second}) {
    std::vector<Patch> own;
    std::string why = plan.why, rbf_note = plan.rbf_note;
    if (m != plan.first) build(soup, index, hole.loop, plan.shape, options, m, own, why, r, rbf_note);
    std::vector<Patch>& candidates = m == plan.first ? plan.candidates : own;
    std::string main_why;  // why the first candidate failed: the later ones are its fallbacks
    for (std::size_t i = 0; i < candidates.size(); ++i) {
      Patch& c = candidates[i];
      c.base = nv;  // planned before earlier holes of the call added their vertices
      if (m == plan.first && i < plan.checked.size()) {
        // Checked when planned; faces are only appended: the new ones and the topology remain
        // (nothing to re-check when no earlier hole of the call appended any).
        why = plan.checked[i];
        if (why.empty() && soup.faces.size() > plan.checked_faces)
          why = fill::check_patch(soup, index, c, {plan.checked_faces, false});
      } else {
        why = fill::check_patch(soup, index, c);
      }
      if (!why.empty()) {
        if (i == 0) main_why = why;
        continue;
      }
      r.method = m;
      if (m == FillMethod::rbf) r.choice += rbf_note;
      if (m != plan.first)
        r.choice += "; " + std::string(to_string(plan.first)) + " failed (" + reasons + ") → " + to_string(m);
      if (&c != &candidates.front())
        r.choice += m == FillMethod::rbf ? " (harmonic start: the C1-faired start folded and was invalid)"
                                         : " (unfaired: the faired patch was invalid)";
      r.reason.clear();
      commit(soup, index, c, r);
      return r;
    }
    reasons += (reasons.empty() ? "" : "; ") + std::string(to_string(m)) + ": " + (main_why.empty() ? why : main_why);
  }
  r.method = plan.first;
  r.reason = reasons;
  return r;
}

FillResult fill_one(TriangleSoup& soup, MeshIndex& index, const Hole& hole, const FillOptions& options) {
  return finish_hole(soup, index, hole, options, plan_hole(soup, index, hole, options));
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
// `plan`, when given, is this loop's plan made before the soup changed (fill_holes).
FillResult fill_loop(TriangleSoup& soup, MeshIndex& index, const Hole& hole, const FillOptions& options, int depth,
                     Plan* plan = nullptr) {
  FillResult r = plan ? finish_hole(soup, index, hole, options, std::move(*plan)) : fill_one(soup, index, hole, options);
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

// fill_holes against an index of `soup` (built for the call, or held by a HoleFiller).
std::vector<FillResult> fill_with(TriangleSoup& soup, MeshIndex& index, const std::vector<Hole>& holes,
                                  const FillOptions& options) {
  std::vector<FillResult> results(holes.size());
  std::vector<double> seconds(holes.size(), 0);
  const auto t_pair = std::chrono::steady_clock::now();
  const std::vector<Loop> loops = repair_pairing(soup, index, holes);
  const double pair_seconds = seconds_since(t_pair);
  // Per input hole: the loops it is the primary source of (normally exactly its own loop).
  std::vector<std::vector<const Loop*>> by_hole(holes.size());
  for (const Loop& l : loops) by_hole[static_cast<std::size_t>(l.sources.front())].push_back(&l);
  // The holes that are one unchanged input loop are planned (method choice and candidate patches,
  // the expensive part) in parallel against the input; validation and commit stay in hole order,
  // so later holes are checked against earlier patches. Every plan depends only on the input:
  // the result is the same whatever the threads do.
  std::vector<std::size_t> simple;
  for (std::size_t h = 0; h < holes.size(); ++h)
    if (by_hole[h].size() == 1 && by_hole[h][0]->note.empty()) simple.push_back(h);
  std::vector<Plan> plans(holes.size());
  std::vector<char> planned(holes.size(), 0);
  // The plans are made, then validated, concurrently; for calls with more than kScanHoles holes
  // the index's block boxes (validation's broad phase, O(#F)) are built while the plans are made.
  const auto over_simple = [&](const auto& work) {
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, simple.size(), 1), [&](const auto& range) {
      for (std::size_t i = range.begin(); i != range.end(); ++i) {
        const std::size_t h = simple[i];
        const auto t0 = std::chrono::steady_clock::now();
        work(h);
        seconds[h] += seconds_since(t0);
      }
    });
  };
  const auto plan_unchecked = [&](std::size_t h) { plans[h] = plan_hole(soup, index, holes[h], options, false); };
  // Up to two holes each validation scans vertices and faces once; more share block boxes
  // (a HoleFiller's index has them already: then only boxes for faces appended since are built).
  constexpr std::size_t kScanHoles = 2;
  const bool blocks = !index.scanning() || simple.size() > kScanHoles;
  if (blocks) index.use_blocks();  // before the plans, which ask scanning()
  if (blocks && !index.boxes_ready())
    tbb::parallel_invoke([&] { index.prepare_boxes(); }, [&] { over_simple(plan_unchecked); });
  else
    over_simple(plan_unchecked);
  over_simple([&](std::size_t h) {
    validate(soup, index, plans[h]);
    planned[h] = 1;
  });
  for (std::size_t h = 0; h < holes.size(); ++h) {
    if (by_hole[h].empty()) continue;  // merged into an earlier hole, reported below
    const auto t0 = std::chrono::steady_clock::now();
    FillResult& r = results[h];
    bool first = true;
    for (const Loop* l : by_hole[h]) {
      Hole piece = holes[h];
      piece.loop = l->loop;
      FillResult part = fill_loop(soup, index, piece, options, 0, planned[h] ? &plans[h] : nullptr);
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
    seconds[h] += seconds_since(t0);
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

}  // namespace

std::vector<FillResult> fill_holes(TriangleSoup& soup, const std::vector<Hole>& holes, const FillOptions& options) {
  MeshIndex index(soup);
  return fill_with(soup, index, holes, options);
}

HoleFiller::HoleFiller(TriangleSoup& soup) : soup_(soup) { index(); }

HoleFiller::~HoleFiller() = default;

void HoleFiller::index() {
  index_ = std::make_unique<MeshIndex>(soup_);
  index_->use_blocks();
  index_->prepare_boxes();
  faces_ = soup_.faces.size();
  vertices_ = soup_.vertices.size();
}

std::vector<FillResult> HoleFiller::fill(const std::vector<Hole>& holes, const FillOptions& options) {
  if (soup_.faces.size() < faces_ || soup_.vertices.size() < vertices_) {
    index();  // not an append: index the soup as it is now
  } else if (soup_.faces.size() > faces_) {
    index_->add_faces(faces_);  // appended since the last call
    index_->prepare_boxes();
  }
  std::vector<FillResult> results = fill_with(soup_, *index_, holes, options);
  faces_ = soup_.faces.size();
  vertices_ = soup_.vertices.size();
  return results;
}

}  // namespace s2c::repair
