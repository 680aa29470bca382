#pragma once
// Marching Cubes case table, generated at start-up from the cube's combinatorics instead of a
// hand-typed 256-entry table: on every cube face the crossing edges are paired (on an ambiguous
// face, each inside corner is cut off on its own), the pairs chain into closed loops on the cube's
// surface, and each loop is fanned into triangles. Because the pairing on a face depends only on
// that face's four corner signs, neighbouring cells agree on every shared face and the union of
// all cells is a closed 2-manifold.
#include <array>
#include <cstdint>
#include <vector>

namespace s2c::repair::mc {

/// Corner c of a cell sits at offset (c & 1, (c >> 1) & 1, (c >> 2) & 1).
/// Edges 0-3 run along x, 4-7 along y, 8-11 along z.
struct Edge {
  int a, b;   ///< corners, a < b, b = a + (1 << axis)
  int axis;
};
const std::array<Edge, 12>& edges();

/// Triangles of one case as edge ids; triangle normals point from inside to outside.
struct Case {
  std::vector<std::array<std::uint8_t, 3>> triangles;
  /// The closed loops of crossing edges on the cube's surface, one per surface sheet in the
  /// cell, oriented like the triangles (dual contouring puts one vertex per loop).
  std::vector<std::vector<std::uint8_t>> loops;
};
/// Indexed by the inside mask: bit c set when corner c is inside.
const std::array<Case, 256>& cases();

}  // namespace s2c::repair::mc
