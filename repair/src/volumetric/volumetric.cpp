#include "s2c/repair/volumetric.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "s2c/core/clock.h"
#include "s2c/core/distance.h"
#include "s2c/core/errors.h"
#include "volumetric/dual_contouring.h"
#include "volumetric/field.h"
#include "volumetric/marching_cubes.h"

namespace s2c::repair {

namespace {

/// Edges used by one face only. Sorted keys, not a hash map: a 1024³-equivalent extraction has
/// some 18 M edges, which a node-based map holds in ~45 B each against 8 here.
std::size_t open_edges(const TriangleSoup& s) {
  std::vector<std::uint64_t> keys;
  keys.reserve(3 * s.faces.size());
  for (const auto& f : s.faces)
    for (int k = 0; k < 3; ++k) keys.push_back(undirected_edge_key(f[k], f[(k + 1) % 3]));
  std::sort(keys.begin(), keys.end());
  std::size_t open = 0;
  for (std::size_t i = 0; i < keys.size();) {
    std::size_t j = i + 1;
    while (j < keys.size() && keys[j] == keys[i]) ++j;
    open += j - i == 1;
    i = j;
  }
  return open;
}

double surface_area(const TriangleSoup& s) {
  double a = 0;
  for (const auto& f : s.faces)
    a += 0.5 * (s.vertices[f[1]] - s.vertices[f[0]]).cross(s.vertices[f[2]] - s.vertices[f[0]]).norm();
  return a;
}

}  // namespace

double volumetric_memory_estimate(double area, double h, double band) {
  // Band vertices ≈ the surface's cells times the band's thickness (2·band voxels). Peak RSS per
  // such cell at 1024³ (bench/README.md "Repair", memory rows): 48 B on the bracket, 60 B on
  // abc_00000009 (the sign's union-find over every vertex of the band's blocks, then the extracted
  // mesh, which Marching Cubes grows while it frees the grid behind its sweep). 55 B is their middle:
  // an estimate, not a bound; the limit it guards is 80 % of the machine's memory.
  const double surface_cells = area / (h * h);
  return surface_cells * 2.0 * band * 55.0;
}

double default_max_memory() {
  const double pages = static_cast<double>(::sysconf(_SC_PHYS_PAGES)), page = static_cast<double>(::sysconf(_SC_PAGE_SIZE));
  return pages > 0 && page > 0 ? 0.8 * pages * page : 8e9;
}

TriangleSoup volumetric_remesh(const TriangleSoup& input, const VolumetricOptions& options, VolumetricStats* stats_out) {
  if (input.faces.empty()) throw InvalidInput("volumetric repair: the mesh has no faces");
  VolumetricStats stats;
  const Bounds box = bounds(input);
  const double longest = (box.max - box.min).maxCoeff();
  if (!(longest > 0)) throw InvalidInput("volumetric repair: the mesh has no extent (all vertices coincide)");
  double h = options.voxel;
  if (!(h > 0)) h = longest / (options.resolution > 0 ? options.resolution : 256);
  const double max_memory = options.max_memory > 0 ? options.max_memory : default_max_memory();
  const double area = surface_area(input);
  const double band_first = std::max(options.band, std::sqrt(3.0) + 0.05);
  if (volumetric_memory_estimate(area, h, band_first) > max_memory) {
    const double h_min = std::sqrt(area * 2.0 * band_first * 55.0 / max_memory);
    throw InvalidInput(fmt::format("volumetric repair: a {:.3g} mm voxel on this {:.3g} mm² surface needs about {:.1f} GB, "
                                   "above the {:.1f} GB allowed (--max-memory); use --voxel {:.3g} or larger",
                                   h, area, volumetric_memory_estimate(area, h, band_first) / 1e9, max_memory / 1e9,
                                   h_min * 1.01));
  }
  const SurfaceQuery query(input);  // one BVH for the field, the sign and the DC normals
  stats.voxel = h;
  // Attempts, until the surface is closed: the band as asked; a wider band that can bridge wider
  // holes; finally a closed shell around whatever the band cannot decide (always closes).
  struct Attempt {
    double band, shell;
  };
  const double band0 = std::max(options.band, std::sqrt(3.0) + 0.05);
  // The shell sits 0.6 voxel off the surface: its cells reach √3 voxels further, so widen the band.
  const Attempt attempts[] = {{band0, 0.0}, {2.5 * band0, 0.0}, {band0 + 1.5, 0.6 * h}};
  TriangleSoup out;
  for (const Attempt& attempt : attempts) {
    if (!options.retry && attempt.band != band0) break;
    if (!options.retry && attempt.shell > 0) break;
    if (attempt.band != band0 && volumetric_memory_estimate(area, h, attempt.band) > max_memory) {
      spdlog::warn("volumetric repair: a {:.3g}-voxel band would exceed --max-memory; not widened", attempt.band);
      break;
    }
    const double radius = attempt.band * h;
    // Edge keys pack 20 bits per axis; beyond that the voxel is far too small for the part anyway.
    const double cells = longest / h + 2 * attempt.band + 4;
    if (cells > (1 << 20) - 16)
      throw ProcessingError(fmt::format("volumetric repair: voxel {:.3g} mm gives {:.0f} cells across a {:.3g} mm part; "
                                        "use a larger --voxel", h, cells, longest));
    // CAD faces sit at round coordinates; a grid plane through a face puts vertices exactly on the
    // surface, where inside/outside is a coin toss. An odd fraction of a voxel keeps them apart.
    const Eigen::Vector3d origin = box.min - Eigen::Vector3d::Constant((std::ceil(attempt.band) + 2 + 0.3719) * h);
    VolumetricStats st;
    st.voxel = h;
    {  // the grid is freed before the closure test: at 1024³ both are hundreds of MB
      SparseGrid grid(origin, h, radius);
      auto t0 = std::chrono::steady_clock::now();
      build_vector_field(input, query, radius, grid, st);
      st.seconds_field = seconds_since(t0);
      t0 = std::chrono::steady_clock::now();
      classify_inside(input, query, options.sign, attempt.shell, grid, st);
      st.seconds_sign = seconds_since(t0);
      t0 = std::chrono::steady_clock::now();
      out = TriangleSoup{};  // the previous attempt's mesh
      out = options.extract == Extract::dc ? dual_contouring(grid, input, query, options.interp, st)
                                           : marching_cubes(std::move(grid), options.interp, st);
      st.seconds_extract = seconds_since(t0);
    }
    st.attempts = stats.attempts + 1;
    st.band = attempt.band;
    st.shell = attempt.shell;
    stats = st;
    if (open_edges(out) == 0) break;
  }
  if (stats_out) *stats_out = stats;
  return out;
}

double vdf_paper_error(const TriangleSoup& mesh, const TriangleSoup& reference) {
  const SurfaceQuery query(reference);
  std::vector<double> vertex_area(mesh.vertices.size(), 0.0);
  double total = 0;
  for (const auto& f : mesh.faces) {
    const double a = 0.5 * (mesh.vertices[f[1]] - mesh.vertices[f[0]]).cross(mesh.vertices[f[2]] - mesh.vertices[f[0]]).norm();
    total += a;
    for (int k = 0; k < 3; ++k) vertex_area[f[k]] += a;
  }
  if (!(total > 0)) return 0;
  double sum = 0;
  for (std::size_t i = 0; i < mesh.vertices.size(); ++i) {
    if (vertex_area[i] == 0) continue;
    const auto hit = query.closest(mesh.vertices[i]);
    const double d = hit ? hit->distance : 0;
    sum += d * d * vertex_area[i];
  }
  return std::sqrt(sum / (3 * total));
}

const char* to_string(Interp i) {
  switch (i) {
    case Interp::vector: return "vector";
    case Interp::hermite: return "hermite";
    default: return "linear";
  }
}
const char* to_string(SignMode s) { return s == SignMode::winding ? "winding" : "dot"; }
const char* to_string(Extract e) { return e == Extract::dc ? "dc" : "mc"; }

}  // namespace s2c::repair
