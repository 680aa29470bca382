#pragma once
/// \file Volumetric repair with the vector-field distance function (VDF) of
/// ../shared/papers/vdf-volumetric-repair.txt: every grid vertex of a sparse narrow band stores the
/// vector to its closest surface point; the surface is re-extracted with Marching Cubes (or dual
/// contouring) whose edge point is the closest point on the cube edge to the segment between the
/// two closest points (the paper's λ), refined at sharp edges by default (`Interp`), or with
/// linear interpolation of signed distances (`linear`, the scalar baseline). Whatever the input's
/// defects, the output is closed, manifold and consistently oriented (where the band reaches
/// across every hole).
#include <cstddef>
#include <vector>

#include "s2c/core/mesh.h"

namespace s2c::repair {

/// Edge point of the extraction: `vector` the paper's λ; `hermite` λ, then, where the two closest
/// points lie on different planes (a sharp edge between the cube edge's ends), the crossing of
/// the cube edge with their tangent planes; `linear` the scalar baseline.
enum class Interp { vector, linear, hermite };
/// Surface extraction: Marching Cubes, or dual contouring from the same Hermite data (closest
/// points + normals) with one vertex per surface sheet of a cell, which keeps sharp edges.
enum class Extract { mc, dc };
/// How a band vertex is classified inside or outside.
/// `winding`: generalised winding number ≥ 1/2 (fast approximation, Barill et al. 2018): robust to
/// holes, overlaps, duplicate and flipped faces, nested shells. `dot`: the paper's rule, sign of
/// (closest point − vertex)·n with angle-weighted pseudonormals at edges and vertices (exact for
/// a clean closed mesh, wrong near holes and overlaps).
enum class SignMode { winding, dot };

struct VolumetricOptions {
  double voxel = 0;        ///< grid spacing, mm; 0 = from `resolution`
  int resolution = 0;      ///< cells along the longest box side when voxel = 0; 0 = 256
  double band = 2.0;       ///< narrow-band half width in voxels (at least sqrt(3): every cell the surface crosses)
  Interp interp = Interp::hermite;
  SignMode sign = SignMode::winding;
  Extract extract = Extract::mc;
  /// When the surface does not close (a hole wider than the band), retry with a 2.5× wider band,
  /// then with a closed shell of 0.6 voxel half-thickness where the band cannot tell inside from
  /// outside. Off: one attempt, whatever it gives.
  bool retry = true;
  /// Memory the grid may use, bytes; 0 = 80% of this machine's RAM. A grid estimated above it is
  /// refused before anything is allocated (InvalidInput naming the smallest voxel that fits).
  double max_memory = 0;
};

/// What the narrow band and the extracted surface of `area` mm² at voxel `h` and band `band`
/// voxels need, bytes (calibrated on peak RSS measurements, bench/README.md "Repair").
double volumetric_memory_estimate(double area, double h, double band);
/// 80% of the physical memory (the default of --max-memory).
double default_max_memory();

struct VolumetricStats {
  double voxel = 0;                  ///< mm
  std::size_t band_vertices = 0;     ///< grid vertices within the band (closest point stored)
  std::size_t blocks = 0;            ///< 8³ blocks allocated
  std::size_t bytes = 0;             ///< memory of the sparse grid
  std::size_t sign_queries = 0;      ///< winding-number evaluations
  std::size_t sign_regions = 0;      ///< band regions no surface separates
  std::size_t sign_regions_mixed = 0;  ///< regions that needed the winding number at every vertex
  std::size_t triangles = 0;         ///< extracted
  std::size_t clamped_edges = 0;     ///< vector interpolation: λ outside [0,1] or parallel (clamped / fell back)
  double seconds_field = 0, seconds_sign = 0, seconds_extract = 0;  ///< of the last attempt
  int attempts = 0;                  ///< 1 when the first band closed the surface
  double band = 0;                   ///< band half width of the last attempt, voxels
  double shell = 0;                  ///< mm; > 0 when the shell fallback was needed
};

/// Extracts a closed surface from the VDF of `input` (any soup; defects are welcome).
/// \throw InvalidInput for an empty input, ProcessingError if the grid would be unreasonably large.
TriangleSoup volumetric_remesh(const TriangleSoup& input, const VolumetricOptions& options,
                               VolumetricStats* stats = nullptr);

/// Meshing an oriented point cloud through the same vector field: each band vertex stores the
/// vector to the implicit moving-least-squares surface of the points (the weighted mean of their
/// tangent planes), and Marching Cubes extracts it. Surface only where the data is: a vertex with
/// less support than `min_support` is outside the band, so unseen regions stay open.
struct PointContourOptions {
  double voxel = 0;          ///< grid spacing, mm (> 0)
  double radius = 0;         ///< support radius of a point, mm; 0 = 2 voxels (below 8 voxels)
  /// Σ weights the vertex's closest surface point needs (one point at distance 0 weighs 1).
  double min_support = 0.5;
  /// The most the closest surface point may lie off the weighted centroid of the points,
  /// tangentially, as a fraction of the radius: where it lies further the surface would go on
  /// past the data (a rim, or a fin past a convex edge).
  double max_offset = 0.5;
  Interp interp = Interp::hermite;
};

/// \param normals unit normals, outward (towards the sensor), one per point.
/// \throw InvalidInput for no points, a size mismatch, non-finite points or a bad voxel/radius.
TriangleSoup contour_oriented_points(const std::vector<Eigen::Vector3d>& points,
                                     const std::vector<Eigen::Vector3d>& normals, const PointContourOptions& options,
                                     VolumetricStats* stats = nullptr);

/// The paper's error measure ε = sqrt( Σ_i dist(v_i, R)² · A(v_i) / (3 A(M)) ), A(v_i) = area of the
/// faces around v_i, A(M) = area of M: the area-weighted RMS distance of M's vertices to R.
double vdf_paper_error(const TriangleSoup& mesh, const TriangleSoup& reference);

const char* to_string(Interp i);
const char* to_string(SignMode s);
const char* to_string(Extract e);

}  // namespace s2c::repair
