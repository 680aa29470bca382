// The Editor: shape maps on the edited features, greedy constraint propagation, restricted ARAP on
// their neighbours, checks, and the update of the hyper-mesh (see editor.h for the steps).
#include "s2c/edit/editor.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <deque>
#include <limits>
#include <queue>
#include <map>
#include <set>
#include <unordered_map>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "arap.h"
#include "constraint_rules.h"
#include "s2c/core/clock.h"
#include "s2c/core/errors.h"
#include "shape_map.h"

namespace s2c::edit {

using Eigen::Vector3d;
using features::ConstraintKind;
using features::Shape;
using features::ShapeType;

namespace {

// Vertex → features incidence in compressed rows.
struct Incidence {
  std::vector<int> start, items;
  template <class Sets>  // a vector of vertex lists: vector<int> per feature, array<int, 3> per face
  void build(int n, const Sets& sets) {
    std::vector<int> count(n + 1, 0);
    for (const auto& s : sets)
      for (int v : s) ++count[v + 1];
    start.assign(n + 1, 0);
    for (int i = 0; i < n; ++i) start[i + 1] = start[i] + count[i + 1];
    items.resize(start[n]);
    std::vector<int> fill(start.begin(), start.end() - 1);
    for (int k = 0; k < static_cast<int>(sets.size()); ++k)
      for (int v : sets[k]) items[fill[v]++] = k;
  }
  template <class F>
  void each(int v, F&& f) const {
    for (int e = start[v]; e < start[v + 1]; ++e) f(items[e]);
  }
};

features::Fit refit(ShapeType type, const std::vector<Vector3d>& pts, bool closed) {
  features::Samples s;
  s.points = pts;
  switch (type) {
    case ShapeType::plane: return features::fit_plane(s);
    case ShapeType::cylinder: return features::fit_cylinder(s);
    case ShapeType::sphere: return features::fit_sphere(s);
    case ShapeType::cone: return features::fit_cone(s);
    case ShapeType::line: return features::fit_line(s);
    case ShapeType::circle:
    case ShapeType::arc: return features::fit_circle(s, closed);
    default: return {};
  }
}

// Keeps the sense of directions a refit may flip (outward plane normals, axis directions).
void keep_sense(Shape& fitted, const Shape& before) {
  if (fitted.dir.dot(before.dir) < 0.0 && fitted.type != ShapeType::line && fitted.type != ShapeType::arc)
    fitted.dir = -fitted.dir;
}

Vector3d face_normal(const std::vector<Vector3d>& p, const std::array<int, 3>& f) {
  return (p[f[1]] - p[f[0]]).cross(p[f[2]] - p[f[0]]);
}

}  // namespace

// A patch whose fit rms is at most this is a CAD tessellation (its vertices lie on the surface).
constexpr double kCleanRms = 1e-3;

struct Editor::Impl {
  Mesh mesh;
  features::FeatureSet fs;
  EditOptions opt;
  std::vector<Vector3d> pos, original;
  std::vector<std::array<int, 3>> faces;
  std::vector<std::vector<int>> patch_verts, line_verts;
  Incidence vertex_patches, vertex_lines;
  std::vector<int> vv_start, vv;  // vertex → neighbouring vertices (compressed rows)
  Incidence vertex_faces;
  std::vector<int> face_patch;
  std::map<std::string, FeatureRef> by_id;
  std::set<FeatureRef> locks;
  double diagonal = 1.0;
  double total_area = 0.0;
  // The last ARAP region and its factorisation (reused while the same region is edited).
  struct Cache {
    std::vector<int> free_patches, handles;
    std::unique_ptr<ArapSolver> solver;
  } cache;
  // The last region found (dragging the same features finds the same one again).
  struct RegionCache {
    std::vector<int> free_patches, handles, unknowns, changed_faces;
    std::vector<std::array<int, 3>> region_faces;
    double reach = -1.0;
    bool valid = false;
  } region_cache;

  const Shape& shape(FeatureRef f) const {
    return f.kind == FeatureRef::Kind::patch ? fs.patches[f.index].shape : fs.lines[f.index].shape;
  }
  Shape& shape(FeatureRef f) {
    return f.kind == FeatureRef::Kind::patch ? fs.patches[f.index].shape : fs.lines[f.index].shape;
  }
  const std::string& id(FeatureRef f) const {
    return f.kind == FeatureRef::Kind::patch ? fs.patches[f.index].id : fs.lines[f.index].id;
  }
  const std::vector<int>& verts(FeatureRef f) const {
    return f.kind == FeatureRef::Kind::patch ? patch_verts[f.index] : line_verts[f.index];
  }
  std::vector<FeatureRef> members(const features::Group& g) const {
    std::vector<FeatureRef> out;
    for (const auto& m : g.members)
      if (auto it = by_id.find(m); it != by_id.end()) out.push_back(it->second);
    return out;
  }
  Vector3d centroid(FeatureRef f) const {
    if (f.kind == FeatureRef::Kind::line) {
      Vector3d c = Vector3d::Zero();
      for (int v : line_verts[f.index]) c += pos[v];
      return line_verts[f.index].empty() ? c : Vector3d(c / line_verts[f.index].size());
    }
    Vector3d c = Vector3d::Zero();
    double a = 0.0;
    for (int fi : fs.patches[f.index].faces) {
      const auto& t = faces[fi];
      const double w = 0.5 * face_normal(pos, t).norm();
      c += w * (pos[t[0]] + pos[t[1]] + pos[t[2]]) / 3.0;
      a += w;
    }
    return a > 0.0 ? Vector3d(c / a) : c;
  }
  std::vector<Vector3d> points(const std::vector<int>& vs) const {
    std::vector<Vector3d> p;
    p.reserve(vs.size());
    for (int v : vs) p.push_back(pos[v]);
    return p;
  }
  std::vector<Vector3d> line_points(int l) const {
    std::vector<Vector3d> p;
    for (int v : fs.lines[l].vertices) p.push_back(pos[v]);
    return p;
  }
  double patch_area(int p) const {
    double a = 0.0;
    for (int fi : fs.patches[p].faces) a += 0.5 * face_normal(pos, faces[fi]).norm();
    return a;
  }
  double rms_to(const Shape& s, const std::vector<int>& vs) const {
    if (vs.empty() || s.type == ShapeType::freeform) return 0.0;
    double sum = 0.0;
    for (int v : vs) sum += std::pow(features::distance(s, pos[v]), 2);
    return std::sqrt(sum / vs.size());
  }
  bool holds(const ConstraintResidual& r) const {
    return edit::holds(r, opt.angle_tolerance_deg, opt.length_tolerance);
  }
  std::vector<int> groups_of(FeatureRef f) const {
    std::vector<int> out;
    const std::string& fid = id(f);
    for (int g = 0; g < static_cast<int>(fs.groups.size()); ++g)
      if (fs.groups[g].constraint && std::find(fs.groups[g].members.begin(), fs.groups[g].members.end(), fid) !=
                                         fs.groups[g].members.end())
        out.push_back(g);
    return out;
  }
  std::string group_text(int g) const {
    const auto& gr = fs.groups[g];
    return fmt::format("{} {}({})", gr.id, features::constraint_name(*gr.constraint), fmt::join(gr.members, ", "));
  }
  /// Worst pairwise residual of a group against its first member (shapes from `shape_of`).
  template <class ShapeOf>
  ConstraintResidual group_residual(int g, ShapeOf&& shape_of) const {
    const auto& gr = fs.groups[g];
    ConstraintResidual worst;
    const auto ms = members(gr);
    for (std::size_t k = 1; k < ms.size(); ++k) {
      const ConstraintResidual r = pair_residual(spec_of(gr), shape_of(ms[0]), shape_of(ms[k]));
      if (!r.checked) continue;
      worst.checked = true;
      worst.angle_deg = std::max(worst.angle_deg, r.angle_deg);
      worst.length = std::max(worst.length, r.length);
    }
    return worst;
  }

