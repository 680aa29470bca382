// Cleaning without inventing geometry: duplicates, degenerate faces, loose fragments, orientation.
#include <algorithm>
#include <array>
#include <map>
#include <queue>

#include "s2c/repair/defects.h"
#include "soup_topology.h"
#include "volumetric/winding.h"

namespace s2c::repair {

namespace {

std::size_t remove_duplicates(TriangleSoup& soup) {
  // Same corner set: identical copies collapse to one; copies with opposite orientations form a
  // two-sided sheet of zero volume and all of them go.
  std::map<std::array<int, 3>, std::vector<int>> groups;
  for (std::size_t fi = 0; fi < soup.faces.size(); ++fi) {
    auto k = soup.faces[fi];
    std::sort(k.begin(), k.end());
    groups[k].push_back(static_cast<int>(fi));
  }
  std::vector<char> drop(soup.faces.size(), 0);
  std::size_t removed = 0;
  auto parity = [&](int fi) {  // orientation class of a face relative to its sorted corners
    const auto& f = soup.faces[fi];
    const int lo = static_cast<int>(std::min_element(f.begin(), f.end()) - f.begin());
    return f[(lo + 1) % 3] < f[(lo + 2) % 3] ? 0 : 1;
  };
  for (const auto& [key, faces] : groups) {
    if (faces.size() < 2) continue;
    const int p0 = parity(faces[0]);
    const bool mixed = std::any_of(faces.begin(), faces.end(), [&](int f) { return parity(f) != p0; });
    for (std::size_t i = mixed ? 0 : 1; i < faces.size(); ++i) {
      drop[faces[i]] = 1;
      ++removed;
    }
  }
  std::size_t w = 0;
  for (std::size_t fi = 0; fi < soup.faces.size(); ++fi)
    if (!drop[fi]) soup.faces[w++] = soup.faces[fi];
  soup.faces.resize(w);
  return removed;
}

std::size_t remove_degenerate(TriangleSoup& soup) {
  std::size_t w = 0;
  for (std::size_t fi = 0; fi < soup.faces.size(); ++fi)
    if (!zero_area(soup, static_cast<int>(fi))) soup.faces[w++] = soup.faces[fi];
  const std::size_t removed = soup.faces.size() - w;
  soup.faces.resize(w);
  return removed;
}

/// Open components with less than 0.5% of the area are scanner fragments and loose triangles;
/// closed components are parts (or cavities) and stay whatever their size.
std::size_t remove_tiny_components(TriangleSoup& soup) {
  int count = 0;
  const std::vector<int> comp = face_components(soup, count);
  if (count < 2) return 0;
  const std::vector<char> drop = tiny_open_components(soup, comp, count);
  const auto removed = static_cast<std::size_t>(std::count(drop.begin(), drop.end(), 1));
  std::size_t w = 0;
  for (std::size_t fi = 0; fi < soup.faces.size(); ++fi)
    if (!drop[comp[fi]]) soup.faces[w++] = soup.faces[fi];
  soup.faces.resize(w);
  return removed;
}

bool has_directed_edge(const std::array<int, 3>& f, int a, int b) {
  for (int k = 0; k < 3; ++k)
    if (f[k] == a && f[(k + 1) % 3] == b) return true;
  return false;
}

/// Breadth-first over manifold edges: a neighbour must traverse the shared edge the other way.
std::size_t make_consistent(TriangleSoup& soup, const EdgeFaces& edges) {
  std::vector<char> seen(soup.faces.size(), 0);
  std::size_t flipped = 0;
  for (std::size_t seed = 0; seed < soup.faces.size(); ++seed) {
    if (seen[seed]) continue;
    std::queue<int> q;
    q.push(static_cast<int>(seed));
    seen[seed] = 1;
    while (!q.empty()) {
      const int fi = q.front();
      q.pop();
      const auto f = soup.faces[fi];
      for (int k = 0; k < 3; ++k) {
        const int a = f[k], b = f[(k + 1) % 3];
        const auto& adj = edges.at(undirected_key(a, b));
        if (adj.size() != 2) continue;
        const int g = adj[0] == fi ? adj[1] : adj[0];
        if (seen[g]) continue;
        seen[g] = 1;
        if (has_directed_edge(soup.faces[g], a, b)) {
          std::swap(soup.faces[g][1], soup.faces[g][2]);
          ++flipped;
        }
        q.push(g);
      }
    }
  }
  return flipped;
}

/// Closed components point outward, or inward when an odd number of other closed components
/// contains them (cavities in hollow parts).
std::size_t orient_outward(TriangleSoup& soup, const EdgeFaces& edges) {
  int count = 0;
  const std::vector<int> comp = face_components(soup, count);
  std::vector<char> closed(count, 1);
  for (const auto& [key, faces] : edges)
    if (faces.size() != 2) closed[comp[faces[0]]] = 0;
  std::vector<std::vector<int>> faces_of(count);
  for (std::size_t fi = 0; fi < soup.faces.size(); ++fi) faces_of[comp[fi]].push_back(static_cast<int>(fi));
  std::vector<double> volume(count, 0.0);
  for (std::size_t fi = 0; fi < soup.faces.size(); ++fi) {
    const auto& f = soup.faces[fi];
    volume[comp[fi]] += soup.vertices[f[0]].dot(soup.vertices[f[1]].cross(soup.vertices[f[2]])) / 6;
  }
  auto winding_of = [&](int c, const Eigen::Vector3d& p) {
    double w = 0;
    for (int fi : faces_of[c]) {
      const auto& f = soup.faces[fi];
      w += triangle_winding(p, soup.vertices[f[0]], soup.vertices[f[1]], soup.vertices[f[2]]);
    }
    return w;
  };
  std::size_t flipped = 0;
  for (int c = 0; c < count; ++c) {
    if (!closed[c]) continue;
    // A point just inside c's first face decides containment by the other closed components.
    const auto& f0 = soup.faces[faces_of[c][0]];
    const Eigen::Vector3d p = (soup.vertices[f0[0]] + soup.vertices[f0[1]] + soup.vertices[f0[2]]) / 3;
    int depth = 0;
    // O(components × faces): beyond a few hundred closed parts, assume none is nested.
    for (int d = 0; d < count && count <= 256; ++d)
      if (d != c && closed[d] && std::abs(winding_of(d, p)) > 0.5) ++depth;
    const bool want_positive = depth % 2 == 0;
    if ((volume[c] > 0) != want_positive && volume[c] != 0) {
      for (int fi : faces_of[c]) std::swap(soup.faces[fi][1], soup.faces[fi][2]);
      flipped += faces_of[c].size();
    }
  }
  return flipped;
}

}  // namespace

CleanStats clean(TriangleSoup& soup) {
  CleanStats st;
  st.degenerate_faces_removed = remove_degenerate(soup);
  st.duplicate_faces_removed = remove_duplicates(soup);
  st.tiny_components_removed = remove_tiny_components(soup);
  const auto edges = edge_faces(soup);
  st.edge_manifold = std::none_of(edges.begin(), edges.end(), [](const auto& e) { return e.second.size() > 2; });
  st.faces_flipped = make_consistent(soup, edges);
  st.faces_flipped += orient_outward(soup, edges);
  st.unreferenced_vertices_removed = remove_unreferenced(soup);
  return st;
}

}  // namespace s2c::repair
