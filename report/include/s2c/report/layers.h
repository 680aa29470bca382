#pragma once
/// \file What the pictures show, built from the pipeline's files: a cloud as points, a mesh in
/// grey, the regions of a mesh that are new compared with another (filled holes, edits),
/// feature patches coloured by type with their feature lines, and a deviation map.
#include <cstddef>
#include <optional>

#include "s2c/core/mesh.h"
#include "s2c/features/feature_set.h"
#include "s2c/report/deviation.h"
#include "s2c/report/render.h"

namespace s2c::report {

/// A cloud's points (with normals when the file has them), at most `max_points` (an even
/// subsample beyond that: a picture does not need more).
PointLayer cloud_layer(const TriangleSoup& cloud, std::size_t max_points = 1500000);

struct ChangedRegions {
  MeshLayer layer;
  std::size_t faces = 0;  ///< faces farther than the threshold from the base surface
  double area = 0;        ///< their area, mm²
  std::size_t regions = 0;  ///< connected regions of such faces
  /// The largest region (by area): its bounds and area-weighted normal, for a close-up.
  std::optional<Bounds> largest;
  Eigen::Vector3d largest_normal = Eigen::Vector3d::UnitZ();
};
/// `mesh` in grey with the faces whose centre is farther than `threshold` mm from `base` in
/// `highlight`: what a repair added (filled holes, closed gaps) or what an edit moved.
ChangedRegions changed_regions(TriangleSoup mesh, const TriangleSoup& base, double threshold, const Colour& highlight);

/// The patches of `features` coloured by type (features::patch_colour, faces in no patch grey)
/// and its feature lines as polylines. \throw InvalidInput when the features refer to faces or
/// vertices the mesh does not have (features.json of another mesh).
void add_features(Scene& scene, TriangleSoup mesh, const features::FeatureSet& features);

/// `mesh` coloured per vertex by its signed deviation (deviation_colour over ±range).
MeshLayer deviation_layer(TriangleSoup mesh, const Deviation& deviation, double range);

}  // namespace s2c::report