  // The patches sharing a moved vertex with the modified features (not modified themselves);
  // small patches (crumbs along a scan's rounded edges) pass the freedom on to their neighbours.
  std::set<int> first_ring(const std::unordered_map<int, Vector3d>& target, const std::map<FeatureRef, Shape>& modified) const {
    std::set<int> free_set;
    for (const auto& entry : target) {
      const int v = entry.first;  // a named copy: lambdas may not capture structured bindings before C++20
      if ((entry.second - pos[v]).norm() <= 0.0) continue;
      vertex_patches.each(v, [&](int q) {
        const FeatureRef r{FeatureRef::Kind::patch, q};
        if (modified.count(r)) return;
        if (locks.count(r))
          throw ProcessingError(fmt::format("the edit moves vertex {} of {}, which is locked", v, fs.patches[q].id));
        free_set.insert(q);
      });
    }
    std::vector<int> small;
    for (int q : free_set)
      if (is_small(q)) small.push_back(q);
    while (!small.empty()) {
      const int q = small.back();
      small.pop_back();
      for (int v : patch_verts[q])
        vertex_patches.each(v, [&](int r) {
          const FeatureRef fr{FeatureRef::Kind::patch, r};
          if (modified.count(fr) || locks.count(fr) || !free_set.insert(r).second) return;
          if (is_small(r)) small.push_back(r);
        });
    }
    return free_set;
  }
  // The crumbs of an edited patch: small patches (is_small) reached from it through shared
  // vertices, directly or through other such crumbs, whose every vertex lies within the carry band
  // of its surface before the edit. On a scan they are pieces of the same surface that the
  // features stage could not merge (a hole wall that repair filled 0.1–0.5 mm inside it, a
  // rounded rim): they take the feature's map instead of lagging behind as ARAP neighbours, which
  // left the widened hole wall of the plate scan with dents of up to 0.4 mm.
  std::vector<int> crumbs_of(int q, const std::map<FeatureRef, Shape>& modified) const {
    std::vector<int> out;
    if (opt.carry_band_fraction <= 0.0 || fs.patches[q].shape.type == ShapeType::freeform) return out;
    const Shape& s = fs.patches[q].shape;
    const double band = opt.carry_band_fraction * diagonal;
    std::set<int> seen{q};
    std::vector<int> stack{q};
    while (!stack.empty()) {
      const int p = stack.back();
      stack.pop_back();
      for (int v : patch_verts[p])
        vertex_patches.each(v, [&](int r) {
          if (!seen.insert(r).second) return;
          const FeatureRef fr{FeatureRef::Kind::patch, r};
          if (!is_small(r) || modified.count(fr) || locks.count(fr)) return;
          for (int w : patch_verts[r])
            if (!(features::distance(s, pos[w]) <= band)) return;
          out.push_back(r);
          stack.push_back(r);
        });
    }
    std::sort(out.begin(), out.end());
    return out;
  }
  bool is_small(int q) const {
    return fs.patches[q].shape.type == ShapeType::freeform || fs.patches[q].area < opt.small_patch_fraction * total_area;
  }
  // Frees every patch sharing a vertex with a free one (not modified, not locked).
  void grow_ring(std::set<int>& free_set, const std::map<FeatureRef, Shape>& modified) const {
    const std::vector<int> current(free_set.begin(), free_set.end());
    for (int q : current)
      for (int v : patch_verts[q])
        vertex_patches.each(v, [&](int r) {
          const FeatureRef fr{FeatureRef::Kind::patch, r};
          if (!modified.count(fr) && !locks.count(fr)) free_set.insert(r);
        });
  }
  // How far from a moved vertex the free region reaches: `influence` times half the size of the
  // largest modified feature, and at least four times the largest displacement. A hole's
  // neighbourhood then stays a disc around it however large the plane it sits in.
  double influence_radius(const std::map<FeatureRef, Shape>& modified, const std::unordered_map<int, Vector3d>& target) const {
    if (opt.influence <= 0.0 || opt.whole_mesh) return std::numeric_limits<double>::infinity();
    double size = 0.0, moved = 0.0;
    for (const auto& [f, s] : modified) {
      Eigen::AlignedBox3d box;
      for (int v : verts(f)) box.extend(original[v]);  // stable while a feature is dragged
      if (!box.isEmpty()) size = std::max(size, box.diagonal().norm());
    }
    for (const auto& [v, p] : target) moved = std::max(moved, (p - pos[v]).norm());
    if (size == 0.0) size = 2.0 * std::sqrt(total_area);  // vertex edits: the whole free patches
    return std::max(opt.influence * 0.5 * size, 4.0 * moved);
  }
  // The unknowns: vertices of free patches that are not handles, touch only free patches and lie
  // within `reach` of a moved vertex (graph distance along edges). `region_faces` receives the
  // faces of free patches with an unknown corner (the ARAP energy) and `changed_faces` those with
  // an unknown or a handle corner (the fold check).
  std::vector<int> region_unknowns(const std::set<int>& free_set, const std::unordered_map<int, Vector3d>& target,
                                   double reach, std::vector<std::array<int, 3>>& region_faces,
                                   std::vector<int>& changed_faces) const {
    std::vector<char> free_patch(fs.patches.size(), 0), handle(pos.size(), 0);
    for (int q : free_set) free_patch[q] = 1;
    for (const auto& [v, p] : target) handle[v] = 1;
    // A candidate: not a handle, and every patch around it is free. Decided lazily (0 unknown,
    // 1 yes, 2 no) so that the cost follows the region, not the size of the patches it lies in.
    std::vector<char> state(pos.size(), 0);
    auto candidate = [&](int v) {
      if (state[v] == 0) {
        bool ok = !handle[v] && vertex_patches.start[v] < vertex_patches.start[v + 1];
        vertex_patches.each(v, [&](int r) { ok = ok && free_patch[r]; });
        vertex_lines.each(v, [&](int l) { ok = ok && !locks.count({FeatureRef::Kind::line, l}); });
        state[v] = ok ? 1 : 2;
      }
      return state[v] == 1;
    };
    std::vector<int> unknowns;
    if (std::isinf(reach)) {
      for (int q : free_set)
        for (int v : patch_verts[q])
          if (state[v] == 0 && candidate(v)) unknowns.push_back(v);
      std::sort(unknowns.begin(), unknowns.end());
      unknowns.erase(std::unique(unknowns.begin(), unknowns.end()), unknowns.end());
    } else {
      // Multi-source Dijkstra from the moved vertices through candidates, on the rest shape.
      std::vector<double> dist(pos.size(), std::numeric_limits<double>::infinity());
      using Item = std::pair<double, int>;
      std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
      for (const auto& [v, p] : target)
        if ((p - pos[v]).squaredNorm() > 0.0) {
          dist[v] = 0.0;
          queue.push({0.0, v});
        }
      while (!queue.empty()) {
        const auto [d, v] = queue.top();
        queue.pop();
        if (d > dist[v]) continue;
        if (!handle[v]) unknowns.push_back(v);
        for (int e = vv_start[v]; e < vv_start[v + 1]; ++e) {
          const int w = vv[e];
          const double dw = d + (original[w] - original[v]).norm();  // stable while dragging
          if (dw <= reach && dw < dist[w] && candidate(w)) {
            dist[w] = dw;
            queue.push({dw, w});
          }
        }
      }
      std::sort(unknowns.begin(), unknowns.end());
    }
    // Faces of free patches around unknowns (the energy) and around unknowns or handles (the fold
    // check), found through the vertices' incident faces.
    std::vector<char> kind(faces.size(), 0);  // 1 changed, 2 changed and in the energy
    std::vector<int> touched;
    auto visit = [&](int v, char k) {
      vertex_faces.each(v, [&](int f) {
        const int q = face_patch[f];
        if (q < 0 || !free_patch[q]) return;
        if (kind[f] == 0) touched.push_back(f);
        kind[f] = std::max(kind[f], k);
      });
    };
    for (int v : unknowns) visit(v, 2);
    for (const auto& [v, p] : target) visit(v, 1);
    std::sort(touched.begin(), touched.end());
    for (int f : touched) {
      changed_faces.push_back(f);
      if (kind[f] == 2) region_faces.push_back(faces[f]);
    }
    return unknowns;
  }
  // Free analytic patches go back onto the shape their border spans (handles and fixed vertices,
  // which the edit placed or kept), each vertex keeping its signed offset from the patch's shape
  // before the edit: a CAD tessellation (offsets 0) lands exactly on it, so stretched planes stay
  // planes; a scan keeps its noise while the patch's fitted shape follows the border instead of
  // ARAP's compromise. `before`: positions before this edit of the vertices it moved.
  void snap_patches(const std::vector<int>& free_patches, const std::vector<int>& unknowns,
                    const std::unordered_map<int, Vector3d>& before) {
    if (opt.snap_max_rms < 0.0) return;
    std::vector<char> unknown(pos.size(), 0);
    for (int v : unknowns) unknown[v] = 1;
    auto old_pos = [&](int v) -> const Vector3d& {
      auto it = before.find(v);
      return it != before.end() ? it->second : pos[v];
    };
    // Per patch: its unknowns, and its border: the vertices next to them that the solve kept
    // (handles, fixed) — the ring that determines where the region must lie.
    std::map<int, std::vector<int>> inner, border;
    std::vector<char> in_border(pos.size(), 0);
    for (int v : unknowns)
      vertex_patches.each(v, [&](int q) { inner[q].push_back(v); });
    for (int v : unknowns)
      for (int e = vv_start[v]; e < vv_start[v + 1]; ++e) {
        const int w = vv[e];
        if (unknown[w] || in_border[w]) continue;
        in_border[w] = 1;
        vertex_patches.each(w, [&](int q) { border[q].push_back(w); });
      }
    for (int q : free_patches) {
      const Shape& s = fs.patches[q].shape;
      if (s.type == ShapeType::freeform || fs.patches[q].rms > opt.snap_max_rms || !inner.count(q)) continue;
      auto offset = [&](int v) {
        const Vector3d& p = old_pos(v);
        return (p - project_onto(s, p)).dot(features::surface_normal(s, p));
      };
      std::vector<Vector3d> ring;
      for (int v : border[q]) ring.push_back(pos[v] - offset(v) * features::surface_normal(s, pos[v]));
      if (ring.size() < 8) continue;
      const features::Fit fit = refit(s.type, ring, false);
      if (!fit.ok) continue;
      spdlog::debug("snap {}: {} inner, {} border vertices, axis turned {:.4f}°", fs.patches[q].id, inner[q].size(),
                    ring.size(), std::acos(std::min(1.0, std::abs(fit.shape.dir.dot(s.dir)))) * 180 / M_PI);
      // On a scan only vertices whose faces lie along the surface move (within 30° of its normal):
      // the steep faces of a rounded edge would fold if their corners moved along the normal.
      const bool clean = fs.patches[q].rms <= kCleanRms;
      auto along_surface = [&](int v) {
        const Vector3d sn = features::surface_normal(s, old_pos(v));
        bool along = true;
        vertex_faces.each(v, [&](int f) {
          const auto& t = faces[f];
          const Vector3d n = (old_pos(t[1]) - old_pos(t[0])).cross(old_pos(t[2]) - old_pos(t[0]));
          along = along && n.norm() > 0.0 && std::abs(n.normalized().dot(sn)) >= std::cos(30.0 * M_PI / 180.0);
        });
        return along;
      };
      // The refit's normal has no preferred sign: the offsets are measured along the patch's own
      // normal, so they go back along the refitted one turned the same way (a flipped plane
      // normal mirrored a scan's noise through the plane: 0.01 mm bumps became 0.01 mm dents,
      // and the side of the plate scan whose top was raised tilted by 0.06° with them).
      auto normal_after = [&](const Vector3d& p) {
        const Vector3d n = features::surface_normal(fit.shape, p);
        return n.dot(features::surface_normal(s, p)) < 0.0 ? Vector3d(-n) : n;
      };
      for (int v : inner[q])
        if (clean || along_surface(v)) pos[v] = project_onto(fit.shape, pos[v]) + offset(v) * normal_after(pos[v]);
    }
  }
  // The first face that folded over (its normal turned by more than 90° from where the edit
  // takes it) or collapsed; -1 when none.
  int first_folded(const std::vector<int>& checked, const std::vector<Vector3d>& before,
                   const std::map<FeatureRef, Eigen::Matrix3d>& turned) const {
    for (std::size_t k = 0; k < checked.size(); ++k) {
      const Vector3d n = face_normal(pos, faces[checked[k]]);
      const Vector3d& n0 = before[k];
      Vector3d expected = n0;
      if (auto it = turned.find({FeatureRef::Kind::patch, face_patch[checked[k]]}); it != turned.end())
        expected = it->second * n0;
      // Faces that were degenerate before the edit are not judged (their normal means nothing).
      if (n0.norm() > 0.0 && (n.norm() <= 1e-12 * n0.norm() || n.dot(expected) <= 0.0)) {
        const auto& t = faces[checked[k]];
        spdlog::debug("folded face {}: n0 {} {} {} n {} {} {}; corners {} {} {} at {} {} {} / {} {} {} / {} {} {}", checked[k], n0.x(), n0.y(), n0.z(), n.x(), n.y(), n.z(), t[0], t[1], t[2],
                      pos[t[0]].x(), pos[t[0]].y(), pos[t[0]].z(), pos[t[1]].x(), pos[t[1]].y(), pos[t[1]].z(), pos[t[2]].x(), pos[t[2]].y(), pos[t[2]].z());
        return checked[k];
      }
    }
    return -1;
  }

