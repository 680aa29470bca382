#pragma once
// Liepa's hole filling ("Filling holes in meshes", SGP 2003; ../shared/papers/repair-survey.txt):
// minimum-weight triangulation, density-controlled refinement, umbrella-operator fairing.
// The RBF method reuses the first two steps for its initial patch.
#include <cstddef>
#include <string>

#include "fill/patch.h"

namespace s2c::repair::fill {

/// Above this many rim corners the O(n³) dynamic program is not run on the whole loop: the
/// loop is cut by short balanced chords into pieces of at most this size, each triangulated by
/// the dynamic program (O(n²) for the cuts + O(pieces · limit³)).
constexpr std::size_t kDpLimit = 300;

/// Minimum-weight triangulation of the loop (patch.rim / patch.points, rim only) into
/// patch.faces; weight = (largest dihedral angle, area) compared lexicographically. Triangles
/// with a repeated vertex, degenerate triangles and interior edges that already exist in the
/// mesh are never chosen. When no such triangulation exists and the rim passes every vertex once,
/// the loop is fanned around one new vertex at its centroid. \return false (with `why`) otherwise.
bool triangulate(const TriangleSoup& soup, const MeshIndex& index, Patch& patch, std::string& why,
                 std::size_t dp_limit = kDpLimit);

/// Liepa's refinement: splits a triangle at its centroid while sqrt(2)·|centroid − corner|
/// exceeds the density σ of the centroid and of the corner, relaxing edges Delaunay-like after
/// each pass. σ of the rim vertices is patch.sigma (set by the caller); new vertices get the
/// mean of their triangle's. \return false when the patch would exceed max_vertices.
bool refine(const MeshIndex& index, Patch& patch, std::size_t max_vertices, std::string& why);

/// Fairs the new vertices with the umbrella operator U with cotangent weights (normalised to
/// sum 1, each clamped to ≥ 0.05; taken on the patch before fairing, as CGAL's
/// triangulate_refine_and_fair_hole). `tangent_continuous` (Liepa): minimises Σ |U(v)|² over
/// the new vertices and the rim, the rim's umbrella including its mesh neighbours, i.e. a
/// discrete bi-Laplacian with the rim and one outer ring fixed (C1-like join). Otherwise
/// U(v) = 0 at the new vertices with only the rim fixed (a harmonic, Tutte-like patch): a
/// planar rim gives a planar patch, and unlike the bi-Laplacian with free rim slopes it cannot
/// overshoot the rim (no folds for convex rims).
bool fair(const TriangleSoup& soup, const MeshIndex& index, Patch& patch, bool tangent_continuous,
          std::string& why);

}  // namespace s2c::repair::fill
