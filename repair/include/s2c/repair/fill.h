#pragma once
/// \file Hole filling: Liepa's minimum-weight triangulation + refinement + fairing
/// (../shared/papers/repair-survey.txt) and the RBF method of ../shared/papers/rbf-hole-filling.txt
/// (Laplacian rim smoothing, barycentric subdivision, r^3 RBF with on-surface and normal-offset
/// constraints, gradient projection). `auto` picks per hole.
#include <cstddef>
#include <memory>
#include <string>
#include <vector>

#include "s2c/core/mesh.h"
#include "s2c/repair/holes.h"

namespace s2c::repair {

enum class FillMethod { automatic, rbf, liepa };

struct FillOptions {
  FillMethod method = FillMethod::automatic;
  /// Target edge length of the patch, mm; 0 = the mean length of the hole's rim edges.
  double edge_length = 0;
  /// Holes with more rim vertices than this are left open (reported), 0 = no limit.
  std::size_t max_hole_vertices = 0;
  /// A patch may not grow beyond this many new vertices (the hole is then left open).
  std::size_t max_patch_vertices = 2000000;
  /// The rim is planar when every rim vertex lies within this fraction of the rim diameter of
  /// the best-fit plane. `automatic` fills a planar rim flat with Liepa when the mesh faces on
  /// the rim are within 10° of the plane (flat ground) or more than 60° off it (a crease: a
  /// missing planar face such as a turntable scan's bottom); every other hole gets RBF.
  double planar_tolerance = 1e-3;
  /// trim_end_caps: a rim within this fraction of its diameter of a plane (a reconstruction's
  /// trimmed rim is jagged) can be the part's unseen end face; see there. 0 = off.
  double end_cap_tolerance = 0.02;
  /// RBF: passes of Laplacian smoothing (eq. 4, λ = 0.5, each followed by Taubin's μ = -0.53
  /// step so that clean surfaces do not shrink) over the `rbf_smoothing_rings`-ring around the
  /// hole, on a copy used for the fit only (the mesh itself is not moved); 0 = off. Only where
  /// the surface there is noisy: its noise (fill/rim_surfaces.h: the median jump of the
  /// umbrella vector's normal component between neighbours, ≈ σ) above `rbf_noise_threshold` ×
  /// the edge length. Smoothing clean input only moves correct vertices (on a clean sphere it
  /// doubled the fill's deviation). Measured: the hole-filling benchmark's shapes (the fandisk
  /// CAD mesh among them) 0–0.27 % of the edge, Poisson meshes of the fixture scans 1.0–1.8 %.
  int rbf_smoothing_passes = 1;
  int rbf_smoothing_rings = 5;
  double rbf_noise_threshold = 0.005;
  /// RBF: where edges sharper than this dihedral angle (degrees) cut the rings around the hole
  /// into smooth pieces that all meet convexly (or all concavely), each piece gets its own RBF
  /// and the patch is projected onto their intersection (union), which keeps the crease through
  /// the hole instead of rounding it; 0 = one RBF over everything (the paper).
  double rbf_crease_angle = 30;
  /// RBF: on-surface constraints are the vertices up to this many rings from the rim.
  int rbf_constraint_rings = 3;
  /// RBF: normal-offset constraint distance d, as a fraction of the edge length.
  double rbf_offset = 0.5;
  /// RBF: gradient projection (eq. 12) stops when a step is shorter than this fraction of the
  /// edge length (the paper's 0.001 on unit-scale models).
  double projection_tolerance = 1e-3;
  /// RBF: more constraints than this switch from one global RBF to local patches blended by a
  /// partition of unity (see fill/rbf.h).
  std::size_t rbf_local_limit = 5000;
};

struct FillResult {
  FillMethod method = FillMethod::liepa;  ///< what was used for this hole
  bool filled = false;
  std::string reason;                     ///< why not, when not filled
  std::size_t new_vertices = 0, new_faces = 0;
  double seconds = 0;
  std::string choice;                     ///< why this method (the auto rule, or fallback)
  std::size_t rbf_constraints = 0;        ///< RBF centres (on-surface + offset), when RBF ran
  double rbf_solve_seconds = 0;           ///< RBF system solve, when RBF ran
};

/// Fills the holes of `soup` in place: appends vertices and faces. Every patch is a manifold
/// disc attached to its rim, free of self-intersections and of intersections with the mesh
/// around it; a hole whose patch fails that test is left open with a reason.
/// Where loops share a rim vertex and their pairing of its rim edges would close a fan of faces
/// on itself (leaving a pinch), the loops are first re-paired there: split, or merged with
/// another hole (that hole's result then says "merged into hole i"); one result per input hole
/// either way. A loop through a vertex twice that still cannot be filled is split there. A rim
/// vertex that already had several fans (a pinch no patch can undo) does not block the fill.
std::vector<FillResult> fill_holes(TriangleSoup& soup, const std::vector<Hole>& holes,
                                   const FillOptions& options = {});

namespace fill {
class MeshIndex;
}

/// fill_holes over several calls on one mesh, the way a halfedge mesh is filled hole by hole
/// (CGAL's triangulate_refine_and_fair_hole on a Surface_mesh): the mesh's vertex → faces
/// adjacency and the boxes of its faces that validation searches are built once, here (O(#F)),
/// and kept up to date as patches are appended. fill_holes builds its adjacency in every call;
/// for one small hole in a large mesh that is most of the call (0.08 ms of 0.6 on the 13k-face
/// fandisk, bench/README.md "Hole filling"). Results are the same either way.
/// The soup must outlive the filler. Between calls it may change only by appending vertices and
/// faces (appended faces are indexed at the next call; a soup that shrank is indexed anew); after
/// any other edit of existing faces or vertices, make a new HoleFiller.
class HoleFiller {
 public:
  explicit HoleFiller(TriangleSoup& soup);
  ~HoleFiller();
  HoleFiller(const HoleFiller&) = delete;
  HoleFiller& operator=(const HoleFiller&) = delete;
  /// As fill_holes(soup, holes, options).
  std::vector<FillResult> fill(const std::vector<Hole>& holes, const FillOptions& options = {});

