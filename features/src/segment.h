#pragma once
// Feature patches: faces flood-filled inside sharp edges, fitted with plane / sphere / cylinder /
// cone, regions no primitive fits split by fit-driven region growing, neighbours with the same
// primitive merged. On noisy meshes the flood fill stops at a stricter turn of the filtered
// normals, the faces left out are grown into the patch whose shape explains each face best, and
// crumbs are absorbed into their neighbours.
#include <vector>

#include "mesh_arrays.h"
#include "s2c/features/analyze.h"
#include "s2c/features/shape.h"

namespace s2c::features {

struct SegmentParams {
  double min_crease_deg = 20.0;
  double tolerance = 0.0;        ///< fit acceptance RMS, mm
  double normal_tol_deg = 10.0;  ///< fit acceptance RMS normal angle
  bool noisy = false;            ///< seeds + growth instead of a plain flood fill
  double diagonal = 1.0;
  /// Fine faces per face of this mesh (a working mesh's, working_mesh.h): on a noisy mesh the
  /// smallest patch is kMinNoisyPatchFaces fine faces' worth of area, so a coarse mesh keeps
  /// the narrow bands along rounded creases that the fine mesh keeps as patches of their own.
  double face_scale = 1.0;
};

struct Region {
  std::vector<int> faces;
  Fit fit;  ///< fit.shape.type == freeform when no primitive is accepted
  double area = 0.0;
  /// faces.size() when `fit` was last chosen afresh for exactly these faces (choose_shape), else
  /// 0: regions only grow, so an equal size means the same faces and the same fit.
  std::size_t fitted_faces = 0;
};

struct Segmentation {
  std::vector<int> face_region;  ///< per face
  std::vector<Region> regions;
  std::size_t merges = 0, seeds = 0, grown_faces = 0, splits = 0, absorbed = 0;
};

/// Bilateral filtering of face normals (Zheng et al. 2011): smooths noise, keeps creases.
std::vector<Eigen::Vector3d> filter_normals(const MeshArrays& m, int iterations, double sigma_r);

/// Picks the simplest primitive whose fit is within tolerance (plane, sphere, cylinder, cone), or
/// freeform. Exposed for tests.
Fit choose_shape(const Samples& s, const SegmentParams& p);

/// The regions of a working mesh's segmentation mapped onto `m` (working_mesh.h), refitted on m's
/// own samples: a fitted region's shape refined on the samples within a few tolerances of it, a
/// freeform one given the shape (simplest type first) that all but a tenth of its samples lie
/// near and that fits those. A coarse face on a rounded crease covers a band the fine mesh would
/// keep apart; its samples are left out of the fit rather than making the region freeform.
void refit_regions(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals, const SegmentParams& p,
                   Segmentation& seg);

Segmentation segment(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals,
                     const std::vector<VertexTensor>& tensors, const SegmentParams& p);

/// The samples of a set of faces: each vertex once, with the area-weighted normal of the set's
/// faces around it (so a crease vertex gets this side's normal) and a third of their area.
Samples region_samples(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals, const std::vector<int>& faces);

}  // namespace s2c::features
