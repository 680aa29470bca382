#pragma once
// Validity of a patch before it is committed to the soup (see fill.h's contract).
#include <cstddef>
#include <string>

#include "fill/patch.h"

namespace s2c::repair::fill {

/// Empty when the patch is a manifold disc attached to its rim (every rim edge used once in the
/// loop's direction, every other patch edge by exactly two patch faces and no mesh face, one
/// fan per touched vertex, Euler characteristic 1), has finite coordinates, no degenerate
/// triangle, and no face pair intersecting within the patch or with the mesh (exact predicates,
/// CGAL's semantics). Otherwise the first reason found.
///
/// `scope` narrows the geometric part for a patch already checked against an earlier state of
/// the soup (faces are only ever appended): the mesh faces from `mesh_faces_from` on, and the
/// patch against itself only when `patch_itself`; without it, of the topology only what involves
/// existing vertices (rim edges, chords between rim vertices, fans at the rim).
struct CheckScope {
  std::size_t mesh_faces_from = 0;
  bool patch_itself = true;
};
std::string check_patch(const TriangleSoup& soup, const MeshIndex& index, const Patch& patch,
                        const CheckScope& scope = {});

/// check_patch's topology part alone (the faces against the soup as it is; the points play no
/// part). A patch that passed it (Patch::topology_ok) skips it in a full check_patch, so that it
/// can run while something else still moves the points (the RBF fill's fit).
std::string check_patch_topology(const TriangleSoup& soup, const MeshIndex& index, const Patch& patch);

/// Whether no two faces of the patch intersect (beyond the edges and vertices they share),
/// shown without testing pairs: a sufficient condition that check_patch tries before its pair
/// test. Dropping a coordinate (the patch's dominant normal axis) is exact, so every test is
/// exact. The argument: the patch's faces are an oriented surface whose boundary is exactly the
/// rim loop (every directed edge has its reverse in the patch or is a rim edge, all rim edges
/// the same way round). If every face projects to a triangle of one orientation sign and the rim
/// projects to a simple polygon, a generic point of the plane has as many preimages as the
/// polygon winds around it, 0 or 1: the projection is one-to-one, so the faces meet only where
/// they share edges and vertices. False whenever that is not shown (a rim over 256 vertices, a
/// repeated rim vertex, a patch that folds over in every axis projection, ...).
bool patch_embeds_by_projection(const Patch& patch);

}  // namespace s2c::repair::fill