 private:
  void index();
  TriangleSoup& soup_;
  std::unique_ptr<fill::MeshIndex> index_;
  std::size_t faces_ = 0, vertices_ = 0;  // the soup's size when last indexed or filled
};

/// The part's end faces a scan never saw (the face a part stands on during a turntable scan):
/// a hole whose rim lies within `options.end_cap_tolerance` of its diameter of a plane, with the
/// whole mesh on one side of that plane (the hole is the part's extreme end along the plane's
/// normal) and around the rim a surface whose angle to the plane does not turn over a band of
/// 5–25 % of the hole's radius (a chamfer, a cylinder wall: their continuation is the end face;
/// a sphere's pole turns and is left to RBF). Its rim is jagged where the reconstruction was
/// trimmed; the band of mesh between the rim's lowest and highest vertices is cut off by the
/// plane through the highest one (faces across it are clipped, vertices within 1 % of an
/// edge snapped onto it), so that the new rim lies in one plane and the fill meets the walls
/// in a clean crease. The holes are found again afterwards; those of the trimmed caps get
/// Hole::end_cap (fill_holes fills them flat). When the new boundary is not one simple loop in
/// the plane the soup is left as it was. Faces and vertices are only removed near the caps;
/// trimmed-off vertices stay in the soup, unreferenced. Holes above `max_hole_vertices` are not
/// touched. Faces must refer to existing vertices (as find_holes requires). One entry per
/// trimmed cap.
struct EndCapTrim {
  static constexpr std::size_t kNone = static_cast<std::size_t>(-1);
  std::size_t hole = kNone;      ///< its rim's index in the holes found again (kNone: none left)
  double depth_mm = 0;           ///< distance from the rim's lowest vertex to the cut plane
  std::size_t faces_removed = 0, faces_clipped = 0, vertices_snapped = 0;
};
std::vector<EndCapTrim> trim_end_caps(TriangleSoup& soup, std::vector<Hole>& holes, const FillOptions& options,
                                      HoleStats* stats = nullptr);

const char* to_string(FillMethod m);

}  // namespace s2c::repair
