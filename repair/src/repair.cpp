// The repair driver: surface repair when it suffices, volumetric repair when it does not.
#include "s2c/repair/repair.h"

#include <algorithm>
#include <chrono>
#include <cmath>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "s2c/core/clock.h"
#include "s2c/core/errors.h"
#include "s2c/core/progress.h"
#include "s2c/repair/defects.h"
#include "s2c/repair/gaps.h"
#include "s2c/repair/holes.h"
#include "soup_topology.h"

namespace s2c::repair {

namespace {

using Clock = std::chrono::steady_clock;

/// Adds the time since t0 to rep.seconds.key (steps can run more than once).
void add_seconds(nlohmann::json& rep, const char* key, Clock::time_point t0) {
  auto& slot = rep["seconds"][key];
  slot = (slot.is_number() ? slot.get<double>() : 0.0) + seconds_since(t0);
}

nlohmann::json clean_json(const CleanStats& c) {
  return {{"duplicate_faces_removed", c.duplicate_faces_removed},
          {"degenerate_faces_removed", c.degenerate_faces_removed},
          {"tiny_components_removed", c.tiny_components_removed},
          {"unreferenced_vertices_removed", c.unreferenced_vertices_removed},
          {"faces_flipped", c.faces_flipped},
          {"edge_manifold", c.edge_manifold}};
}

/// Removes the faces on non-manifold edges and, optionally, the faces of intersecting pairs with
/// their edge neighbours: what is left is edge-manifold, and the holes this cuts are filled like
/// any other hole (MeshFix's strategy: cut out what is wrong, then patch).
std::size_t cut_out_bad_faces(TriangleSoup& soup, bool self_intersections) {
  std::vector<char> drop(soup.faces.size(), 0);
  const auto edges = edge_faces(soup);
  for (const auto& [key, faces] : edges)
    if (faces.size() > 2)
      for (int f : faces) drop[f] = 1;
  if (self_intersections) {
    for (const auto& [a, b] : self_intersecting_pairs(soup)) drop[a] = drop[b] = 1;
    // One ring of neighbours too: the patch then starts from a rim that is clear of the crossing.
    std::vector<char> grown = drop;
    for (const auto& [key, faces] : edges) {
      bool any = false;
      for (int f : faces) any |= drop[f] != 0;
      if (any)
        for (int f : faces) grown[f] = 1;
    }
    drop.swap(grown);
  }
  std::size_t w = 0, removed = 0;
  for (std::size_t fi = 0; fi < soup.faces.size(); ++fi) {
    if (drop[fi]) {
      ++removed;
      continue;
    }
    soup.faces[w++] = soup.faces[fi];
  }
  soup.faces.resize(w);
  return removed;
}

/// Gap closing and hole filling on an edge-manifold soup.
void close_and_fill(TriangleSoup& soup, const RepairOptions& o, nlohmann::json& rep, int round) {
  auto t0 = Clock::now();
  GapOptions go;
  go.tolerance = o.gap_tolerance;
  const GapStats g = o.close_gaps ? close_gaps(soup, go) : GapStats{};
  if (round == 0)
    rep["gaps"] = {{"contractions", g.contractions}, {"edge_splits", g.edge_splits}, {"max_distance_mm", g.max_distance}};
  add_seconds(rep, "gaps", t0);
  if (g.contractions > 0) clean(soup);  // contractions can leave unreferenced vertices and slivers
  if (!o.fill_holes) return;
  t0 = Clock::now();
  HoleStats hs;
  std::vector<Hole> holes = find_holes(soup, &hs);
  // The part's unseen end faces: their jagged rims are cut flush with one plane first.
  std::vector<EndCapTrim> caps;
  if (o.fill.method == FillMethod::automatic) caps = trim_end_caps(soup, holes, o.fill, &hs);
  const std::vector<FillResult> filled = fill_holes(soup, holes, o.fill);
  nlohmann::json list = nlohmann::json::array();
  std::size_t n_filled = 0;
  for (std::size_t i = 0; i < filled.size(); ++i) {
    const auto& f = filled[i];
    n_filled += f.filled;
    list.push_back({{"rim_vertices", holes[i].loop.size()},
                    {"origin", holes[i].origin == Hole::Origin::nested ? "nested" : "single"},
                    {"diameter_mm", holes[i].diameter},
                    {"method", to_string(f.method)},
                    {"choice", f.choice},
                    {"filled", f.filled},
                    {"reason", f.reason},
                    {"new_faces", f.new_faces},
                    {"seconds", f.seconds}});
  }
  for (const EndCapTrim& c : caps)
    if (c.hole < list.size()) list[c.hole]["end_cap_trim"] = {{"depth_mm", c.depth_mm}, {"faces_removed", c.faces_removed},
                                    {"faces_clipped", c.faces_clipped}, {"vertices_snapped", c.vertices_snapped}};
  rep["holes"].push_back({{"round", round}, {"boundary_edges", hs.boundary_edges}, {"single", hs.single_holes},
                          {"nested", hs.nested_holes}, {"common_points", hs.common_points},
                          {"to_fill", hs.holes_out}, {"filled", n_filled}, {"list", list}});
  add_seconds(rep, "holes", t0);
  clean(soup);  // filled components may now be closed: orient them outward
}

/// Cleaning, cutting out non-manifold and self-intersecting faces, gap closing, hole filling,
/// in up to three rounds. Returns the check of the result.
CheckResult surface_repair(TriangleSoup& soup, const RepairOptions& o, nlohmann::json& rep) {
  auto t0 = Clock::now();
  const CleanStats c = clean(soup);
  rep["clean"] = clean_json(c);
  rep["seconds"]["clean"] = seconds_since(t0);
  rep["holes"] = nlohmann::json::array();
  CheckResult check;
  for (int round = 0; round < 3; ++round) {
    const bool cut_intersections = round > 0;
    const std::size_t cut = cut_out_bad_faces(soup, cut_intersections);
    if (cut > 0) {
      rep["cut_faces"].push_back({{"round", round}, {"faces", cut}, {"self_intersections", cut_intersections}});
      clean(soup);
    }
    if (soup.faces.empty()) break;
    close_and_fill(soup, o, rep, round);
    check = check_mesh(soup);
    if (check.cad_ready || check.self_intersections == 0) break;
  }
  return check;
}

/// The default grid: the longest side / 320, but no finer than √(area / 60000) so that Marching
/// Cubes gives some 10⁵ triangles, not millions, before decimation (which costs ~25 µs per collapse).
double default_voxel(const TriangleSoup& soup) {
  const Bounds b = bounds(soup);
  double area = 0;
  for (std::size_t f = 0; f < soup.faces.size(); ++f) area += face_area(soup, static_cast<int>(f));
  return std::max((b.max - b.min).maxCoeff() / 320, std::sqrt(area / 60000));
}

nlohmann::json volumetric_json(const VolumetricOptions& vo, const VolumetricStats& st) {
  return {{"voxel_mm", st.voxel},
          {"band_voxels", vo.band},
          {"interp", to_string(vo.interp)},
          {"sign", to_string(vo.sign)},
          {"extract", to_string(vo.extract)},
          {"band_vertices", st.band_vertices},
          {"blocks", st.blocks},
          {"grid_bytes", st.bytes},
          {"triangles", st.triangles},
          {"clamped_edges", st.clamped_edges},
          {"seconds_field", st.seconds_field},
          {"seconds_sign", st.seconds_sign},
          {"seconds_extract", st.seconds_extract},
          {"attempts", st.attempts},
          {"final_band_voxels", st.band},
          {"shell_mm", st.shell}};
}

/// Volumetric remeshing of the first candidate input that gives a closed surface free of
/// self-intersections; the edge point asked for, then the linear one (the closest-point segment
/// can fold a triangle where a thin wall puts A and B on different sheets).
TriangleSoup volumetric_repair(const std::vector<const TriangleSoup*>& inputs, const RepairOptions& o,
                               nlohmann::json& rep) {
  auto t0 = Clock::now();
  TriangleSoup out, fallback;
  bool have_fallback = false;
  rep["volumetric"] = nlohmann::json::array();
  for (std::size_t k = 0; k < inputs.size(); ++k) {
    const TriangleSoup& soup = *inputs[k];
    VolumetricOptions vo = o.volumetric;
    if (!(vo.voxel > 0) && vo.resolution <= 0) vo.voxel = default_voxel(soup);
    // What is asked first; then Marching Cubes (dual contouring can pinch two sheets of one cell
    // into a non-manifold edge); then the linear edge point.
    std::vector<std::pair<Extract, Interp>> tries = {{vo.extract, vo.interp}};
    if (vo.extract != Extract::mc) tries.push_back({Extract::mc, vo.interp});
    if (vo.interp != Interp::linear) tries.push_back({Extract::mc, Interp::linear});
    bool good = false, shell = false;
    for (const auto& [extract, interp] : tries) {
      vo.extract = extract;
      vo.interp = interp;
      VolumetricStats st;
      TriangleSoup candidate = volumetric_remesh(soup, vo, &st);
      nlohmann::json j = volumetric_json(vo, st);
      j["input"] = k == 0 && inputs.size() > 1 ? "surface-repaired" : "input";
      j["clean"] = clean_json(clean(candidate));  // loose specks of the band
      const CheckResult c = check_mesh(candidate);
      j["cad_ready"] = c.cad_ready;
      j["self_intersections"] = c.self_intersections;
      j["nonmanifold_edges"] = c.nonmanifold_edges;
      j["problems"] = c.problems;
      rep["volumetric"].push_back(j);
      rep["voxel_mm"] = st.voxel;
      if (c.cad_ready) {
        good = true;
        shell = st.shell > 0;
        out = std::move(candidate);
        break;
      }
      if (!have_fallback && k + 1 == inputs.size()) out = std::move(candidate);  // nothing better yet
    }
    // A result that needed the shell fallback is kept, but the next input may do without it.
    if (good && !shell) {
      have_fallback = false;
      break;
    }
    if (good && !have_fallback) {
      fallback = std::move(out);
      have_fallback = true;
    }
  }
  if (have_fallback) out = std::move(fallback);
  rep["seconds"]["volumetric"] = seconds_since(t0);
  t0 = Clock::now();
  const double voxel = rep["voxel_mm"].get<double>();
  if (o.decimate_tolerance_voxels > 0) {
    // Quadric decimation does not look at the far side of thin walls: a collapse can push a face
    // through it. Where that happens, the vertices of the full-resolution mesh around the
    // crossing are locked and the decimation is redone, up to three times; then the remaining
    // crossings are cut out and patched; failing all that, the mesh stays undecimated.
    nlohmann::json tries = nlohmann::json::array();
    const double tol = o.decimate_tolerance_voxels * voxel;
    std::vector<char> locked(out.vertices.size(), 0);
    for (int round = 0; round < 4; ++round) {
      TriangleSoup dec = out;
      const std::size_t removed = decimate(dec, tol, &locked);
      const auto pairs = self_intersecting_pairs(dec);
      nlohmann::json t = {{"tolerance_mm", tol}, {"faces_removed", removed}, {"faces", dec.faces.size()},
                          {"self_intersections", pairs.size()}, {"locked_vertices", std::count(locked.begin(), locked.end(), 1)}};
      bool ok = pairs.empty();
      if (!ok && round == 3) {
        nlohmann::json fix;
        for (int r = 0; r < 2 && !ok; ++r) {
          cut_out_bad_faces(dec, true);
          clean(dec);
          close_and_fill(dec, o, fix, r + 1);
          ok = check_mesh(dec).cad_ready;
        }
        t["patched"] = ok;
      }
      tries.push_back(t);
      if (ok) {
        out = std::move(dec);
        break;
      }
      // Lock the full-resolution vertices within a few voxels of every crossing.
      std::vector<Eigen::Vector3d> spots;
      for (const auto& [a, b] : pairs)
        for (int f : {a, b}) {
          const auto& tri = dec.faces[f];
          for (int k = 0; k < 3; ++k) spots.push_back(dec.vertices[tri[k]]);
        }
      const double r2 = std::pow((3.0 + 3.0 * round) * voxel, 2);
      for (std::size_t v = 0; v < out.vertices.size(); ++v)
        for (const auto& p : spots)
          if ((out.vertices[v] - p).squaredNorm() < r2) {
            locked[v] = 1;
            break;
          }
    }
    rep["decimate"] = tries;
  }
  rep["seconds"]["decimate"] = seconds_since(t0);
  return out;
}

}  // namespace

const char* to_string(Strategy s) {
  switch (s) {
    case Strategy::surface: return "surface";
    case Strategy::volumetric: return "volumetric";
    default: return "auto";
  }
}

RepairResult repair_mesh(const TriangleSoup& input, const RepairOptions& o) {
  if (input.faces.empty()) throw InvalidInput("the mesh has no faces");
  RepairResult res;
  nlohmann::json& rep = res.report;
  auto t0 = Clock::now();
  Progress progress("repair steps", 4);  // defects, surface, volumetric, final check
  const DefectReport before = find_defects(input);
  progress.advance();
  rep["defects_before"] = to_json(before);
  rep["seconds"]["defects_before"] = seconds_since(t0);
  if (before.check.cad_ready && o.strategy != Strategy::volumetric) {
    res.mesh = input;
    res.path = "unchanged";
    res.cad_ready = true;
    rep["path"] = res.path;
    rep["defects_after"] = rep["defects_before"];
    return res;
  }

  TriangleSoup surface = input;
  bool surface_ok = false;
  CheckResult surface_check;
  if (o.strategy != Strategy::volumetric) {
    nlohmann::json srep;
    surface_check = surface_repair(surface, o, srep);
    surface_ok = surface_check.cad_ready;
    if (!surface_ok)
      spdlog::info("surface repair is not enough ({}); rebuilding the surface volumetrically",
                   surface_check.problems.empty() ? "non-manifold input" : surface_check.problems.front());
    if (!surface_ok && o.close_gaps && srep.contains("gaps") && srep["gaps"]["contractions"].get<std::size_t>() > 0) {
      // Gap closing can zip a narrow hole's rim onto itself and fold it; try again without it.
      RepairOptions no_gaps = o;
      no_gaps.close_gaps = false;
      TriangleSoup retry = input;
      nlohmann::json rrep;
      const CheckResult c = surface_repair(retry, no_gaps, rrep);
      if (c.cad_ready) {
        surface = std::move(retry);
        surface_check = c;
        surface_ok = true;
        rrep["gaps_retry"] = "the first attempt with gap closing was not CAD-ready";
        srep = rrep;
      }
    }
    rep["surface"] = srep;
  }
  if (surface_ok) {
    res.mesh = std::move(surface);
    res.path = "surface";
  } else if (o.strategy == Strategy::surface) {
    res.mesh = std::move(surface);
    res.path = "surface";
    res.problem = "surface repair could not make the mesh CAD-ready (" +
                  (surface_check.problems.empty() ? std::string("unknown") : surface_check.problems.front()) +
                  "); try --strategy auto or volumetric";
    rep["path"] = res.path;
    return res;
  } else {
    // Filled holes help the volumetric step (the band need not bridge them); the winding number
    // does not mind what the surface step left behind.
    const bool use_surface = rep.contains("surface") && !surface.faces.empty();
    nlohmann::json vrep;
    std::vector<const TriangleSoup*> inputs;
    if (use_surface) inputs.push_back(&surface);
    inputs.push_back(&input);
    progress.advance();  // the surface step
    res.mesh = volumetric_repair(inputs, o, vrep);
    rep["volumetric_path"] = vrep;
    res.path = "volumetric";
  }
  progress.advance(res.path == "volumetric" ? 1 : 2);  // the volumetric step, or both steps, are behind
  // Stage files store float coordinates (OpenMesh's PLY writer): judge what will be written.
  for (auto& v : res.mesh.vertices) v = v.cast<float>().cast<double>();
  t0 = Clock::now();
  const DefectReport after = find_defects(res.mesh);
  rep["defects_after"] = to_json(after);
  rep["seconds"]["defects_after"] = seconds_since(t0);
  rep["path"] = res.path;
  res.cad_ready = after.check.cad_ready;
  progress.finish();
  if (!res.cad_ready)
    res.problem = fmt::format("{} repair did not give a CAD-ready mesh: {}", res.path,
                              after.check.problems.empty() ? "unknown" : after.check.problems.front());
  return res;
}

}  // namespace s2c::repair
