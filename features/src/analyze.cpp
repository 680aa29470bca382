// The feature analysis pipeline (paper §3): tensor voting → patches (flood fill, shape fitting,
// merging) → lines (patch borders at creases, fitted) → components, adjacency → constraints.
#include "s2c/features/analyze.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <functional>
#include <map>
#include <optional>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include "lines.h"
#include "mesh_arrays.h"
#include "s2c/core/clock.h"
#include "s2c/core/disjoint_sets.h"
#include "s2c/core/errors.h"
#include "s2c/features/constraints.h"
#include "segment.h"
#include "tensor_voting.h"
#include "working_mesh.h"

namespace s2c::features {
namespace {

using Clock = std::chrono::steady_clock;

/// Relative noise (measure_noise / median edge) below which a mesh counts as a clean
/// tessellation: raw face normals are then trusted as they are (no filtering, plain flood fill).
/// Measured: CAD exports 0 – 5.4e-4 (real/cad, the fixture parts' OpenSCAD meshes), Poisson
/// meshes of the fixture scans 0.011 – 0.016, noise-sweep meshes at σ = 0.1h 0.094 – 0.10. The
/// threshold sits between CAD and scans with a margin of about 4 each way (it was 0.01, which a
/// scan with a flat-filled end face fell below).
constexpr double kCleanNoise = 0.003;

/// Relative noise (noise / median edge) from which the vote is kWideVoteEdges wide instead of
/// kNarrowVoteEdges. Measured: the fixture scans' repaired meshes 0.011 – 0.016, the noise sweep's
/// meshes at σ = 0.1h 0.094 – 0.10; the threshold sits between them, about 2.5 from each. On the
/// scans two edges give the quality tables of three (bench/README, "a narrower vote on scans")
/// at 0.6 of the vote's time; at σ = 0.1h the shaft's chamfer needs three (NoisyShaft test).
constexpr double kWideVoteNoise = 0.04;
constexpr double kNarrowVoteEdges = 2.0, kWideVoteEdges = 3.0;

/// The working mesh's cell is at most this many median edges of the mesh (kWorkingSlack).
constexpr double kMaxCellEdges = 4.0;

/// The default voting radius in median edge lengths. (On a noisy mesh the tensors only order the
/// split's seeds and count the classes in the report: the patches, lines and constraints come from
/// the filtered normals and the fits, so the vote need only be as wide as the noise demands.)
double vote_edges(bool noisy, double relative_noise) {
  if (!noisy) return 1.0;
  return relative_noise < kWideVoteNoise ? kNarrowVoteEdges : kWideVoteEdges;
}

/// A noisy mesh with more than this many times FeatureOptions::working_vertices vertices is analysed
/// on a working mesh (working_mesh.h). Below, the whole mesh takes under 2 s (about 10 s per
/// million vertices). A mesh whose noise is at least kWideVoteNoise of its edge is finer than its
/// noise: the full analysis votes three edges wide and smooths its normals over several, so it
/// resolves nothing narrower than the working mesh's cell (at most kMaxCellEdges edges), and the
/// working mesh has working_vertices vertices.
constexpr int kWorkingSlack = 3;

/// A smoother mesh (a Poisson surface: noise 1.1-2.2 % of the edge) resolves more: its working
/// mesh keeps one vertex in this many (at least working_vertices). Stop 50, on the five fixture
/// scans at Poisson depth 9 (0.40-0.87 M vertices): a sixth found 42 of 44 primitives, the whole
/// mesh 41, at 2.3-2.6 s per million vertices instead of 7.9-8.8; an eighth 13 of the pocket's
/// 14, a tenth 11; 60 k found 4. Since stop 54 (lines as precise as the working edge) a seventh:
/// 43 of 44 primitives on those five and 43 of 44 on five more scans of the parts (seed 2), every
/// constraint precision ≥ 0.98 (a sixth: 42 and 41 of 44, precision 0.60 and 0.81 on two of the
/// second five; an eighth lost the bracket's wall top there again), at 6-17 % less time
/// (bench/README, "a seventh, and lines as precise as the working edge").
constexpr int kSmoothReduction = 7;

/// The working mesh's target vertices for a mesh of `relative_noise` (noise / median edge), or 0
/// for none: only noisy meshes larger than kWorkingSlack times `working_vertices` have one.
int working_target(int vertices, double relative_noise, int working_vertices) {
  if (working_vertices <= 0 || relative_noise <= kCleanNoise || vertices <= kWorkingSlack * working_vertices) return 0;
  return relative_noise >= kWideVoteNoise ? working_vertices : std::max(working_vertices, vertices / kSmoothReduction);
}

/// Fit tolerance floor on noisy meshes, in median edge lengths, and in measured waviness (see
/// analyze()).
constexpr double kWavinessPerEdge = 0.1;
constexpr double kWavinessFactor = 3.0;

/// Constraint detection compares features pairwise. A mesh that falls apart into more features
/// than this (a broken or unrepaired scan) gets none, with a warning, rather than a run of hours:
/// its constraints would mean nothing anyway.
constexpr std::size_t kMaxConstraintFeatures = 20000;

/// The mesh's connected components as groups of the features on them, numbered from G0.
std::vector<Group> component_groups(const MeshArrays& m, const Segmentation& seg, const FeatureSet& f) {
  DisjointSets sets(m.faces());
  for (const auto& E : m.edges)
    if (E.f1 >= 0) sets.unite(E.f0, E.f1);
  std::map<int, std::vector<std::string>> members;  // component root → feature ids
  for (std::size_t p = 0; p < f.patches.size(); ++p)
    members[sets.find(seg.regions[p].faces.front())].push_back(f.patches[p].id);
  for (const auto& l : f.lines) {
    const int v = l.vertices.front();
    members[sets.find(m.vf[m.vf_start[v]])].push_back(l.id);
  }
  std::vector<Group> groups;
  for (auto& [root, ids] : members) {
    Group g;
    g.id = fmt::format("G{}", groups.size());
    g.kind = "component";
    g.members = std::move(ids);
    groups.push_back(std::move(g));
  }
  return groups;
}

/// Patches sharing a vertex are adjacent (the paper: one shared vertex counts), lines are adjacent
/// to the patches around their vertices and to lines they share a vertex with.
void add_adjacency(const MeshArrays& m, const Segmentation& seg, FeatureSet& f) {
  // Features by number: patch p is p, line l is np + l, which is the ids' natural order (P before
  // L, numbers ascending). Pairs of numbers sort and compare for much less than pairs of ids.
  const int np = static_cast<int>(f.patches.size()), nv = m.vertices();
  // (vertex, line) for every vertex of every line, by vertex: a few per cent of the vertices have
  // lines (a list per vertex was 23 MB of empty lists at a million vertices).
  std::vector<std::pair<int, int>> line_at;
  for (std::size_t l = 0; l < f.lines.size(); ++l)
    for (int v : f.lines[l].vertices) line_at.emplace_back(v, np + static_cast<int>(l));
  std::sort(line_at.begin(), line_at.end());
  // The vertices in blocks side by side, each collecting its pairs (smaller number first).
  constexpr int kBlock = 1 << 16;
  std::vector<std::vector<std::pair<int, int>>> found((nv + kBlock - 1) / kBlock);
  tbb::parallel_for(0, static_cast<int>(found.size()), [&](int block) {
    std::vector<std::pair<int, int>>& pairs = found[block];
    auto add = [&](int a, int b) {
      if (a != b) pairs.emplace_back(std::min(a, b), std::max(a, b));
    };
    std::vector<int> around, lines_here;
    const int begin = block * kBlock, end = std::min(nv, begin + kBlock);
    auto next = std::lower_bound(line_at.begin(), line_at.end(), std::make_pair(begin, -1));
    for (int v = begin; v < end; ++v) {
      lines_here.clear();
      for (; next != line_at.end() && next->first == v; ++next) lines_here.push_back(next->second);
      around.clear();
      for (int k = m.vf_start[v]; k < m.vf_start[v + 1]; ++k) around.push_back(seg.face_region[m.vf[k]]);
      std::sort(around.begin(), around.end());
      around.erase(std::unique(around.begin(), around.end()), around.end());
      for (std::size_t i = 0; i < around.size(); ++i) {
        for (std::size_t j = i + 1; j < around.size(); ++j) add(around[i], around[j]);
        for (int l : lines_here) add(around[i], l);
      }
      for (std::size_t i = 0; i < lines_here.size(); ++i)
        for (std::size_t j = i + 1; j < lines_here.size(); ++j) add(lines_here[i], lines_here[j]);
    }
  });
  std::vector<std::pair<int, int>> pairs;
  for (const auto& block : found) pairs.insert(pairs.end(), block.begin(), block.end());
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  auto id = [&](int k) -> const std::string& { return k < np ? f.patches[k].id : f.lines[k - np].id; };
  f.adjacency.clear();
  f.adjacency.reserve(pairs.size());
  for (const auto& [a, b] : pairs) f.adjacency.emplace_back(id(a), id(b));
}

}  // namespace

std::vector<VertexTensor> vote_tensors(const Mesh& mesh, double radius, double min_crease_deg, double noise) {
  const MeshArrays m = build_arrays(mesh);
  return vote(m, m.fnormal, radius, voting_thresholds(min_crease_deg, noise, m.median_edge));
}

namespace {

/// The analysis of the arrays; `timings` already holds the time taken to build them.
Analysis analyze_arrays(const MeshArrays& m, const FeatureOptions& o, nlohmann::json timings, nlohmann::json* report) {
  Analysis out;
  auto t = Clock::now();
  const double diag = std::max(m.box.diagonal(), 1e-9);
  const double edge = m.median_edge > 0 ? m.median_edge : diag * 1e-3;

  out.noise = o.noise >= 0 ? o.noise : measure_noise(m);
  const bool noisy = out.noise > kCleanNoise * edge;
  // A reconstructed surface (Poisson) is smooth between its vertices, so the edge-local noise
  // misses its error, which is waviness a few edges wide: a tenth of an edge bounds it on noisy
  // meshes at the default reconstruction depth (fixture scans: plane RMS 0.015-0.02 mm at 0.26 mm
  // edges). A finer reconstruction has shorter edges but no smaller bumps, so the waviness itself
  // counts too, three times over as the noise does (the pocket scan at Poisson depth 9: 0.0069
  // mm, the floor 0.0147 mm from the diagonal: 1,523 patches, 603 with this floor).
  const double waviness = noisy && o.fit_tolerance <= 0 ? measure_waviness(m) : 0.0;
  const double floor = std::max({2e-4 * diag, noisy ? kWavinessPerEdge * edge : 0.0, kWavinessFactor * waviness});
  out.fit_tolerance = o.fit_tolerance > 0 ? o.fit_tolerance : std::max(3.0 * out.noise, floor);
  timings["noise"] = seconds_since(t);
  t = Clock::now();

  // A large noisy mesh is analysed on a coarser copy (working_mesh.h); the tolerance above stays
  // the fine mesh's, the vote's radius and thresholds are the copy's own.
  std::optional<WorkingMesh> working;
  const bool smooth = out.noise < kWideVoteNoise * edge;
  if (const int target = working_target(m.vertices(), out.noise / edge, o.working_vertices); target > 0) {
    working = coarsen(m, target, kMaxCellEdges * edge, smooth);
    // Most of the mesh collapsed (debris: pieces smaller than a cell): no copy to analyse.
    if (working->arrays.faces() < target / 2) working.reset();
    timings["working_mesh"] = seconds_since(t);
    t = Clock::now();
  }
  const MeshArrays& a = working ? working->arrays : m;
  const double a_edge = working && a.median_edge > 0 ? a.median_edge : edge;
  const double a_noise = working ? measure_noise(a) : out.noise;
  // Noise needs a wider vote and smoothed normals; a clean tessellation keeps its exact normals,
  // so one edge is enough: a vertex's own faces always vote, and faces one edge away show a crease
  // that passes next to it. Two edges found the same patches, lines and constraints on the
  // fixture parts at twice the time (bench/README, "speed"), and widened the crease band.
  out.radius = o.radius > 0 ? o.radius : vote_edges(noisy, a_noise / a_edge) * a_edge;
  // (A reference, not a copy, of the face normals: 80 MB at 3.3 M faces.)
  std::vector<Eigen::Vector3d> filtered;
  if (noisy) filtered = filter_normals(a, 8, 0.35);
  const std::vector<Eigen::Vector3d>& normals = noisy ? filtered : a.fnormal;
  timings["normals"] = seconds_since(t);

  t = Clock::now();
  std::vector<VertexTensor> tensors = vote(a, normals, out.radius, voting_thresholds(o.min_crease_deg, noisy ? a_noise : 0.0, a_edge));
  timings["tensor_voting"] = seconds_since(t);

  t = Clock::now();
  SegmentParams sp;
  sp.min_crease_deg = o.min_crease_deg;
  sp.noisy = noisy;
  sp.diagonal = diag;
  sp.tolerance = out.fit_tolerance;
  sp.normal_tol_deg = noisy ? 20.0 : 10.0;
  if (working && smooth) sp.face_scale = static_cast<double>(m.faces()) / std::max(a.faces(), 1);
  Segmentation seg = segment(a, normals, tensors, sp);
  timings["patches"] = seconds_since(t);

  std::optional<MappedNormals> fine_normals;
  if (working) {
    t = Clock::now();
    // The border moves by up to a working edge; a face ring more covers the crease's zigzag.
    const int passes = static_cast<int>(std::ceil(working->cell / edge)) + 1;
    seg = map_back(m, *working, seg, out.fit_tolerance, passes);
    // A smooth mesh's own normals are as good as the working mesh's filtered ones.
    if (smooth) refit_regions(m, m.fnormal, sp, seg);
    fine_normals.emplace(m, *working, normals);
    out.vertices.resize(m.vertices());
    tbb::parallel_for(0, m.vertices(), [&](int v) { out.vertices[v] = tensors[working->vertex_cluster[v]]; });
    timings["map_back"] = seconds_since(t);
  } else {
    out.vertices = std::move(tensors);
  }

  t = Clock::now();
  // (Through a working mesh the borders are a working edge precise: the lines' tolerance says so.)
  const std::vector<TracedLine> traced =
      working ? trace_lines(m, std::cref(*fine_normals), seg, o.min_crease_deg, out.fit_tolerance, noisy, a_edge)
              : trace_lines(m, normals, seg, o.min_crease_deg, out.fit_tolerance, noisy);
  timings["lines"] = seconds_since(t);

  FeatureSet& f = out.features;
  f.mesh_vertices = m.vertices();
  f.mesh_faces = m.faces();
  out.face_patch = seg.face_region;
  for (std::size_t r = 0; r < seg.regions.size(); ++r) {
    const Region& region = seg.regions[r];
    Patch p;
    p.id = fmt::format("P{}", r);
    p.faces = region.faces;
    p.area = region.area;
    p.rms = region.fit.rms;
    p.shape = region.fit.shape;
    f.patches.push_back(std::move(p));
  }
  for (std::size_t l = 0; l < traced.size(); ++l) {
    Line line;
    line.id = fmt::format("L{}", l);
    line.vertices = traced[l].vertices;
    line.closed = traced[l].closed;
    line.rms = traced[l].fit.rms;
    line.shape = traced[l].fit.shape;
    f.lines.push_back(std::move(line));
  }
  t = Clock::now();
  int constraints = 0;
  const std::size_t feature_count = f.patches.size() + f.lines.size();
  const bool too_many = feature_count > kMaxConstraintFeatures;
  if (o.constraints && too_many)
    spdlog::warn("{} patches and lines: more than {}, so no constraints are detected; the mesh is "
                 "probably broken or very noisy: run scan2cad repair first, or raise --min-angle",
                 feature_count, kMaxConstraintFeatures);
  ConstraintOptions co = o.constraint;
  co.diagonal = diag;
  if (noisy && co.min_patch_area <= 0) {
    double total = 0;
    for (const auto& p : f.patches) total += p.area;
    co.min_patch_area = kMinorAreaShare * total;
  }
  if (noisy && co.min_fixed_angle_deg <= 0) co.min_fixed_angle_deg = o.min_crease_deg;
  // The component groups beside the adjacency and the constraint search that reads it (0.05 s
  // each at a million vertices); the constraints are numbered after the components.
  std::optional<ConstraintSearch> search;
  std::vector<Group> components;
  tbb::parallel_invoke(
      [&] {
        add_adjacency(m, seg, f);
        if (o.constraints && !too_many) search.emplace(f, co);
      },
      [&] { components = component_groups(m, seg, f); });
  f.groups = std::move(components);
  if (search) constraints = search->add_to(f);
  timings["groups"] = seconds_since(t);

  if (report) {
    std::map<std::string, int> patch_types, line_types, kinds;
    for (const auto& p : f.patches) ++patch_types[shape_name(p.shape.type)];
    for (const auto& l : f.lines) ++line_types[shape_name(l.shape.type)];
    for (const auto& g : f.groups)
      if (g.constraint) ++kinds[constraint_name(*g.constraint)];
    std::size_t classes[3] = {0, 0, 0};
    for (const auto& v : out.vertices) ++classes[static_cast<int>(v.cls)];
    (*report)["mode"] = noisy ? "noisy" : "clean";
    (*report)["noise_mm"] = out.noise;
    (*report)["median_edge_mm"] = edge;
    (*report)["voting_radius_mm"] = out.radius;
    (*report)["fit_tolerance_mm"] = out.fit_tolerance;
    if (waviness > 0) (*report)["waviness_mm"] = waviness;
    if (working)
      (*report)["working_mesh"] = {{"vertices", working->arrays.vertices()}, {"faces", working->arrays.faces()},
                                   {"cell_mm", working->cell}, {"noise_mm", a_noise}};
    (*report)["vertices"] = {{"face", classes[0]}, {"crease", classes[1]}, {"corner", classes[2]}};
    (*report)["patches"] = f.patches.size();
    (*report)["patch_types"] = patch_types;
    (*report)["lines"] = f.lines.size();
    (*report)["line_types"] = line_types;
    (*report)["constraints"] = constraints;
    if (o.constraints && too_many) (*report)["constraints_skipped"] = "too many features";
    (*report)["constraint_kinds"] = kinds;
    (*report)["seed_regions"] = seg.seeds;
    (*report)["merged_patches"] = seg.merges;
    (*report)["split_patches"] = seg.splits;
    (*report)["grown_faces"] = seg.grown_faces;
    (*report)["absorbed_patches"] = seg.absorbed;
    (*report)["timings_s"] = timings;
  }
  spdlog::info("{} patches ({} freeform), {} lines, {} constraints; noise {:.3g} mm ({})", f.patches.size(),
               std::count_if(f.patches.begin(), f.patches.end(),
                             [](const Patch& p) { return p.shape.type == ShapeType::freeform; }),
               f.lines.size(), constraints, out.noise, noisy ? "noisy: normals filtered" : "clean tessellation");
  return out;
}

}  // namespace

Analysis analyze(const Mesh& mesh, const FeatureOptions& o, nlohmann::json* report) {
  if (mesh.n_faces() == 0) throw InvalidInput("the mesh has no faces: nothing to analyse");
  const auto t = Clock::now();
  const MeshArrays m = build_arrays(mesh);
  return analyze_arrays(m, o, {{"arrays", seconds_since(t)}}, report);
}

Analysis analyze(TriangleSoup&& soup, const FeatureOptions& o, nlohmann::json* report) {
  if (soup.faces.empty()) throw InvalidInput("the mesh has no faces: nothing to analyse");
  const auto t = Clock::now();
  bool through_mesh = false;
  const MeshArrays m = build_arrays(std::move(soup), &through_mesh);
  Analysis out = analyze_arrays(m, o, {{"arrays", seconds_since(t)}}, report);
  if (report) (*report)["half_edge_mesh_built"] = through_mesh;
  return out;
}

}  // namespace s2c::features
