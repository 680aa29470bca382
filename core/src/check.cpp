#include "s2c/core/check.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <numeric>
#include <unordered_map>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "s2c/core/errors.h"
#include "s2c/core/disjoint_sets.h"
#include "s2c/core/predicates.h"

namespace s2c {
namespace {

std::uint64_t edge_key(int a, int b) { return undirected_edge_key(a, b); }

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

  // Edges: (key, traversed from the smaller index) per face side, sorted so that each edge's
  // faces are one run (a hash map of edges was most of this function's time at 10⁵ faces).
  std::vector<std::uint64_t> sides;
  sides.reserve(s.faces.size() * 3);
  for (const auto& f : s.faces)
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      sides.push_back(edge_key(a, b) << 1 | (a < b ? 1u : 0u));
    }
  std::sort(sides.begin(), sides.end());
  DisjointSets boundary_sets(nv);
  std::vector<char> on_boundary(nv, 0);
  for (std::size_t i = 0; i < sides.size();) {
    const std::uint64_t key = sides[i] >> 1;
    int faces = 0, forward = 0;
    for (; i < sides.size() && sides[i] >> 1 == key; ++i, ++faces) forward += static_cast<int>(sides[i] & 1u);
    ++r.edges;
    const int a = static_cast<int>(key >> 32), b = static_cast<int>(key & 0xffffffffu);
    if (faces == 1) {
      ++r.boundary_edges;
      boundary_sets.unite(a, b);
      on_boundary[a] = on_boundary[b] = 1;
    } else if (faces > 2) {
      ++r.nonmanifold_edges;
    } else if (forward != 1) {
      ++r.orientation_conflicts;
    }
  }
  sides = {};
  for (int v = 0; v < nv; ++v)
    if (on_boundary[v] && boundary_sets.find(v) == v) ++r.boundary_loops;

  // Vertex fans: faces around a vertex linked through the edges incident to it (faces per
  // vertex in compressed rows; per vertex, (other corner, face slot) sorted to find the links).
  std::vector<int> fan_start(nv + 1, 0), fan;
  for (const auto& f : s.faces)
    for (int v : f) ++fan_start[v + 1];
  for (int v = 0; v < nv; ++v) fan_start[v + 1] += fan_start[v];
  fan.resize(fan_start[nv]);
  {
    std::vector<int> fill(fan_start.begin(), fan_start.end() - 1);
    for (std::size_t fi = 0; fi < s.faces.size(); ++fi)
      for (int v : s.faces[fi]) fan[fill[v]++] = static_cast<int>(fi);
  }
  std::vector<std::pair<int, int>> corners;  // (other corner, slot of its face in the fan)
  for (int v = 0; v < nv; ++v) {
    const int n = fan_start[v + 1] - fan_start[v];
    if (n == 0) {
      ++r.unreferenced_vertices;
      continue;
    }
    ++r.vertices;
    if (n == 1) continue;
    corners.clear();
    for (int i = 0; i < n; ++i)
      for (int w : s.faces[fan[fan_start[v] + i]])
        if (w != v) corners.emplace_back(w, i);
    std::sort(corners.begin(), corners.end());
    DisjointSets fans(n);
    for (std::size_t k = 1; k < corners.size(); ++k)
      if (corners[k].first == corners[k - 1].first) fans.unite(corners[k].second, corners[k - 1].second);
    int roots = 0;
    for (int i = 0; i < n; ++i) roots += fans.find(i) == i;
    if (roots > 1) ++r.nonmanifold_vertices;
  }

  // Components (vertex-connected), duplicates, degenerate faces, area and volume.
  DisjointSets comp(nv);
  std::vector<std::pair<std::array<int, 3>, int>> corner_sets;  // sorted corners, face
  corner_sets.reserve(s.faces.size());
  for (std::size_t fi = 0; fi < s.faces.size(); ++fi) {
    const auto& f = s.faces[fi];
    comp.unite(f[0], f[1]);
    comp.unite(f[1], f[2]);
    std::array<int, 3> sorted = f;
    std::sort(sorted.begin(), sorted.end());
    corner_sets.emplace_back(sorted, static_cast<int>(fi));
    const auto &a = s.vertices[f[0]], &b = s.vertices[f[1]], &c = s.vertices[f[2]];
    if (collinear(a, b, c)) ++r.degenerate_faces;
    r.area += 0.5 * (b - a).cross(c - a).norm();
    r.volume += a.dot(b.cross(c)) / 6.0;
  }
  // A duplicate: a face with the same corners as an earlier one.
  std::sort(corner_sets.begin(), corner_sets.end());
  for (std::size_t k = 1; k < corner_sets.size(); ++k)
    if (corner_sets[k].first == corner_sets[k - 1].first) ++r.duplicate_faces;
  corner_sets = {};
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
