#include "s2c/core/check.h"

#include <algorithm>
#include <cstdint>
#include <numeric>
#include <unordered_map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "s2c/core/errors.h"
#include "s2c/core/disjoint_sets.h"
#include "s2c/core/predicates.h"

namespace s2c {
namespace {

std::uint64_t edge_key(int a, int b) { return undirected_edge_key(a, b); }

struct EdgeInfo {
  int faces = 0;
  int forward = 0;  // faces traversing it from the smaller to the larger index
  int first_face = -1;
};

bool collinear(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  // Exactly: the three projections to coordinate planes all have zero orientation.
  auto proj = [](const Eigen::Vector3d& p, int i, int j) { return Eigen::Vector2d(p[i], p[j]); };
  return orient2d(proj(a, 0, 1), proj(b, 0, 1), proj(c, 0, 1)) == 0 &&
         orient2d(proj(a, 1, 2), proj(b, 1, 2), proj(c, 1, 2)) == 0 &&
         orient2d(proj(a, 0, 2), proj(b, 0, 2), proj(c, 0, 2)) == 0;
}

// Winding number of point p with respect to the faces in `faces` (solid angles / 4π).
double winding_number(const TriangleSoup& s, const std::vector<int>& faces, const Eigen::Vector3d& p) {
  double w = 0;
  for (int fi : faces) {
    const auto& f = s.faces[fi];
    const Eigen::Vector3d a = s.vertices[f[0]] - p, b = s.vertices[f[1]] - p, c = s.vertices[f[2]] - p;
    const double la = a.norm(), lb = b.norm(), lc = c.norm();
    const double num = a.dot(b.cross(c));
    const double den = la * lb * lc + a.dot(b) * lc + b.dot(c) * la + c.dot(a) * lb;
    w += 2.0 * std::atan2(num, den);
  }
  return w / (4.0 * M_PI);
}

}  // namespace

CheckResult check_mesh(const TriangleSoup& s, const CheckOptions& options) {
  CheckResult r;
  const int nv = static_cast<int>(s.vertices.size());
  r.faces = s.faces.size();
  for (std::size_t i = 0; i < s.faces.size(); ++i)
    for (int v : s.faces[i])
      if (v < 0 || v >= nv) throw InvalidInput(fmt::format("face {} refers to missing vertex {}", i, v));
  // The exact predicates cannot take NaN or infinity (GMP aborts on them).
  for (std::size_t i = 0; i < s.vertices.size(); ++i)
    if (!s.vertices[i].allFinite()) throw InvalidInput(fmt::format("vertex {} has a non-finite coordinate", i));

  // Edges.
  std::unordered_map<std::uint64_t, EdgeInfo> edges;
  edges.reserve(s.faces.size() * 2);
  for (std::size_t fi = 0; fi < s.faces.size(); ++fi) {
    const auto& f = s.faces[fi];
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      EdgeInfo& e = edges[edge_key(a, b)];
      if (e.faces == 0) e.first_face = static_cast<int>(fi);
      ++e.faces;
      if (a < b) ++e.forward;
    }
  }
  r.edges = edges.size();
  DisjointSets boundary_sets(nv);
  std::vector<char> on_boundary(nv, 0);
  for (const auto& [key, e] : edges) {
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
    if (e.faces == 1) {
      ++r.boundary_edges;
      boundary_sets.unite(a, b);
      on_boundary[a] = on_boundary[b] = 1;
    } else if (e.faces > 2) {
      ++r.nonmanifold_edges;
    } else if (e.forward != 1) {
      ++r.orientation_conflicts;
    }
  }
  for (int v = 0; v < nv; ++v)
    if (on_boundary[v] && boundary_sets.find(v) == v) ++r.boundary_loops;

  // Vertex fans: faces around a vertex linked through the edges incident to it.
  std::vector<std::vector<int>> vertex_faces(nv);
  for (std::size_t fi = 0; fi < s.faces.size(); ++fi)
    for (int v : s.faces[fi]) vertex_faces[v].push_back(static_cast<int>(fi));
  for (int v = 0; v < nv; ++v) {
    const auto& vf = vertex_faces[v];
    if (vf.empty()) {
      ++r.unreferenced_vertices;
      continue;
    }
    ++r.vertices;
    if (vf.size() == 1) continue;
    // Map each other vertex of the fan to the first face seen with it; link faces sharing it.
    std::unordered_map<int, int> first_with;
    DisjointSets fans(vf.size());
    for (std::size_t i = 0; i < vf.size(); ++i)
      for (int w : s.faces[vf[i]]) {
        if (w == v) continue;
        auto [it, fresh] = first_with.emplace(w, static_cast<int>(i));
        if (!fresh) fans.unite(static_cast<int>(i), it->second);
      }
    int roots = 0;
    for (std::size_t i = 0; i < vf.size(); ++i) roots += fans.find(static_cast<int>(i)) == static_cast<int>(i);
    if (roots > 1) ++r.nonmanifold_vertices;
  }

