#pragma once
// The working mesh of a large noisy mesh (issue 5: "remesh internally if needed, map results
// back"). A noisy mesh costs the analysis about ten seconds per million vertices (filtered normals,
// a vote several edges wide, the fit-driven split), while its primitives are as well resolved by
// a tenth of its vertices (a smooth one's, a Poisson surface's, by a sixth): the analysis runs on
// a coarser copy and its patches are mapped back.
#include <vector>

#include <Eigen/Core>

#include "mesh_arrays.h"
#include "segment.h"

namespace s2c::features {

struct WorkingMesh {
  MeshArrays arrays;               ///< the coarse copy
  std::vector<int> vertex_cluster; ///< per fine vertex: its coarse vertex
  std::vector<int> face_of;        ///< per fine face: its coarse face, -1 where it collapsed
  double cell = 0.0;               ///< the clustering grid's cell, mm
};

/// Clusters of vertices about a cell wide, the cell chosen for about `target_vertices` clusters
/// (but at most `max_cell`): connected pieces of the surface grown from seeds spaced over it
/// (cluster_vertices in the .cpp), each placed where the planes of its faces meet (Lindstrom's
/// quadric; the mean where they do not pin it down), so creases stay sharp. A fine face on three
/// clusters is a face of the working mesh, kept once; faces that collapse are dropped, and so are
/// two faces on the same three clusters facing away from each other. With `mean_flat` (a smooth
/// mesh's), a cluster whose faces lie in one plane stays at the mean of its vertices (see
/// place_clusters in the .cpp).
WorkingMesh coarsen(const MeshArrays& fine, int target_vertices, double max_cell, bool mean_flat = false);

/// The candidates (indices into `pos`), in order, that have no seed taken before them closer
/// than `spacing`: the seeds of coarsen's clusters (exposed for tests). `origin` is a corner
/// below the points.
std::vector<int> spaced_seeds(const std::vector<Eigen::Vector3d>& pos, const Eigen::Vector3d& origin,
                              const std::vector<int>& candidates, double spacing);

/// The fine mesh's segmentation from the working mesh's: each face takes its coarse face's
/// region, a collapsed face one of the regions around its clusters (the nearest fitted shape
/// within 3 `tolerance`s, else the most common); then the faces along a border between two fitted
/// patches move to the patch whose shape lies nearer (up to `passes` face rings), so the border
/// follows the fine mesh's crease rather than the coarse mesh's zigzag, and a mode filter
/// removes the notches noise leaves. Regions keep their fits; their faces and areas are the fine
/// mesh's.
Segmentation map_back(const MeshArrays& fine, const WorkingMesh& w, const Segmentation& coarse, double tolerance,
                      int passes);

/// Per fine face, the working mesh's (filtered) normal of its coarse face; where it collapsed, the
/// working mesh's normal at its first vertex's cluster (trace_lines' FaceNormal).
class MappedNormals {
 public:
  /// Holds references to all three.
  MappedNormals(const MeshArrays& fine, const WorkingMesh& w, const std::vector<Eigen::Vector3d>& coarse_normals);
  Eigen::Vector3d operator()(int face) const;

 private:
  const MeshArrays& fine_;
  const WorkingMesh& w_;
  const std::vector<Eigen::Vector3d>& coarse_normals_;
  std::vector<Eigen::Vector3d> at_cluster_;
};

}  // namespace s2c::features
