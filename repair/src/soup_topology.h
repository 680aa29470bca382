#pragma once
// Small topology helpers on an indexed triangle soup, shared by cleaning, the defect report and
// the repair driver: undirected edge keys, edge → faces, components.
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "s2c/core/mesh.h"

namespace s2c::repair {

inline std::uint64_t undirected_key(int a, int b) { return undirected_edge_key(a, b); }

/// Faces of every undirected edge.
std::unordered_map<std::uint64_t, std::vector<int>> edge_faces(const TriangleSoup& soup);

/// Vertex-connected components of the faces: component id per face, and the count.
std::vector<int> face_components(const TriangleSoup& soup, int& count);

double face_area(const TriangleSoup& soup, int face);

/// Per component (ids of face_components): open (has a boundary edge) and with less than
/// `fraction` of the total area. Such components are scanner fragments and loose triangles.
std::vector<char> tiny_open_components(const TriangleSoup& soup, const std::vector<int>& comp, int count,
                                       double fraction = 0.005);

/// Exactly collinear corners (or repeated indices).
bool zero_area(const TriangleSoup& soup, int face);

/// Drops vertices no face uses and renumbers; returns how many were dropped.
std::size_t remove_unreferenced(TriangleSoup& soup);

}  // namespace s2c::repair