  // Components (vertex-connected), duplicates, degenerate faces, area and volume.
  DisjointSets comp(nv);
  std::unordered_map<std::uint64_t, std::vector<int>> face_sets;  // hash of sorted corners -> faces
  for (std::size_t fi = 0; fi < s.faces.size(); ++fi) {
    const auto& f = s.faces[fi];
    comp.unite(f[0], f[1]);
    comp.unite(f[1], f[2]);
    std::array<int, 3> sorted = f;
    std::sort(sorted.begin(), sorted.end());
    const std::uint64_t h = (static_cast<std::uint64_t>(sorted[0]) * 73856093u) ^
                            (static_cast<std::uint64_t>(sorted[1]) * 19349663u << 20) ^
                            (static_cast<std::uint64_t>(sorted[2]) * 83492791u << 40);
    auto& bucket = face_sets[h];
    for (int other : bucket) {
      std::array<int, 3> o = s.faces[other];
      std::sort(o.begin(), o.end());
      if (o == sorted) {
        ++r.duplicate_faces;
        break;
      }
    }
    bucket.push_back(static_cast<int>(fi));
    const auto &a = s.vertices[f[0]], &b = s.vertices[f[1]], &c = s.vertices[f[2]];
    if (collinear(a, b, c)) ++r.degenerate_faces;
    r.area += 0.5 * (b - a).cross(c - a).norm();
    r.volume += a.dot(b.cross(c)) / 6.0;
  }
  std::unordered_map<int, std::vector<int>> comp_faces;
  for (std::size_t fi = 0; fi < s.faces.size(); ++fi) comp_faces[comp.find(s.faces[fi][0])].push_back(static_cast<int>(fi));
  r.components = comp_faces.size();

  r.closed = !s.faces.empty() && r.boundary_edges == 0 && r.nonmanifold_edges == 0;
  bool outward = true;
  if (r.closed && r.orientation_conflicts == 0) {
    // Each shell must enclose positive volume, unless it lies inside another shell (a cavity),
    // where it must be negative.
    for (const auto& [root, faces] : comp_faces) {
      double vol = 0;
      for (int fi : faces) {
        const auto& f = s.faces[fi];
        vol += s.vertices[f[0]].dot(s.vertices[f[1]].cross(s.vertices[f[2]])) / 6.0;
      }
      std::vector<int> others;
      if (comp_faces.size() > 1)
        for (const auto& [root2, faces2] : comp_faces)
          if (root2 != root) others.insert(others.end(), faces2.begin(), faces2.end());
      const bool inside_other =
          !others.empty() && std::abs(winding_number(s, others, s.vertices[s.faces[faces[0]][0]])) > 0.5;
      const int depth_parity = inside_other ? -1 : 1;
      if (vol * depth_parity <= 0) outward = false;
    }
  }
  r.oriented = r.nonmanifold_edges == 0 && r.orientation_conflicts == 0 && (!r.closed || outward);

  if (options.self_intersections) {
    const auto pairs = self_intersecting_pairs(s);
    r.self_intersections_checked = true;
    r.self_intersections = pairs.size();
    std::vector<char> hit(s.faces.size(), 0);
    for (const auto& [a, b] : pairs) hit[a] = hit[b] = 1;
    r.self_intersecting_faces = static_cast<std::size_t>(std::count(hit.begin(), hit.end(), 1));
    r.intersecting_pairs.assign(pairs.begin(), pairs.begin() + static_cast<long>(std::min(pairs.size(), options.max_pairs_listed)));
  }

  auto problem = [&](bool bad, std::string what) { if (bad) r.problems.push_back(std::move(what)); };
  problem(s.faces.empty(), "no faces");
  problem(r.boundary_edges > 0, fmt::format("{} boundary loops ({} open edges): not closed", r.boundary_loops, r.boundary_edges));
  problem(r.nonmanifold_edges > 0, fmt::format("{} non-manifold edges", r.nonmanifold_edges));
  problem(r.nonmanifold_vertices > 0, fmt::format("{} non-manifold vertices", r.nonmanifold_vertices));
  problem(r.orientation_conflicts > 0, fmt::format("{} edges with inconsistent face orientation", r.orientation_conflicts));
  problem(r.closed && r.orientation_conflicts == 0 && !outward, "faces point inward");
  problem(r.self_intersections > 0, fmt::format("{} intersecting face pairs", r.self_intersections));
  problem(r.degenerate_faces > 0, fmt::format("{} degenerate (zero-area) faces", r.degenerate_faces));
  problem(r.duplicate_faces > 0, fmt::format("{} duplicate faces", r.duplicate_faces));
  problem(!options.self_intersections, "self-intersections not checked");
  r.cad_ready = r.problems.empty();
  return r;
}

std::string to_json(const CheckResult& r, int indent) {
  nlohmann::json j = {
      {"closed", r.closed},
      {"boundary_loops", r.boundary_loops},
      {"boundary_edges", r.boundary_edges},
      {"nonmanifold_edges", r.nonmanifold_edges},
      {"nonmanifold_vertices", r.nonmanifold_vertices},
      {"components", r.components},
      {"self_intersections", r.self_intersections_checked ? nlohmann::json(r.self_intersections) : nlohmann::json()},
      {"self_intersecting_faces", r.self_intersections_checked ? nlohmann::json(r.self_intersecting_faces) : nlohmann::json()},
      {"degenerate_faces", r.degenerate_faces},
      {"duplicate_faces", r.duplicate_faces},
      {"orientation_conflicts", r.orientation_conflicts},
      {"oriented", r.oriented},
      {"cad_ready", r.cad_ready},
      {"vertices", r.vertices},
      {"unreferenced_vertices", r.unreferenced_vertices},
      {"faces", r.faces},
      {"edges", r.edges},
      {"area_mm2", r.area},
      {"volume_mm3", r.volume},
      {"problems", r.problems},
  };
  nlohmann::json pairs = nlohmann::json::array();
  for (const auto& [a, b] : r.intersecting_pairs) pairs.push_back({a, b});
  j["intersecting_pairs_sample"] = pairs;
  return j.dump(indent);
}

}  // namespace s2c
