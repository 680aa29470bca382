#pragma once
/// \file Feature analysis of a triangle mesh (paper §3, Kim/Choi/Lee 2009): tensor voting per
/// vertex, feature lines, feature patches with fitted shapes, components and constraints.
#include <array>
#include <cstdint>
#include <filesystem>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "s2c/core/mesh.h"
#include "s2c/features/constraints.h"
#include "s2c/features/feature_set.h"

namespace s2c::features {

enum class VertexClass : unsigned char { face, crease, corner };

struct FeatureOptions {
  double min_crease_deg = 25.0;   ///< smallest crease angle (between face normals) to detect
  double radius = 0.0;            ///< voting radius, mm (0: 1 median edge length; noisy: 2, 3 from noise ≥ 4 % of it)
  double noise = -1.0;            ///< noise σ of the surface, mm (< 0: measured from the mesh)
  double fit_tolerance = 0.0;     ///< accept a shape when RMS ≤ this, mm (0: from noise and size)
  /// A noisy mesh (not a clean tessellation) with more than three times this many vertices is
  /// analysed on a coarser copy (clustered), and the patches are mapped back onto it: a copy of
  /// about this many vertices when the noise is at least 4 % of the edge, of a sixth of the
  /// vertices (at least this many) when smoother (docs/features.md, "Large meshes"); 0: never.
  int working_vertices = 60000;
  bool constraints = true;
  ConstraintOptions constraint;   ///< diagonal is filled from the mesh
};

/// Per-vertex result of tensor voting.
/// In float (computed in double): the class is decided before rounding, and a
/// million vertices' tensors take 27 MB instead of 54 MB.
struct VertexTensor {
  Eigen::Vector3f lambda = Eigen::Vector3f::Zero();  ///< λ1 ≥ λ2 ≥ λ3 (normalised: λ1 = 1)
  /// Crease tangent (the eigenvector of λ3). The normal, e1, is not kept: nothing reads it, and at
  /// a million vertices it was 23 MB.
  Eigen::Vector3f e3 = Eigen::Vector3f::Zero();
  VertexClass cls = VertexClass::face;
};

struct Analysis {
  FeatureSet features;
  std::vector<VertexTensor> vertices;  ///< per mesh vertex
  std::vector<int> face_patch;         ///< per face: index into features.patches
  double noise = 0.0;                  ///< the noise σ used, mm
  double radius = 0.0;                 ///< the voting radius used, mm
  double fit_tolerance = 0.0;          ///< the acceptance RMS used, mm
};

/// Tensor voting only (exposed for tests): T = Σ μ_f n_f n_fᵀ over faces near each vertex.
std::vector<VertexTensor> vote_tensors(const Mesh& mesh, double radius, double min_crease_deg, double noise);

/// The whole analysis. The mesh must have face normals updated. \throw InvalidInput for an empty mesh.
Analysis analyze(const Mesh& mesh, const FeatureOptions& options, nlohmann::json* report = nullptr);

/// The same analysis of an indexed triangle list as read_soup gives it, which it takes over. A
/// manifold list with its faces oriented alike skips the half-edge mesh (a million vertices: 0.1 GB
/// and about a second less); any other goes through soup_to_mesh. Either way the result equals
/// analyze(soup_to_mesh(soup)). \throw InvalidInput for no faces or a face index out of range.
Analysis analyze(TriangleSoup&& soup, const FeatureOptions& options, nlohmann::json* report = nullptr);

}  // namespace s2c::features

namespace s2c::features {

/// The display colour of patch `index` (0–255 RGB): the hue family says the type (planes blues,
/// cylinders greens, cones oranges, spheres purples, freeform grey), the shade varies with the
/// index so that neighbouring patches of one type stay distinguishable.
std::array<std::uint8_t, 3> patch_colour(ShapeType type, int index);

/// Writes the mesh as binary PLY with a per-face `segment` (patch index) and a colour per patch
/// (planes in blues, cylinders greens, cones oranges, spheres purples, freeform grey), so the
/// segmentation can be looked at in any viewer. Atomic. \throw IoError
void write_segments_ply(const Mesh& mesh, const Analysis& analysis, const std::filesystem::path& path);

}  // namespace s2c::features
