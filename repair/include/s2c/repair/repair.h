#pragma once
/// \file The repair stage: from any mesh to a CAD-ready one (DESIGN.md). Surface repair first,
/// because it keeps every input triangle: cleaning, gap closing, hole finding with nested-hole
/// splitting, hole filling. When that cannot make the mesh CAD-ready (non-manifold edges,
/// self-intersections, holes that cannot be patched) the volumetric VDF repair rebuilds the
/// surface, and feature-preserving decimation brings the triangle count back to the detail.
#include <cstddef>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "s2c/core/mesh.h"
#include "s2c/repair/fill.h"
#include "s2c/repair/volumetric.h"

namespace s2c::repair {

enum class Strategy { automatic, surface, volumetric };

struct RepairOptions {
  Strategy strategy = Strategy::automatic;
  FillOptions fill;                  ///< hole filling (method none → holes are left to the volumetric step)
  bool fill_holes = true;
  bool close_gaps = true;
  double gap_tolerance = 0;          ///< mm; 0 = half the mean boundary edge length
  VolumetricOptions volumetric;      ///< voxel 0 = max(longest box side / 320, √(area / 60000))
  /// Decimation after volumetric repair: largest distance a collapse may move the surface,
  /// in voxels (quadric error); 0 = keep every Marching Cubes triangle.
  double decimate_tolerance_voxels = 0.25;
};

struct RepairResult {
  TriangleSoup mesh;
  std::string path;                  ///< "unchanged", "surface" or "volumetric"
  nlohmann::json report;             ///< defects before/after, what each step did, timings
  bool cad_ready = false;
  std::string problem;               ///< why not, when not CAD-ready
};

/// Repairs `input`. When no path gives a CAD-ready mesh, the result says so (`cad_ready` false,
/// `problem`) and still carries the report. \throw InvalidInput for an empty mesh.
RepairResult repair_mesh(const TriangleSoup& input, const RepairOptions& options = {});

/// Quadric-error decimation (OpenMesh Decimater) that never flips a normal, keeps the mesh
/// manifold and stops when the next collapse would move the surface more than `tolerance` mm.
/// Vertices marked in `locked` (by index, optional) are never moved or removed. No collapse leaves
/// a triangle whose longest edge exceeds `max_aspect` times its height (OpenMesh's aspect ratio).
/// Returns the number of faces removed.
std::size_t decimate(TriangleSoup& soup, double tolerance, const std::vector<char>* locked = nullptr,
                     double max_aspect = 8.0);

/// May the source of halfedge h collapse into its target without breaking the mesh's topology?
/// OpenMesh's link condition (the test of TriConnectivity::is_collapse_ok), compiled here: Debian
/// builds libOpenMeshCore with assertions on, which made that library call the decimation's
/// bottleneck (decimate.cpp).
bool collapse_keeps_topology(const Mesh& mesh, Mesh::HalfedgeHandle h);

const char* to_string(Strategy s);

}  // namespace s2c::repair