  EditReport run(const std::vector<std::pair<FeatureRef, ShapeMap>>& initial,
                 const std::unordered_map<int, Vector3d>& vertex_targets = {});
  void remove_groups(const std::set<int>& drop);
};

Editor::Editor(Mesh mesh, features::FeatureSet fs, EditOptions options) : impl_(std::make_unique<Impl>()) {
  Impl& m = *impl_;
  m.mesh = std::move(mesh);
  m.fs = std::move(fs);
  m.opt = options;
  const int nv = static_cast<int>(m.mesh.n_vertices()), nf = static_cast<int>(m.mesh.n_faces());
  if (m.fs.mesh_vertices != nv || m.fs.mesh_faces != nf)
    throw InvalidInput(fmt::format("the features describe a mesh of {} vertices and {} faces, the mesh has {} and {}",
                                   m.fs.mesh_vertices, m.fs.mesh_faces, nv, nf));
  m.pos.resize(nv);
  for (auto v : m.mesh.vertices()) m.pos[v.idx()] = to_eigen(m.mesh.point(v));
  m.original = m.pos;
  m.faces.resize(nf);
  for (auto f : m.mesh.faces()) {
    int k = 0;
    for (auto v : m.mesh.fv_range(f)) m.faces[f.idx()][k++] = v.idx();
  }
  m.face_patch.assign(nf, -1);
  m.patch_verts.resize(m.fs.patches.size());
  for (int p = 0; p < static_cast<int>(m.fs.patches.size()); ++p) {
    auto& vs = m.patch_verts[p];
    for (int f : m.fs.patches[p].faces) {
      if (f < 0 || f >= nf) throw InvalidInput(fmt::format("patch {} names face {}, the mesh has {}", m.fs.patches[p].id, f, nf));
      m.face_patch[f] = p;
      vs.insert(vs.end(), m.faces[f].begin(), m.faces[f].end());
    }
    std::sort(vs.begin(), vs.end());
    vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
    m.by_id[m.fs.patches[p].id] = {FeatureRef::Kind::patch, p};
  }
  m.line_verts.resize(m.fs.lines.size());
  for (int l = 0; l < static_cast<int>(m.fs.lines.size()); ++l) {
    auto vs = m.fs.lines[l].vertices;
    for (int v : vs)
      if (v < 0 || v >= nv) throw InvalidInput(fmt::format("line {} names vertex {}, the mesh has {}", m.fs.lines[l].id, v, nv));
    std::sort(vs.begin(), vs.end());
    vs.erase(std::unique(vs.begin(), vs.end()), vs.end());
    m.line_verts[l] = std::move(vs);
    m.by_id[m.fs.lines[l].id] = {FeatureRef::Kind::line, l};
  }
  m.vertex_patches.build(nv, m.patch_verts);
  m.vertex_lines.build(nv, m.line_verts);
  m.vertex_faces.build(nv, m.faces);
  {
    std::vector<std::vector<int>> nb(nv);
    for (const auto& t : m.faces)
      for (int c = 0; c < 3; ++c) {
        nb[t[c]].push_back(t[(c + 1) % 3]);
        nb[t[c]].push_back(t[(c + 2) % 3]);
      }
    m.vv_start.assign(nv + 1, 0);
    for (int v = 0; v < nv; ++v) {
      std::sort(nb[v].begin(), nb[v].end());
      nb[v].erase(std::unique(nb[v].begin(), nb[v].end()), nb[v].end());
      m.vv_start[v + 1] = m.vv_start[v] + static_cast<int>(nb[v].size());
    }
    m.vv.reserve(m.vv_start[nv]);
    for (const auto& n : nb) m.vv.insert(m.vv.end(), n.begin(), n.end());
  }
  const Bounds b = bounds(m.mesh);
  m.diagonal = std::max(b.diagonal(), 1e-9);
  for (const auto& p : m.fs.patches) m.total_area += p.area;
}

Editor::~Editor() = default;
Editor::Editor(Editor&&) noexcept = default;
Editor& Editor::operator=(Editor&&) noexcept = default;

const Mesh& Editor::mesh() const { return impl_->mesh; }
const features::FeatureSet& Editor::features() const { return impl_->fs; }
const EditOptions& Editor::options() const { return impl_->opt; }

std::vector<FeatureRef> Editor::all() const {
  std::vector<FeatureRef> out;
  for (int p = 0; p < static_cast<int>(impl_->fs.patches.size()); ++p) out.push_back({FeatureRef::Kind::patch, p});
  for (int l = 0; l < static_cast<int>(impl_->fs.lines.size()); ++l) out.push_back({FeatureRef::Kind::line, l});
  return out;
}
std::optional<FeatureRef> Editor::find(const std::string& id) const {
  auto it = impl_->by_id.find(id);
  if (it == impl_->by_id.end()) return std::nullopt;
  return it->second;
}
const std::string& Editor::id(FeatureRef f) const { return impl_->id(f); }
const Shape& Editor::shape(FeatureRef f) const { return impl_->shape(f); }
Vector3d Editor::centroid(FeatureRef f) const { return impl_->centroid(f); }
double Editor::area(FeatureRef f) const {
  return f.kind == FeatureRef::Kind::patch ? impl_->fs.patches[f.index].area : 0.0;
}
double Editor::length(FeatureRef f) const {
  if (f.kind != FeatureRef::Kind::line) return 0.0;
  const auto p = impl_->line_points(f.index);
  double len = 0.0;
  for (std::size_t k = 1; k < p.size(); ++k) len += (p[k] - p[k - 1]).norm();
  if (impl_->fs.lines[f.index].closed && p.size() > 2) len += (p.front() - p.back()).norm();
  return len;
}
const std::vector<int>& Editor::vertices(FeatureRef f) const { return impl_->verts(f); }

std::vector<FeatureRef> Editor::neighbours(FeatureRef f) const {
  std::set<FeatureRef> out;
  for (int v : impl_->verts(f)) {
    impl_->vertex_patches.each(v, [&](int p) { out.insert({FeatureRef::Kind::patch, p}); });
    impl_->vertex_lines.each(v, [&](int l) { out.insert({FeatureRef::Kind::line, l}); });
  }
  out.erase(f);
  return {out.begin(), out.end()};
}

std::vector<FeatureRef> Editor::select(const std::function<bool(FeatureRef)>& keep) const {
  std::vector<FeatureRef> out;
  for (FeatureRef f : all())
    if (keep(f)) out.push_back(f);
  return out;
}

// ---- edits ------------------------------------------------------------------------------------

namespace {
Vector3d selection_centre(const Editor& ed, const std::vector<FeatureRef>& fs) {
  Vector3d c = Vector3d::Zero();
  for (FeatureRef f : fs) c += ed.centroid(f);
  return fs.empty() ? c : Vector3d(c / fs.size());
}
void require_some(const std::vector<FeatureRef>& fs, const char* what) {
  if (fs.empty()) throw InvalidInput(fmt::format("{}: the selection holds no feature", what));
}
}  // namespace

EditReport Editor::set_radius(const std::vector<FeatureRef>& fs, double radius) {
  require_some(fs, "set radius");
  if (!(radius > 0.0) || !std::isfinite(radius)) throw InvalidInput(fmt::format("radius {} must be > 0 mm", radius));
  std::vector<std::pair<FeatureRef, ShapeMap>> edits;
  for (FeatureRef f : fs) {
    Shape t = shape(f);
    if (radius_of(t) <= 0.0)
      throw InvalidInput(fmt::format("{} is a {}: only cylinders, spheres, circles and arcs have a radius", id(f),
                                     features::shape_name(t.type)));
    t.radius = radius;
    edits.emplace_back(f, ShapeMap::resize(shape(f), t));
  }
  return impl_->run(edits);
}

EditReport Editor::set_half_angle(const std::vector<FeatureRef>& fs, double degrees) {
  require_some(fs, "set half_angle");
  if (!(degrees > 0.0 && degrees < 90.0)) throw InvalidInput(fmt::format("half angle {}° must be in (0°, 90°)", degrees));
  std::vector<std::pair<FeatureRef, ShapeMap>> edits;
  for (FeatureRef f : fs) {
    Shape t = shape(f);
    if (t.type != ShapeType::cone)
      throw InvalidInput(fmt::format("{} is a {}: only cones have a half angle", id(f), features::shape_name(t.type)));
    t.half_angle_deg = degrees;
    edits.emplace_back(f, ShapeMap::resize(shape(f), t));
  }
  return impl_->run(edits);
}

EditReport Editor::move(const std::vector<FeatureRef>& fs, const Vector3d& by) {
  require_some(fs, "move");
  std::vector<std::pair<FeatureRef, ShapeMap>> edits;
  for (FeatureRef f : fs) edits.emplace_back(f, ShapeMap::translation(by));
  return impl_->run(edits);
}

EditReport Editor::rotate(const std::vector<FeatureRef>& fs, const Vector3d& axis, double degrees,
                          const std::optional<Vector3d>& pivot) {
  require_some(fs, "rotate");
  if (!(axis.norm() > 0.0)) throw InvalidInput("rotate: the axis is the zero vector");
  const ShapeMap m = ShapeMap::rotation(axis, degrees, pivot.value_or(selection_centre(*this, fs)));
  std::vector<std::pair<FeatureRef, ShapeMap>> edits;
  for (FeatureRef f : fs) edits.emplace_back(f, m);
  return impl_->run(edits);
}

EditReport Editor::scale(const std::vector<FeatureRef>& fs, double factor, const std::optional<Vector3d>& pivot) {
  require_some(fs, "scale");
  if (!(factor > 0.0) || !std::isfinite(factor)) throw InvalidInput(fmt::format("scale factor {} must be > 0", factor));
  const ShapeMap m = ShapeMap::scaling(factor, pivot.value_or(selection_centre(*this, fs)));
  std::vector<std::pair<FeatureRef, ShapeMap>> edits;
  for (FeatureRef f : fs) edits.emplace_back(f, m);
  return impl_->run(edits);
}

EditReport Editor::move_vertices(const std::vector<int>& vs, const std::vector<Vector3d>& targets) {
  if (vs.size() != targets.size()) throw InvalidInput("move_vertices: as many targets as vertices are needed");
  if (vs.empty()) throw InvalidInput("move_vertices: no vertex given");
  // Bubbling (paper §4.1): the vertices are handles; the patches holding them are solved by ARAP
  // inside their borders and refitted, so the edit rises to their shapes.
  std::unordered_map<int, Vector3d> moved;
  for (std::size_t k = 0; k < vs.size(); ++k) {
    if (vs[k] < 0 || vs[k] >= static_cast<int>(impl_->pos.size()))
      throw InvalidInput(fmt::format("move_vertices: vertex {} does not exist (the mesh has {})", vs[k], impl_->pos.size()));
    if (!targets[k].allFinite()) throw InvalidInput(fmt::format("move_vertices: the target of vertex {} is not finite", vs[k]));
    moved[vs[k]] = targets[k];
  }
  return impl_->run({}, moved);
}

// ---- the edit transaction ---------------------------------------------------------------------

EditReport Editor::Impl::run(const std::vector<std::pair<FeatureRef, ShapeMap>>& initial,
                             const std::unordered_map<int, Vector3d>& vertex_targets) {
  const auto t0 = std::chrono::steady_clock::now();
  EditReport rep;
  std::map<FeatureRef, Shape> new_shape;
  std::unordered_map<int, Vector3d> target = vertex_targets;
  std::map<FeatureRef, Eigen::Matrix3d> turned;  // the linear part of each modified feature's map
  auto current = [&](FeatureRef f) -> const Shape& {
    auto it = new_shape.find(f);
    return it != new_shape.end() ? it->second : shape(f);
  };
  // Each map moves a vertex once, however many of the features it is applied to share it (a
  // cylinder and its rim circles moved together); `map_id` names the map.
  std::unordered_map<int, int> moved_by;  // vertex → the last map that moved it
  int next_map = 0;
  // The vertices `vs` of (or carried by) feature f go where `map` takes them.
  auto move_by = [&](FeatureRef f, const std::vector<int>& vs, const ShapeMap& map, int map_id) {
    for (int v : vs) {
      auto seen = moved_by.find(v);
      if (seen != moved_by.end() && seen->second == map_id) continue;
      moved_by[v] = map_id;
      auto it = target.find(v);
      const Vector3d base = it != target.end() ? it->second : pos[v];
      // A resize keeps each vertex's offset from the feature's surface before the edit.
      const Vector3d to = map.kind == ShapeMap::Kind::resize ? resize_point(shape(f), map.target, pos[v], base) : map.apply(base);
      if (!to.allFinite())
        throw InvalidInput(fmt::format("{}: the edit takes vertex {} beyond the range of numbers", id(f), v));
      target[v] = to;
    }
  };
  auto apply_map = [&](FeatureRef f, const ShapeMap& map, int map_id) {
    if (locks.count(f) && !map.is_identity())
      throw ProcessingError(fmt::format("{} is locked and the edit would change it ({})", id(f), map.describe(shape(f))));
    const Shape moved = map.apply(current(f));
    if (!finite_shape(moved))
      throw InvalidInput(fmt::format("{}: the edit takes its shape beyond the range of numbers ({})", id(f), map.describe(shape(f))));
    new_shape[f] = moved;
    if (map.kind == ShapeMap::Kind::affine) turned[f] = map.linear * (turned.count(f) ? turned[f] : Eigen::Matrix3d::Identity());
    move_by(f, verts(f), map, map_id);
    // A modified patch takes its crumbs along (crumbs_of): their vertices get the same map.
    if (f.kind != FeatureRef::Kind::patch) return;
    for (int c : crumbs_of(f.index, new_shape)) {
      move_by(f, patch_verts[c], map, map_id);
      const FeatureRef cr{FeatureRef::Kind::patch, c};
      if (std::find(rep.carried.begin(), rep.carried.end(), cr) == rep.carried.end()) rep.carried.push_back(cr);
    }
  };
  std::deque<FeatureRef> queue;
  {
    // Features sharing one map (move/rotate/scale of a selection) share its id.
    const ShapeMap* previous = nullptr;
    for (const auto& [f, map] : initial) {
      const bool same = previous && previous->kind == ShapeMap::Kind::affine && map.kind == ShapeMap::Kind::affine &&
                        previous->linear == map.linear && previous->offset == map.offset;
      if (!same) ++next_map;
      apply_map(f, map, next_map);
      previous = &map;
      rep.edited.push_back(f);
      queue.push_back(f);
    }
  }
  // Greedy propagation over the constraint groups (paper §4.3), patches only: line constraints
  // follow from the patches the lines bound.
  // A constraint is kept when its residual did not grow beyond the tolerances: on a scan the
  // constraints hold only to the detection tolerance, and an edit must not "repair" them all.
  auto kept = [&](const features::Group& gr, FeatureRef a, FeatureRef b) {
    const ConstraintSpec spec = spec_of(gr);
    const ConstraintResidual after = pair_residual(spec, current(a), current(b));
    if (!after.checked) return true;
    const ConstraintResidual before = pair_residual(spec, shape(a), shape(b));
    return after.angle_deg <= before.angle_deg + opt.angle_tolerance_deg &&
           after.length <= before.length + opt.length_tolerance;
  };
  std::map<FeatureRef, int> adjusted;  // how often propagation changed each feature
  constexpr int kMaxAdjustments = 4;   // one per independent parameter group (direction, position, size, …)
  while (opt.propagate && !queue.empty()) {
    const FeatureRef f = queue.front();
    queue.pop_front();
    if (f.kind != FeatureRef::Kind::patch) continue;
    for (int g : groups_of(f)) {
      const auto& gr = fs.groups[g];
      // Mirror symmetry is found by the features stage, seldom designed: it does not drive
      // propagation; when an edit breaks it, it is reported and dropped (see the end of run).
      if (*gr.constraint == ConstraintKind::symmetric) continue;
      for (FeatureRef other : members(gr)) {
        if (other == f || other.kind != FeatureRef::Kind::patch) continue;
        // Greedy propagation stops at features the user edited; a feature propagation already
        // changed may change again for another constraint (a hole turned parallel, then resized).
        const bool user_edited = std::find(rep.edited.begin(), rep.edited.end(), other) != rep.edited.end();
        if (user_edited || adjusted[other] >= kMaxAdjustments || kept(gr, f, other)) continue;
        const auto adj = adjustment(spec_of(gr), current(f), current(other), centroid(other));
        if (!adj)
          throw ProcessingError(fmt::format(
              "constraint {} would no longer hold and {} cannot be adjusted to keep it: unconstrain it or edit "
              "both features",
              group_text(g), id(other)));
        if (locks.count(other))
          throw ProcessingError(fmt::format("constraint {} would move {}, which is locked: unconstrain it or unlock",
                                            group_text(g), id(other)));
        rep.propagation.push_back(fmt::format("{} {}: {} {}", gr.id, features::constraint_name(*gr.constraint),
                                              id(other), adj->describe(current(other))));
        apply_map(other, *adj, ++next_map);
        ++adjusted[other];
        if (std::find(rep.propagated.begin(), rep.propagated.end(), other) == rep.propagated.end())
          rep.propagated.push_back(other);
        queue.push_back(other);
      }
    }
  }
  // Constraints among modified features must hold: propagation stopped at them.
  for (int g = 0; g < static_cast<int>(fs.groups.size()); ++g) {
    if (!fs.groups[g].constraint || *fs.groups[g].constraint == ConstraintKind::symmetric) continue;
    std::vector<FeatureRef> mod;
    for (FeatureRef f : members(fs.groups[g]))
      if (f.kind == FeatureRef::Kind::patch && new_shape.count(f)) mod.push_back(f);
    for (std::size_t k = 1; k < mod.size(); ++k) {
      if (kept(fs.groups[g], mod[0], mod[k])) continue;
      const auto r = pair_residual(spec_of(fs.groups[g]), new_shape[mod[0]], new_shape[mod[k]]);
      throw ProcessingError(fmt::format("conflict: constraint {} between {} and {} cannot hold after the edit "
                                        "(residual {:.3g}°, {:.3g} mm); both are set by it",
                                        group_text(g), id(mod[0]), id(mod[k]), r.angle_deg, r.length));
    }
  }

  // A locked line keeps its vertices: the edit may not move them, ARAP keeps them fixed.
  // (Named copies, not structured bindings: lambdas may not capture those before C++20.)
  for (const auto& entry : target) {
    const int v = entry.first;
    if ((entry.second - pos[v]).squaredNorm() > 0.0)
      vertex_lines.each(v, [&](int l) {
        if (locks.count({FeatureRef::Kind::line, l}))
          throw ProcessingError(fmt::format("the edit moves vertex {} of {}, which is locked", v, fs.lines[l].id));
      });
  }
  auto lap = std::chrono::steady_clock::now();
  auto step = [&](double& into) {
    const auto now = std::chrono::steady_clock::now();
    into += std::chrono::duration<double>(now - lap).count();
    lap = now;
  };
  step(rep.time.propagation);
  // The ARAP region (paper §4.2): patches sharing a moved vertex are free, the rest fixed.
  std::vector<int> handles;
  for (const auto& [v, p] : target) handles.push_back(v);
  std::sort(handles.begin(), handles.end());
  rep.handle_vertices = static_cast<int>(handles.size());
  std::set<int> free_set = first_ring(target, new_shape);
  if (opt.whole_mesh && !free_set.empty())
    for (int q = 0; q < static_cast<int>(fs.patches.size()); ++q)
      if (!new_shape.count({FeatureRef::Kind::patch, q}) && !locks.count({FeatureRef::Kind::patch, q})) free_set.insert(q);

  // Place the handles and solve; when triangles fold (a scan's strip of small patches between the
  // edited feature and a big fixed one cannot absorb the change), free the next ring and retry.
  std::vector<std::pair<int, Vector3d>> saved;
  std::vector<int> free_patches, unknowns, checked_faces;
  std::vector<Vector3d> normals_before;
  double reach = influence_radius(new_shape, target);
  for (int ring = 0;; ++ring) {
    free_patches.assign(free_set.begin(), free_set.end());
    std::vector<std::array<int, 3>> region_faces;
    checked_faces.clear();
    for (const auto& [f, s] : new_shape)
      if (f.kind == FeatureRef::Kind::patch)
        checked_faces.insert(checked_faces.end(), fs.patches[f.index].faces.begin(), fs.patches[f.index].faces.end());
    auto& rc = region_cache;
    if (rc.valid && rc.reach == reach && rc.free_patches == free_patches && rc.handles == handles) {
      unknowns = rc.unknowns;
      region_faces = rc.region_faces;
      checked_faces.insert(checked_faces.end(), rc.changed_faces.begin(), rc.changed_faces.end());
    } else {
      std::vector<int> changed;
      unknowns = region_unknowns(free_set, target, reach, region_faces, changed);
      checked_faces.insert(checked_faces.end(), changed.begin(), changed.end());
      rc = {free_patches, handles, unknowns, std::move(changed), region_faces, reach, true};
    }
    saved.clear();
    for (int v : handles) saved.emplace_back(v, pos[v]);
    for (int v : unknowns) saved.emplace_back(v, pos[v]);
    normals_before.clear();
    normals_before.reserve(checked_faces.size());
    for (int f : checked_faces) normals_before.push_back(face_normal(pos, faces[f]));

    step(rep.time.region);
    // The rest shape of a new solver is the mesh before this edit (handles not yet placed).
    const bool reuse = !unknowns.empty() && cache.solver && cache.free_patches == free_patches &&
                       cache.handles == handles && cache.solver->unknowns() == unknowns;
    if (!unknowns.empty() && !reuse) {
      cache.solver.reset();
      cache.solver = std::make_unique<ArapSolver>(pos, region_faces, unknowns);
      cache.free_patches = free_patches;
      cache.handles = handles;
    }
    step(rep.time.factorization);
    for (const auto& [v, p] : target) pos[v] = p;
    if (!unknowns.empty()) {
      rep.factorization_reused = reuse;
      rep.arap_iterations = cache.solver->solve(pos, opt.arap_iterations, opt.arap_tolerance, reuse).iterations;
      step(rep.time.solve);
      std::unordered_map<int, Vector3d> before(saved.begin(), saved.end());
      std::vector<Vector3d> solved;
      for (int v : unknowns) solved.push_back(pos[v]);
      snap_patches(free_patches, unknowns, before);
      // A snap that folds a triangle is undone: ARAP's own result stays.
      if (first_folded(checked_faces, normals_before, turned) >= 0)
        for (std::size_t k = 0; k < unknowns.size(); ++k) pos[unknowns[k]] = solved[k];
    }
    step(rep.time.snap);
    const int folded = first_folded(checked_faces, normals_before, turned);
    step(rep.time.check);
    if (folded < 0) {
      rep.extra_rings = ring;
      break;
    }
    for (const auto& [v, p] : saved) pos[v] = p;  // roll back, then widen or give up
    const std::size_t before = free_set.size();
    const double reach_before = reach;
    if (ring < opt.max_extra_rings) {
      grow_ring(free_set, new_shape);
      reach *= 2.0;
    }
    if (ring >= opt.max_extra_rings || (free_set.size() == before && reach == reach_before))
      throw ProcessingError(fmt::format(
          "the edit folds or collapses triangle {} of {} even with {} more ring(s) of neighbouring features free: the "
          "change is too large for the mesh around it (try a smaller change, or unconstrain / edit the neighbouring "
          "features too)",
          folded, fs.patches[face_patch[folded]].id, ring));
  }
  // The cached solver's rest shape is only valid while nothing else moved its region.
  if (unknowns.empty() && !target.empty()) cache = {};
  rep.free_vertices = static_cast<int>(unknowns.size());
  for (int q : free_patches) rep.free.push_back({FeatureRef::Kind::patch, q});

  // Commit: shapes, areas, rms; lines that moved are refitted.
  std::vector<Shape> patch_shapes_before, line_shapes_before;
  std::vector<double> patch_rms_before, line_rms_before;
  for (const auto& p : fs.patches) {
    patch_shapes_before.push_back(p.shape);
    patch_rms_before.push_back(p.rms);
  }
  for (const auto& l : fs.lines) {
    line_shapes_before.push_back(l.shape);
    line_rms_before.push_back(l.rms);
  }
  for (const auto& [v, p0] : saved) rep.max_displacement = std::max(rep.max_displacement, (pos[v] - p0).norm());
  for (const auto& [f, s] : new_shape) {
    if (f.kind != FeatureRef::Kind::patch) continue;
    auto& patch = fs.patches[f.index];
    patch.shape = s;
    patch.area = patch_area(f.index);
    patch.rms = rms_to(s, patch_verts[f.index]);
  }
  // Free patches: refitted on at most kRefitSamples of their vertices (a stride through them) and
  // their area updated by the faces that changed, so a huge plane around a small edit costs little.
  constexpr std::size_t kRefitSamples = 20000;
  std::map<int, double> area_change;
  for (std::size_t k = 0; k < checked_faces.size(); ++k)
    area_change[face_patch[checked_faces[k]]] +=
        0.5 * (face_normal(pos, faces[checked_faces[k]]).norm() - normals_before[k].norm());
  for (int q : free_patches) {
    auto& patch = fs.patches[q];
    if (patch.shape.type != ShapeType::freeform) {
      const auto& all = patch_verts[q];
      std::vector<int> sample;
      const std::size_t stride = (all.size() + kRefitSamples - 1) / kRefitSamples;
      for (std::size_t k = 0; k < all.size(); k += std::max<std::size_t>(stride, 1)) sample.push_back(all[k]);
      features::Fit fit = refit(patch.shape.type, points(sample), false);
      if (fit.ok) {
        keep_sense(fit.shape, patch.shape);
        patch.shape = fit.shape;
      }
      patch.rms = rms_to(patch.shape, sample);
    }
    patch.area += area_change[q];
  }
  std::set<int> moved_lines;
  for (const auto& [v, p0] : saved)
    if ((pos[v] - p0).squaredNorm() > 0.0) vertex_lines.each(v, [&](int l) { moved_lines.insert(l); });
  for (int l : moved_lines) {
    auto& line = fs.lines[l];
    if (line.shape.type == ShapeType::freeform) continue;
    features::Fit fit = refit(line.shape.type, line_points(l), line.closed);
    if (fit.ok && (fit.shape.type == line.shape.type || line.shape.type != ShapeType::line)) {
      if (line.shape.type == ShapeType::circle || line.shape.type == ShapeType::arc) keep_sense(fit.shape, line.shape);
      line.shape = fit.shape;
      line.rms = fit.rms;
    }
  }
  for (const auto& [v, p0] : saved) mesh.set_point(OpenMesh::VertexHandle(v), to_om(pos[v]));

  // Constraints among features the edit did not set that no longer hold are reported and dropped.
  std::set<FeatureRef> touched;
  for (const auto& [f, s] : new_shape) touched.insert(f);
  for (int q : free_patches) touched.insert({FeatureRef::Kind::patch, q});
  for (int l : moved_lines) touched.insert({FeatureRef::Kind::line, l});
  std::set<int> drop;
  for (int g = 0; g < static_cast<int>(fs.groups.size()); ++g) {
    if (!fs.groups[g].constraint) continue;
    bool involved = false;
    for (FeatureRef f : members(fs.groups[g])) involved = involved || touched.count(f);
    if (!involved) continue;
    if (*fs.groups[g].constraint == ConstraintKind::symmetric && !spec_of(fs.groups[g]).mirror) {
      rep.broken.push_back(fmt::format("{} cannot be verified after the edit (it names no mirror plane)",
                                       group_text(g)));
      drop.insert(g);
      continue;
    }
    const ConstraintResidual r = group_residual(g, [&](FeatureRef f) -> const Shape& { return shape(f); });
    const ConstraintResidual r0 = group_residual(g, [&](FeatureRef f) -> const Shape& {
      return f.kind == FeatureRef::Kind::patch ? patch_shapes_before[f.index] : line_shapes_before[f.index];
    });
    // Refitted shapes carry the fit's scatter: a constraint is broken when its residual grew by
    // more than ten tolerances plus three times the members' fit rms (scan noise).
    double rms = 0.0;
    for (FeatureRef f : members(fs.groups[g]))
      rms = std::max(rms, f.kind == FeatureRef::Kind::patch ? std::max(patch_rms_before[f.index], fs.patches[f.index].rms)
                                                             : std::max(line_rms_before[f.index], fs.lines[f.index].rms));
    const double len = 10.0 * opt.length_tolerance + 3.0 * rms;
    const double ang = 10.0 * opt.angle_tolerance_deg + 3.0 * rms / (0.1 * diagonal) * 180.0 / M_PI;
    if (r.checked && (r.angle_deg > r0.angle_deg + ang || r.length > r0.length + len)) {
      rep.broken.push_back(fmt::format("{} no longer holds (residual {:.3g}° / {:.3g} mm, before {:.3g}° / {:.3g} mm)",
                                       group_text(g), r.angle_deg, r.length, r0.angle_deg, r0.length));
      drop.insert(g);
    }
  }
  remove_groups(drop);
  // A new region next time may need the cache only if it is the same one; keep it.
  step(rep.time.commit);
  rep.seconds = seconds_since(t0);
  return rep;
}

void Editor::Impl::remove_groups(const std::set<int>& drop) {
  if (drop.empty()) return;
  std::set<std::string> dropped_ids;
  for (int g : drop) dropped_ids.insert(fs.groups[g].id);
  std::vector<features::Group> kept;
  for (int g = 0; g < static_cast<int>(fs.groups.size()); ++g) {
    if (drop.count(g)) continue;
    auto gr = fs.groups[g];
    gr.members.erase(std::remove_if(gr.members.begin(), gr.members.end(), [&](const std::string& m) { return dropped_ids.count(m) > 0; }),
                     gr.members.end());
    if (gr.constraint && gr.members.size() < 2) {
      dropped_ids.insert(gr.id);
      continue;
    }
    kept.push_back(std::move(gr));
  }
  fs.groups = std::move(kept);
}

// ---- constraints ------------------------------------------------------------------------------

void Editor::lock(FeatureRef f) {
  impl_->locks.insert(f);
  impl_->region_cache.valid = false;  // a locked line's vertices are no longer unknowns
}
bool Editor::locked(FeatureRef f) const { return impl_->locks.count(f) > 0; }

std::vector<int> Editor::constraints_of(const std::vector<FeatureRef>& fs) const {
  std::set<int> out;
  for (FeatureRef f : fs)
    for (int g : impl_->groups_of(f)) out.insert(g);
  return {out.begin(), out.end()};
}

ConstraintResidual Editor::residual(int g) const {
  if (g < 0 || g >= static_cast<int>(impl_->fs.groups.size()) || !impl_->fs.groups[g].constraint) return {};
  return impl_->group_residual(g, [&](FeatureRef f) -> const Shape& { return impl_->shape(f); });
}

EditReport Editor::constrain(ConstraintKind kind, const std::vector<FeatureRef>& ms, std::optional<double> value) {
  Impl& m = *impl_;
  if (ms.size() < 2) throw InvalidInput(fmt::format("constrain {} needs at least two features", features::constraint_name(kind)));
  if (kind == ConstraintKind::symmetric)
    throw InvalidInput("constrain symmetric(a, b) is not available: the script cannot give the mirror plane");
  if (kind == ConstraintKind::fixed_angle && !value)
    throw InvalidInput("constrain fixed_angle(a, b) needs a value: constrain fixed_angle(a, b) = 30");
  for (std::size_t k = 1; k < ms.size(); ++k) {
    const auto r = pair_residual({kind, value, {}}, m.shape(ms[0]), m.shape(ms[k]));
    if (!r.checked && kind != ConstraintKind::connected && kind != ConstraintKind::symmetric && kind != ConstraintKind::equal_angle)
      throw InvalidInput(fmt::format("{} does not apply to {} ({}) and {} ({})", features::constraint_name(kind), m.id(ms[0]),
                                     features::shape_name(m.shape(ms[0]).type), m.id(ms[k]),
                                     features::shape_name(m.shape(ms[k]).type)));
  }
  // Enforce: adjust every member after the first, as propagation from the first would.
  std::vector<std::pair<FeatureRef, ShapeMap>> edits;
  for (std::size_t k = 1; k < ms.size(); ++k) {
    const auto r = pair_residual({kind, value, {}}, m.shape(ms[0]), m.shape(ms[k]));
    if (m.holds(r)) continue;
    const auto adj = adjustment({kind, value, {}}, m.shape(ms[0]), m.shape(ms[k]), m.centroid(ms[k]));
    if (!adj)
      throw ProcessingError(fmt::format("{}({}, {}) does not hold and {} cannot be adjusted to make it hold",
                                        features::constraint_name(kind), m.id(ms[0]), m.id(ms[k]), m.id(ms[k])));
    edits.emplace_back(ms[k], *adj);
  }
  // The group is added first so that the edit propagates from it consistently; removed on failure.
  features::Group g;
  std::set<std::string> taken;
  for (const auto& gr : m.fs.groups) taken.insert(gr.id);
  std::size_t next = m.fs.groups.size();
  while (taken.count(fmt::format("G{}", next))) ++next;
  g.id = fmt::format("G{}", next);
  g.kind = "constraint";
  g.constraint = kind;
  g.value = value;
  for (FeatureRef f : ms) g.members.push_back(m.id(f));
  m.fs.groups.push_back(g);
  if (edits.empty()) return {};
  try {
    return m.run(edits);
  } catch (...) {
    auto it = std::find_if(m.fs.groups.begin(), m.fs.groups.end(), [&](const features::Group& x) { return x.id == g.id; });
    if (it != m.fs.groups.end()) m.fs.groups.erase(it);
    throw;
  }
}

int Editor::unconstrain(std::optional<ConstraintKind> kind, const std::vector<FeatureRef>& ms) {
  Impl& m = *impl_;
  if (ms.empty()) return 0;
  // A patch takes the lines lying on it along (its rims), so their constraints go too.
  auto with_lines = [&](FeatureRef f) {
    std::set<std::string> ids{m.id(f)};
    if (f.kind == FeatureRef::Kind::patch) {
      const auto& pv = m.patch_verts[f.index];
      for (int l = 0; l < static_cast<int>(m.fs.lines.size()); ++l)
        if (!m.line_verts[l].empty() &&
            std::includes(pv.begin(), pv.end(), m.line_verts[l].begin(), m.line_verts[l].end()))
          ids.insert(m.fs.lines[l].id);
    }
    return ids;
  };
  int changed = 0;
  if (!kind) {
    std::set<std::string> ids;
    for (FeatureRef f : ms) {
      auto s = with_lines(f);
      ids.insert(s.begin(), s.end());
    }
    for (auto& gr : m.fs.groups) {
      if (!gr.constraint) continue;
      const auto n = gr.members.size();
      gr.members.erase(std::remove_if(gr.members.begin(), gr.members.end(), [&](const std::string& x) { return ids.count(x) > 0; }),
                       gr.members.end());
      changed += gr.members.size() != n;
    }
  } else {
    // The members after the first leave the groups of `kind` that hold the first (or its lines).
    const auto first = with_lines(ms[0]);
    std::set<std::string> rest;
    for (std::size_t k = 1; k < ms.size(); ++k) {
      auto s = with_lines(ms[k]);
      rest.insert(s.begin(), s.end());
    }
    for (auto& gr : m.fs.groups) {
      if (!gr.constraint || *gr.constraint != *kind) continue;
      const bool has_first = std::any_of(gr.members.begin(), gr.members.end(), [&](const std::string& x) { return first.count(x) > 0; });
      if (!has_first) continue;
      const auto n = gr.members.size();
      gr.members.erase(std::remove_if(gr.members.begin(), gr.members.end(), [&](const std::string& x) { return rest.count(x) > 0; }),
                       gr.members.end());
      changed += gr.members.size() != n;
    }
  }
  std::set<int> empty;
  for (int g = 0; g < static_cast<int>(m.fs.groups.size()); ++g)
    if (m.fs.groups[g].constraint && m.fs.groups[g].members.size() < 2) empty.insert(g);
  m.remove_groups(empty);
  return changed;
}

std::vector<double> Editor::displacement() const {
  std::vector<double> d(impl_->pos.size());
  for (std::size_t v = 0; v < d.size(); ++v) d[v] = (impl_->pos[v] - impl_->original[v]).norm();
  return d;
}

}  // namespace s2c::edit
