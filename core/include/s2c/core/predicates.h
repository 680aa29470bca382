#pragma once
/// \file Exact geometric predicates and exact triangle–triangle intersection tests.
///
/// Every function here returns the mathematically correct answer for its double inputs, as if
/// computed with real numbers. Each orientation is decided by the first stage that can:
///  1. floating point with a semi-static error bound (nonzero, well-conditioned results);
///  2. exact floating-point expansion arithmetic on the stack, no allocation (zero and
///     near-zero results, e.g. coplanar neighbouring faces), for coordinates that are 0 or
///     have magnitudes in [2^-306, 2^300] (orient3d) / [2^-484, 2^500] (orient2d);
///  3. exact GMP rationals (mpq_class) for the remaining magnitudes.
/// Measured on the real meshes in ../shared/data (self-intersection candidates): no call
/// reaches stage 3; 0–31 % of orient3d calls reach stage 2 (median 0.5 %, the most on CAD
/// meshes with large flat regions), nearly all of them exact zeros.
/// Inputs must be finite (no NaN, no infinity); any finite double is accepted, including
/// subnormals and values near the overflow threshold. Coordinates carry no unit of their own
/// (the project uses millimetres); results do not depend on the unit.
/// All functions are pure and thread-safe.
#include <array>

#include <Eigen/Core>

namespace s2c {

/// Sign of det[b-a, c-a, d-a]: +1 when d lies on the side of the plane through a, b, c that
/// the normal (b-a)×(c-a) points to (a, b, c seen counter-clockwise from d), -1 on the other
/// side, 0 when the four points are coplanar (or a, b, c collinear). Exact.
int orient3d(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c,
             const Eigen::Vector3d& d);

/// Sign of det[b-a, c-a]: +1 when a, b, c turn counter-clockwise, -1 clockwise, 0 collinear. Exact.
int orient2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c);

/// True when the closed segments ab and cd share at least one point (a segment of two equal
/// ends is that point). Exact.
bool segments_intersect_2d(const Eigen::Vector2d& a, const Eigen::Vector2d& b, const Eigen::Vector2d& c,
                           const Eigen::Vector2d& d);

/// True when the closed triangles t and u (boundary included) share at least one point. Exact.
/// A degenerate triangle is treated as the point set it is: three coincident points are a
/// point, three collinear points are the segment between the two extreme ones.
bool triangles_intersect(const std::array<Eigen::Vector3d, 3>& t, const std::array<Eigen::Vector3d, 3>& u);

/// Self-intersection test for two faces p and q of one mesh; pi and qi are their vertex
/// indices, so shared vertices are known combinatorially (equal index = same vertex; two
/// different indices at the same position are two vertices). Exact. Let S be the set of
/// distinct indices occurring in both faces and K the convex hull of their positions:
///  - |S| = 0: intersect iff the closed triangles share any point;
///  - |S| = 1 (one shared vertex v): intersect iff they share any point other than v;
///  - |S| = 2 (a shared edge ab): intersect iff they share a point outside the segment ab. For
///    non-degenerate faces this is: the four vertices are coplanar and the two opposite
///    vertices lie strictly on the same side of the line ab (the faces fold onto each other);
///  - |S| = 3 (duplicate face, either orientation): intersect.
/// In short, for |S| < 3: intersect iff (p ∩ q) is not contained in K.
///
/// This matches CGAL::Polygon_mesh_processing::self_intersections (CGAL 5.5,
/// internal::do_faces_intersect) on every pair of non-degenerate faces of a valid triangle mesh.
/// Differences, all outside what CGAL defines:
///  - CGAL never tests a degenerate (collinear) face against others: it reports the pair (f, f)
///    once and skips f. Here degenerate faces are tested as the point or segment they are, with
///    the rule above (two degenerate faces on a common edge line intersect only if both extend
///    beyond the same end of the shared edge).
///  - CGAL detects the shared edge through halfedge adjacency, so it needs a valid
///    (manifold) mesh; here it is detected from the indices, so soups with non-manifold edges,
///    duplicate faces or faces with a repeated index work too. Faces sharing two vertices
///    are always treated as sharing that edge.
///  - CGAL's one-shared-vertex test checks only the first shared vertex it finds; with
///    non-degenerate faces two shared vertices always mean a shared edge, so this never differs.
/// pi and qi may contain any int values (they are only compared for equality).
bool faces_self_intersect(const std::array<Eigen::Vector3d, 3>& p, const std::array<int, 3>& pi,
                          const std::array<Eigen::Vector3d, 3>& q, const std::array<int, 3>& qi);

}  // namespace s2c
