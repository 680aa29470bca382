#pragma once
/// \file Is a mesh CAD-ready? Topology and geometry checks on the mesh exactly as stored.
#include <cstddef>
#include <string>
#include <utility>
#include <vector>

#include "s2c/core/mesh.h"

namespace s2c {

struct CheckOptions {
  bool self_intersections = true;  ///< the O(F log F) exact pair test; off for a quick look
  std::size_t max_pairs_listed = 100;  ///< how many intersecting pairs to keep in the result
};

/// Definitions (shared with tests/tools/cgal_check and ../shared/data/real/manifest.json):
/// an edge is an unordered vertex pair; its faces are the faces using both vertices.
struct CheckResult {
  std::size_t vertices = 0;              ///< referenced vertices
  std::size_t unreferenced_vertices = 0;
  std::size_t faces = 0;
  std::size_t edges = 0;
  std::size_t boundary_edges = 0;        ///< edges with exactly one face
  std::size_t boundary_loops = 0;        ///< connected components of the boundary-edge graph
  std::size_t nonmanifold_edges = 0;     ///< edges with more than two faces
  std::size_t nonmanifold_vertices = 0;  ///< faces around the vertex form more than one edge-connected fan
  std::size_t orientation_conflicts = 0; ///< two-face edges both faces traverse in the same direction
  std::size_t components = 0;            ///< vertex-connected components of the faces
  std::size_t self_intersections = 0;    ///< intersecting face pairs (exact; CGAL's semantics, see predicates.h)
  std::size_t self_intersecting_faces = 0;
  std::size_t degenerate_faces = 0;      ///< collinear corners (zero area), exactly
  std::size_t duplicate_faces = 0;       ///< faces with the same vertex set as an earlier face
  double volume = 0;                     ///< signed volume, mm³ (meaningful when closed)
  double area = 0;                       ///< mm²
  bool closed = false;                   ///< no boundary and no non-manifold edge
  bool oriented = false;                 ///< consistent, and outward when closed (cavities inward)
  bool self_intersections_checked = false;
  bool cad_ready = false;                ///< closed, manifold, oriented, no self-intersections, no degenerate or duplicate faces
  std::vector<std::pair<int, int>> intersecting_pairs;  ///< the first max_pairs_listed pairs (face indices)
  std::vector<std::string> problems;     ///< human-readable reasons cad_ready is false
};

/// \throw InvalidInput if a face refers to a missing vertex.
CheckResult check_mesh(const TriangleSoup& soup, const CheckOptions& options = {});

/// Intersecting face pairs (i < j), exact, candidates from an Embree BVH.
std::vector<std::pair<int, int>> self_intersecting_pairs(const TriangleSoup& soup);

/// The result as one JSON object (the keys of DESIGN.md plus the counts above).
std::string to_json(const CheckResult& result, int indent = 2);

}  // namespace s2c
