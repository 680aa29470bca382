#include "segment.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <deque>
#include <limits>
#include <optional>
#include <queue>
#include <map>

#include <spdlog/spdlog.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>
#include <tbb/task_group.h>

#include "fit_util.h"
#include "s2c/core/disjoint_sets.h"

namespace s2c::features {
namespace {

constexpr double kSeedTurnDeg = 20.0;
/// Latitude span (radians, ≈ 30°) below which a sphere zone is ambiguous with a cone band.
constexpr double kNarrowZoneRad = 0.5;
/// How much larger a cone's RMS distance may be than a sphere's and it still takes a narrow band
/// (see choose_shape; the normals are not compared: smoothing at the creases biases them).
constexpr double kChamferPreference = 1.15;
/// A band wraps at least this far around its axis (radians, 90°).
constexpr double kBandTurnRad = M_PI / 2;
/// Smallest patch on a noisy mesh: fewer faces cannot pin down a primitive against the noise.
constexpr std::size_t kMinNoisyPatchFaces = 30;
/// ... and on a working mesh never fewer than this (SegmentParams::face_scale).
constexpr double kMinCoarsePatchFaces = 6.0;
constexpr double kFreeformCrumbShare = 0.01;
/// Seed neighbourhood of the fit-driven split: up to kSeedRings rings, stopping at kSeedFaces.
constexpr int kSeedRings = 8;
constexpr std::size_t kSeedFaces = 100;
/// A growing region's fits of types other than its own serve as starts for the next refit once
/// they were made on this many faces.
constexpr std::size_t kWarmFaces = 1000;
/// A refused merge is tried again once one of the two regions has grown by this share.
constexpr double kRetryGrowth = 0.02;
/// A merge trial decides whether another type beats the pair's own on this many of the union's
/// samples; only a union that passes is fitted and measured on all of them.
constexpr std::size_t kMergeScreenSamples = 2000;
/// A merge partner this small against the region (faces) is a crumb: see absorbs() in segment().
constexpr double kCrumbShare = 0.01;

void log_regions(const char* stage, const std::vector<Region>& regions) {
  if (!spdlog::should_log(spdlog::level::debug)) return;
  for (std::size_t r = 0; r < regions.size(); ++r) {
    const Fit& f = regions[r].fit;
    spdlog::debug("{} region {}: {} faces, {} rms {:.4g} normal rms {:.3g}°", stage, r, regions[r].faces.size(),
                  shape_name(f.shape.type), f.rms, f.normal_rms_deg);
  }
}

bool sharp_edge(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals, int e, double cos_min) {
  const auto& E = m.edges[e];
  if (E.f1 < 0) return true;
  return normals[E.f0].dot(normals[E.f1]) < cos_min;
}

/// Connected components of `faces` (a mask) across non-sharp edges, each in face order, ordered
/// by their first face. The edges are united on all cores (ConcurrentDisjointSets), which gives
/// the components a sequential walk gives: they depend only on which faces are joined.
std::vector<std::vector<int>> flood_fill(const MeshArrays& m, const std::vector<char>& sharp,
                                         const std::vector<char>& usable) {
  const int nf = m.faces();
  ConcurrentDisjointSets sets(nf);
  tbb::parallel_for(tbb::blocked_range<int>(0, static_cast<int>(m.edges.size()), 16384),
                    [&](const tbb::blocked_range<int>& r) {
                      for (int e = r.begin(); e < r.end(); ++e) {
                        const auto& E = m.edges[e];
                        if (!sharp[e] && E.f1 >= 0 && usable[E.f0] && usable[E.f1]) sets.unite(E.f0, E.f1);
                      }
                    });
  tbb::parallel_for(0, nf, [&](int f) { sets.flatten(f); });
  std::vector<int> index(nf, -1);  // component of each root (roots are face ids)
  std::vector<std::vector<int>> out;
  for (int f = 0; f < nf; ++f) {
    if (!usable[f]) continue;
    int& k = index[sets.find(f)];
    if (k < 0) {
      k = static_cast<int>(out.size());
      out.emplace_back();
    }
    out[k].push_back(f);
  }
  return out;
}

double area_of(const MeshArrays& m, const std::vector<int>& faces) {
  double a = 0;
  for (int f : faces) a += m.farea[f];
  return a;
}

/// Cost of giving face f to a region: distance of the face to the region's shape in tolerances,
/// plus the normal disagreement. Freeform regions only have the normal of the neighbour face.
double growth_cost(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals, int f, const Region& r,
                   int via, double tolerance) {
  const Eigen::Vector3d& n = normals[f];
  if (r.fit.shape.type == ShapeType::freeform) return 2.0 * (1.0 - n.dot(normals[via])) + 1.0;
  const ShapeMetric metric(r.fit.shape);
  double d = 0;
  for (int v : m.tri[f]) d = std::max(d, metric.distance(m.pos[v]));
  const Eigen::Vector3d sn = metric.normal(m.centroid(f));
  const double agree = std::abs(sn.dot(n));
  return d / tolerance + 4.0 * (1.0 - agree);
}

/// Samples of a face set before their normals are normalised, with the vertex of each: the
/// merges continue the samples of A ∪ B from A's instead of gathering all of them again.
struct RawSamples {
  std::vector<int> vertex;
  Samples s;  ///< normals: area-weighted sums, not yet unit
};

/// Adds the contributions of faces[from..] to `raw`, vertices new to it at the end: over the
/// faces of A and then those of B this gives bit for bit what one pass over A's and B's faces
/// gives (the merges; a growing region adds only its new faces).
void accumulate(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals, const std::vector<int>& faces,
                RawSamples& raw, std::size_t from = 0) {
  // Slot of each vertex in the samples, in a per-thread table as long as the mesh (a hash map
  // cost a fifth of the analysis on million-face regions); only the entries set here are reset.
  thread_local std::vector<int> slot;
  if (slot.size() < static_cast<std::size_t>(m.vertices())) slot.assign(m.vertices(), -1);
  for (std::size_t k = 0; k < raw.vertex.size(); ++k) slot[raw.vertex[k]] = static_cast<int>(k);
  Samples& s = raw.s;
  for (std::size_t i = from; i < faces.size(); ++i) {
    const int f = faces[i];
    for (int v : m.tri[f]) {
      int& k = slot[v];
      if (k < 0) {
        k = static_cast<int>(s.points.size());
        raw.vertex.push_back(v);
        s.points.push_back(m.pos[v]);
        s.normals.push_back(Eigen::Vector3d::Zero());
        s.weights.push_back(0.0);
      }
      s.normals[k] += m.farea[f] * normals[f];
      s.weights[k] += m.farea[f] / 3.0;
    }
  }
  for (int v : raw.vertex) slot[v] = -1;
}

/// A stratified subsample of at most `max` samples: enough to tell which type fits a merged pair
/// best, at a fraction of the cost of every type's metrics over all of a large union.
Samples thinned(const Samples& s, std::size_t max) {
  if (s.points.size() <= max) return s;
  Samples out;
  for (std::size_t i : fit::stratified_pick(s.points.size(), max)) {
    out.points.push_back(s.points[i]);
    out.normals.push_back(s.normals[i]);
    out.weights.push_back(s.weights[i]);
  }
  return out;
}

/// The samples: normals made unit.
Samples finished(RawSamples raw) {
  Samples s = std::move(raw.s);
  for (auto& n : s.normals) {
    const double len = n.norm();
    if (len > 0) n /= len;
  }
  return s;
}

}  // namespace

Samples region_samples(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals, const std::vector<int>& faces) {
  RawSamples raw;
  accumulate(m, normals, faces, raw);
  return finished(std::move(raw));
}

namespace {

/// Do the samples form a narrow band around the cone's axis: less than kNarrowZoneRad of
/// latitude on a sphere of radius r (their extent along the axis, over r), and around the axis
/// at least a quarter turn, as an annulus (a small patch anywhere on a sphere is narrow, but it is
/// no band)?
bool narrow_zone(const Samples& s, const Shape& cone, double r) {
  if (!(r > 0) || s.points.empty()) return false;
  const auto uv = fit::perpendicular_frame(cone.dir);
  double lo = std::numeric_limits<double>::infinity(), hi = -lo, r_min = lo, r_max = 0;
  std::vector<double> azimuth;
  azimuth.reserve(s.points.size());
  for (const auto& q : s.points) {
    const Eigen::Vector3d d = q - cone.point;
    const double h = cone.dir.dot(d);
    lo = std::min(lo, h);
    hi = std::max(hi, h);
    const double x = uv.col(0).dot(d), y = uv.col(1).dot(d), radial = std::hypot(x, y);
    r_min = std::min(r_min, radial);
    r_max = std::max(r_max, radial);
    azimuth.push_back(std::atan2(y, x));
  }
  // A band is an annulus around the axis, not a cap: the pole of a sphere wraps its own axis.
  if (!(hi - lo < kNarrowZoneRad * r) || !(r_min > 0.5 * r_max)) return false;
  std::sort(azimuth.begin(), azimuth.end());
  double gap = azimuth.front() + 2 * M_PI - azimuth.back();
  for (std::size_t i = 1; i < azimuth.size(); ++i) gap = std::max(gap, azimuth[i] - azimuth[i - 1]);
  return 2 * M_PI - gap >= kBandTurnRad;
}

bool acceptable(const Fit& f, const SegmentParams& p) {
  return f.ok && f.rms <= p.tolerance && f.normal_rms_deg <= p.normal_tol_deg;
}

/// A curved fit that may be chosen: acceptable, radius below 20 diagonals (else it is a plane),
/// a cone neither nearly a cylinder nor nearly a plane.
bool usable(const Fit& c, const SegmentParams& p) {
  if (!acceptable(c, p)) return false;
  if (c.shape.type != ShapeType::cone && !(c.shape.radius < 20.0 * p.diagonal)) return false;
  return c.shape.type != ShapeType::cone || (c.shape.half_angle_deg >= 2.0 && c.shape.half_angle_deg <= 88.0);
}

/// Can choose_shape(s, p) come out as `type`, given that type's own fit? Only if it is acceptable
/// (plane) or usable (curved).
bool eligible(ShapeType type, const Fit& fit, const SegmentParams& p) {
  return type == ShapeType::plane ? acceptable(fit, p) : usable(fit, p);
}

/// eligible() for the fit of `type` to `s`; one fit instead of four tells most failed merges apart.
/// `fit` receives it.
bool may_choose(ShapeType type, const Samples& s, const SegmentParams& p, Fit& fit) {
  fit = fit::SurfaceFits(s).fit(type);
  return eligible(type, fit, p);
}

/// may_choose for the type of `start`, refined from it first (a merge's union from the first
/// region's shape: one refinement instead of the robust starts' several), from the robust
/// starts when that refinement is not good enough.
bool may_refit(const Shape& start, const Samples& s, const SegmentParams& p, Fit& fit) {
  const fit::SurfaceFits fits(s);
  if (start.type != ShapeType::plane) {  // a plane's fit is direct: nothing to start from
    fit = fits.refit(start);
    if (usable(fit, p)) return true;
  }
  fit = fits.fit(start.type);
  return eligible(start.type, fit, p);
}

/// Fits of one sample set by type: plane, sphere, cylinder, cone (ok false: none).
using TypeFits = std::array<Fit, 4>;
int type_slot(ShapeType t) {
  switch (t) {
    case ShapeType::plane: return 0;
    case ShapeType::sphere: return 1;
    case ShapeType::cylinder: return 2;
    case ShapeType::cone: return 3;
    default: return -1;
  }
}

/// choose_shape, reusing `known` (a fit of the same samples, or null) for its type. With `warm`
/// (fits of nearly the same samples: a growing region before its last growth), each curved type
/// with an acceptable fit there is refined from it, and fitted from the robust starts only when
/// that refinement is no longer acceptable. `made`, when given, receives the fits of every type.
Fit choose_shape_with(const Samples& s, const SegmentParams& p, const Fit* known, const TypeFits* warm = nullptr,
                      TypeFits* made = nullptr) {
  // Distances alone cannot tell shapes apart on CAD tessellations whose vertices lie on two rims
  // (a sphere, a cone and often a cylinder pass exactly through two circles), nor a plane from a
  // strip of a noisy cylinder: the normals can. Score distance and normal residuals against their
  // tolerances; a more complex shape must halve the score of a simpler one to win.
  auto score = [&](const Fit& f) {
    const double d = f.rms / p.tolerance, n = f.normal_rms_deg / p.normal_tol_deg;
    return d * d + n * n;
  };
  const fit::SurfaceFits fits(s);
  auto fit = [&](ShapeType type) {
    if (known && known->shape.type == type) return *known;
    const Fit* before = warm && type != ShapeType::plane ? &(*warm)[type_slot(type)] : nullptr;
    if (before && before->shape.type == type && acceptable(*before, p)) {
      Fit f = fits.refit(before->shape);
      if (acceptable(f, p)) return f;
    }
    return fits.fit(type);
  };
  const Fit plane = fit(ShapeType::plane);
  Fit freeform;
  freeform.shape.type = ShapeType::freeform;
  freeform.rms = plane.ok ? plane.rms : 0.0;
  const Fit* chosen = acceptable(plane, p) ? &plane : nullptr;
  if (chosen && score(plane) < 1e-6) {  // exactly flat: nothing can do better
    if (made) *made = {plane, Fit{}, Fit{}, Fit{}};
    return plane;
  }
  // The three fits are independent and each costs milliseconds (the cone most): run them at once.
  Fit candidates[3];
  tbb::parallel_invoke([&] { candidates[0] = fit(ShapeType::sphere); },
                       [&] { candidates[1] = fit(ShapeType::cylinder); }, [&] { candidates[2] = fit(ShapeType::cone); });
  if (made) *made = {plane, candidates[0], candidates[1], candidates[2]};
  for (const Fit& c : candidates) {
    if (!usable(c, p)) continue;
    // Against a plane a curved shape must halve the score; among the curved ones (a narrow noisy
    // cone band is nearly a sphere zone) a clear 20 % decides.
    const double margin = chosen == &plane ? 0.5 : 0.8;
    if (!chosen || score(c) < margin * score(*chosen)) chosen = &c;
  }
  // On a noisy mesh a narrow chamfer band fits a sphere zone better than its own cone: the
  // filtered normals blend into both neighbours at the band's creases and so turn across the
  // band as a sphere's do. A CAD part's narrow band between two creases is a chamfer far more
  // often than a sphere zone, so the cone takes it unless it is clearly farther from the
  // samples. (Not on clean tessellations: there each ring of a faceted sphere is exactly a cone
  // band.)
  const Fit& cone = candidates[2];
  if (p.noisy && chosen == &candidates[0] && usable(cone, p) && cone.rms <= kChamferPreference * chosen->rms &&
      narrow_zone(s, cone.shape, chosen->shape.radius))
    chosen = &cone;
  return chosen ? *chosen : freeform;
}

}  // namespace

Fit choose_shape(const Samples& s, const SegmentParams& p) { return choose_shape_with(s, p, nullptr); }

namespace {

/// refit_regions: samples farther than this many tolerances from a shape are a rounded crease's,
/// not the shape's ...
constexpr double kTrimTolerances = 3.0;
/// ... and the shape holds when they are at most this share of the region's sample weight.
constexpr double kTrimmedShare = 0.1;
/// Samples per region for the refit (a stratified subsample of larger regions).
constexpr std::size_t kRefitSamples = 4000;

/// The samples of `s` within kTrimTolerances of `shape`, or none when more than kTrimmedShare of
/// the weight lies beyond.
std::optional<Samples> near_samples(const Samples& s, const Shape& shape, double tolerance) {
  Samples kept;
  double total = 0, near = 0;
  for (std::size_t i = 0; i < s.points.size(); ++i) {
    total += s.weights[i];
    if (!(distance(shape, s.points[i]) <= kTrimTolerances * tolerance)) continue;
    near += s.weights[i];
    kept.points.push_back(s.points[i]);
    kept.normals.push_back(s.normals[i]);
    kept.weights.push_back(s.weights[i]);
  }
  if (kept.points.empty() || near < (1.0 - kTrimmedShare) * total) return std::nullopt;
  return kept;
}

}  // namespace

void refit_regions(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals, const SegmentParams& p,
                   Segmentation& seg) {
  tbb::parallel_for(0, static_cast<int>(seg.regions.size()), [&](int r) {
    Region& region = seg.regions[r];
    if (region.faces.size() < kMinNoisyPatchFaces) return;
    const Samples all = thinned(region_samples(m, normals, region.faces), kRefitSamples);
    if (region.fit.shape.type != ShapeType::freeform) {
      // The working mesh's shape, refined on the fine samples near it.
      const auto near = near_samples(all, region.fit.shape, p.tolerance);
      Fit fit;
      if (near && may_refit(region.fit.shape, *near, p, fit)) region.fit = fit;
      return;
    }
    // A freeform region of the working mesh: each type's fit to all its samples, then the shape
    // chosen among the samples near it (the simplest type first, as choose_shape).
    const fit::SurfaceFits fits(all);
    for (ShapeType type : {ShapeType::plane, ShapeType::sphere, ShapeType::cylinder, ShapeType::cone}) {
      const Fit rough = fits.fit(type);
      if (!rough.ok) continue;
      const auto near = near_samples(all, rough.shape, p.tolerance);
      if (!near) continue;
      const Fit fit = choose_shape(*near, p);
      if (fit.shape.type != ShapeType::freeform) {
        region.fit = fit;
        return;
      }
    }
  });
}

namespace {

/// Per-face state of the splits, over the whole mesh, shared by the regions split side by side:
/// each split reads and writes only the entries of its own region's faces (hash maps of a
/// region's faces cost more than the fits on million-face regions; arrays of its own per region
/// took 10 MB each of fresh memory on the worker threads).
struct SplitState {
  explicit SplitState(int faces) : state(faces, 0), stamp(faces, 0) {}
  std::vector<unsigned char> state;
  std::vector<int> stamp;  ///< faces visited by a region's current search: stamp == its epoch
};

/// Splits a region no single primitive fits (a cylinder running tangentially into a hemisphere,
/// noisy creases the flood fill leaked through) by fit-driven region growing: from a seed face,
/// fit the simplest shape to its neighbourhood, grow over faces within tolerance of that shape,
/// refit as it grows, carve it out, repeat on the rest. `faces` are the faces f with
/// face_region[f] == region.
std::vector<Region> split_region(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals,
                                 const std::vector<VertexTensor>& tensors, const std::vector<int>& face_region,
                                 int region, const std::vector<int>& faces, const SegmentParams& p,
                                 SplitState& shared) {
  enum : unsigned char { kRemaining = 1, kTried = 2 };
  std::vector<unsigned char>& state = shared.state;
  std::vector<int>& stamp = shared.stamp;
  for (int f : faces) state[f] = kRemaining;
  // Another region's faces are never read: another split may be writing them.
  auto remaining = [&](int f) { return face_region[f] == region && (state[f] & kRemaining) != 0; };
  int epoch = 0;
  const double cos_tol = std::cos(p.normal_tol_deg * M_PI / 180.0);
  auto fits = [&](const ShapeMetric& shape, int f) {
    for (int v : m.tri[f])
      if (shape.distance(m.pos[v]) > 1.5 * p.tolerance) return false;
    return std::abs(shape.normal(m.centroid(f)).dot(normals[f])) >= cos_tol;
  };
  auto neighbours = [&](int f, auto&& visit) {
    for (int e : m.face_edges[f]) {
      if (e < 0) continue;
      const int g = m.across(e, f);
      if (g >= 0) visit(g);
    }
  };
  // Seeds: interior faces (all vertices face-type) first, larger first.
  std::vector<std::pair<double, int>> keyed;  // (−area, face), interior faces first
  std::vector<std::pair<double, int>> rim;
  for (int f : faces) {
    bool interior = true;
    for (int v : m.tri[f]) interior &= tensors[v].cls == VertexClass::face;
    (interior ? keyed : rim).emplace_back(-m.farea[f], f);
  }
  auto by_area = [](const auto& a, const auto& b) { return a.first < b.first; };
  std::stable_sort(keyed.begin(), keyed.end(), by_area);
  std::stable_sort(rim.begin(), rim.end(), by_area);
  keyed.insert(keyed.end(), rim.begin(), rim.end());
  std::vector<Region> out;
  std::vector<int> leftovers;
  // A carved-out region's last fit reads only its own samples, and the search goes on without
  // it: it runs as a task beside the next seeds (a scan's single flood-fill region is split on
  // one thread, whose fits otherwise left the other core idle a third of the time). The deque
  // keeps each job where it is while more are added.
  struct FinalFit {
    RawSamples samples;
    TypeFits warm;
    Fit fit;
  };
  std::deque<FinalFit> final_fits;
  tbb::task_group fitting;
  // Faces near a seed no shape fitted are not tried as seeds again (on a freeform surface every
  // face would cost two fits otherwise), but other regions may still grow over them.
  for (const auto& keyed_seed : keyed) {
    const int seed = keyed_seed.second;  // a plain variable: lambdas below capture it
    if (state[seed] != kRemaining) continue;
    // The seed's neighbourhood: rings of faces inside the region until it holds kSeedFaces faces,
    // so that a finely refined faceted cylinder is seen as a cylinder, not as one flat facet; if
    // no shape fits that (the neighbourhood crossed a tangent edge), two rings.
    auto neighbourhood = [&](int rings, std::size_t enough) {
      std::vector<int> faces_near = {seed};
      stamp[seed] = ++epoch;
      for (int ring = 0; ring < rings && faces_near.size() < enough; ++ring) {
        const std::size_t n = faces_near.size();
        for (std::size_t i = 0; i < n; ++i)
          neighbours(faces_near[i], [&](int g) {
            if (remaining(g) && stamp[g] != epoch) stamp[g] = epoch, faces_near.push_back(g);
          });
      }
      return faces_near;
    };
    std::vector<int> current = neighbourhood(kSeedRings, kSeedFaces);
    TypeFits type_fits;  // every type's fit at the last refit
    Fit fit = choose_shape_with(region_samples(m, normals, current), p, nullptr, nullptr, &type_fits);
    if (fit.shape.type == ShapeType::freeform && current.size() > 20)
      fit = choose_shape_with(region_samples(m, normals, neighbourhood(2, std::numeric_limits<std::size_t>::max())), p,
                              nullptr, nullptr, &type_fits);
    if (fit.shape.type == ShapeType::freeform) {
      for (int f : current) state[f] |= kTried;
      continue;
    }
    // Grow over faces the shape explains; refit whenever the region has grown by half.
    current = {seed};
    stamp[seed] = ++epoch;
    std::size_t fitted_size = 1;
    // The region's shape moves little as it grows, so each refit refines the last one's fits
    // instead of starting afresh (the robust starts cost several refinements each): its own
    // type's always, the other types' once they were fitted to kWarmFaces faces (on fewer, a
    // fit of a type the region is not, e.g. a cone to a patch of a sphere, is no start to go on from).
    auto warm_starts = [&] {
      if (fitted_size >= kWarmFaces) return type_fits;
      TypeFits own;
      const int k = type_slot(fit.shape.type);
      if (k >= 0) own[k] = type_fits[k];
      return own;
    };
    RawSamples grown;  // samples of current[0 .. gathered), extended at each fit
    std::size_t gathered = 0;
    auto gather = [&] {  // the faces of `current` not yet in `grown`
      accumulate(m, normals, current, grown, gathered);
      gathered = current.size();
    };
    auto current_samples = [&] {
      gather();
      return finished(grown);
    };
    ShapeMetric metric(fit.shape);
    for (std::size_t i = 0; i < current.size(); ++i) {
      neighbours(current[i], [&](int g) {
        if (remaining(g) && stamp[g] != epoch && fits(metric, g)) stamp[g] = epoch, current.push_back(g);
      });
      if (current.size() > fitted_size * 3 / 2 + 8) {
        const TypeFits warm = warm_starts();
        const Fit refit = choose_shape_with(current_samples(), p, nullptr, &warm, &type_fits);
        if (refit.shape.type == ShapeType::freeform) break;
        fit = refit;
        metric = ShapeMetric(fit.shape);
        fitted_size = current.size();
      }
    }
    for (int f : current) state[f] &= ~kRemaining;
    if (current.size() < 3) {
      leftovers.insert(leftovers.end(), current.begin(), current.end());
      continue;
    }
    gather();
    FinalFit& job = final_fits.emplace_back(FinalFit{std::move(grown), warm_starts(), Fit{}});
    fitting.run([&job, &p] { job.fit = choose_shape_with(finished(std::move(job.samples)), p, nullptr, &job.warm); });
    Region r;
    r.faces = std::move(current);
    out.push_back(std::move(r));
  }
  fitting.wait();
  for (std::size_t k = 0; k < final_fits.size(); ++k) out[k].fit = final_fits[k].fit;
  for (int f : faces)
    if (remaining(f)) leftovers.push_back(f);
  if (!leftovers.empty()) {
    Region r;
    r.faces = std::move(leftovers);
    r.fit.shape.type = ShapeType::freeform;
    out.push_back(std::move(r));
  }
  return out;
}

/// Grows the regions over the unassigned faces, cheapest face first (Dijkstra-like): each face
/// goes to the neighbouring region whose shape explains it best, so patch borders settle on the
/// crease. Faces no region reaches (islands) become one region per connected piece.
void grow_regions(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals, const SegmentParams& p,
                  Segmentation& seg) {
  const int nf = m.faces();
  using Item = std::tuple<double, int, int, int>;  // cost, face, region, via face
  std::priority_queue<Item, std::vector<Item>, std::greater<Item>> queue;
  auto push_neighbours = [&](int f) {
    const int r = seg.face_region[f];
    for (int e : m.face_edges[f]) {
      if (e < 0) continue;
      const int g = m.across(e, f);
      if (g >= 0 && seg.face_region[g] < 0)
        queue.emplace(growth_cost(m, normals, g, seg.regions[r], f, p.tolerance), g, r, f);
    }
  };
  for (int f = 0; f < nf; ++f)
    if (seg.face_region[f] >= 0) push_neighbours(f);
  while (!queue.empty()) {
    auto [cost, f, r, via] = queue.top();
    queue.pop();
    if (seg.face_region[f] >= 0) continue;
    seg.face_region[f] = r;
    seg.regions[r].faces.push_back(f);
    ++seg.grown_faces;
    push_neighbours(f);
  }
  std::vector<char> left(nf, 0);
  bool any = false;
  for (int f = 0; f < nf; ++f) any |= (left[f] = seg.face_region[f] < 0);
  if (!any) return;
  const std::vector<char> none(m.edges.size(), 0);
  for (auto& faces : flood_fill(m, none, left)) {
    Region r;
    r.faces = std::move(faces);
    for (int f : r.faces) seg.face_region[f] = static_cast<int>(seg.regions.size());
    seg.regions.push_back(std::move(r));
  }
}

/// Points every face at the region holding it.
void index_faces(Segmentation& seg) {
  for (int r = 0; r < static_cast<int>(seg.regions.size()); ++r)
    for (int f : seg.regions[r].faces) seg.face_region[f] = r;
}

/// Drops the regions for which `drop` is true and renumbers the rest; faces of dropped regions
/// become unassigned (-1).
template <class Drop>
void drop_regions(Segmentation& seg, Drop drop) {
  std::vector<int> remap(seg.regions.size(), -1);
  std::vector<Region> kept;
  for (std::size_t r = 0; r < seg.regions.size(); ++r)
    if (!drop(seg.regions[r])) {
      remap[r] = static_cast<int>(kept.size());
      kept.push_back(std::move(seg.regions[r]));
    }
  seg.regions = std::move(kept);
  for (int& r : seg.face_region)
    if (r >= 0) r = remap[r];
}

/// Region pairs ordered (smaller number first), sorted, each once.
void sort_pairs(std::vector<std::pair<int, int>>& pairs) {
  for (auto& [a, b] : pairs)
    if (a > b) std::swap(a, b);
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
}

}  // namespace

Segmentation segment(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals,
                     const std::vector<VertexTensor>& tensors, const SegmentParams& p) {
  const int nf = m.faces(), ne = static_cast<int>(m.edges.size());
  // On a noisy mesh the filtered normals still turn by a few degrees between neighbours, and a
  // small hole's wall turns by edge/radius: the seeds are cut where they turn by more than
  // kSeedTurnDeg, a stricter barrier than the crease angle, so no seed leaks across a worn crease.
  const double barrier_deg = p.noisy ? std::min(p.min_crease_deg, kSeedTurnDeg) : p.min_crease_deg;
  const double cos_min = std::cos(barrier_deg * M_PI / 180.0);
  std::vector<char> sharp(ne);
  tbb::parallel_for(0, ne, [&](int e) { sharp[e] = sharp_edge(m, normals, e, cos_min); });

  Segmentation seg;
  const std::vector<char> usable(nf, 1);
  auto components = flood_fill(m, sharp, usable);
  const std::size_t min_seed = p.noisy ? 6 : 1;
  for (auto& faces : components) {
    if (faces.size() < min_seed) continue;
    Region r;
    r.faces = std::move(faces);
    seg.regions.push_back(std::move(r));
  }
  seg.seeds = seg.regions.size();
  seg.face_region.assign(nf, -1);
  index_faces(seg);
  auto fit_region = [&](Region& r) {
    r.fit = choose_shape(region_samples(m, normals, r.faces), p);
    r.area = area_of(m, r.faces);
    r.fitted_faces = r.faces.size();
  };
  tbb::parallel_for(0, static_cast<int>(seg.regions.size()), [&](int r) { fit_region(seg.regions[r]); });
  log_regions("seed", seg.regions);

  // A region whose fit was chosen afresh for its faces keeps it until it gains faces (regions
  // only grow, so an equal count means the same faces).
  auto refit_grown = [&] {
    tbb::parallel_for(0, static_cast<int>(seg.regions.size()), [&](int r) {
      if (seg.regions[r].fitted_faces != seg.regions[r].faces.size()) fit_region(seg.regions[r]);
    });
  };
  if (p.noisy) {
    grow_regions(m, normals, p, seg);
    refit_grown();
    log_regions("grown", seg.regions);
  }

  // Regions no primitive fits are split by fit-driven region growing.
  {
    auto needs_split = [](const Region& r) { return r.fit.shape.type == ShapeType::freeform && r.faces.size() >= 6; };
    const int nr = static_cast<int>(seg.regions.size());
    std::vector<std::vector<Region>> parts(nr);  // regions are split independently, in parallel
    SplitState shared(nf);
    tbb::parallel_for(0, nr, [&](int r) {
      if (needs_split(seg.regions[r]))
        parts[r] = split_region(m, normals, tensors, seg.face_region, r, seg.regions[r].faces, p, shared);
    });
    std::vector<Region> all;
    for (int r = 0; r < nr; ++r) {
      if (!needs_split(seg.regions[r])) {
        all.push_back(std::move(seg.regions[r]));
        continue;
      }
      for (auto& part : parts[r]) {
        part.area = area_of(m, part.faces);
        all.push_back(std::move(part));
        ++seg.splits;
      }
      --seg.splits;
    }
    seg.regions = std::move(all);
    index_faces(seg);
  }

  if (p.noisy) {
    // Crumbs along worn creases (a few faces the growth or the split left over) are no patches:
    // their faces go to the neighbours that explain them best.
    // Small freeform leftovers of the split (a noisy band along a crease) go the same way.
    const double least = p.face_scale > 1.0 ? std::max(kMinCoarsePatchFaces, kMinNoisyPatchFaces / p.face_scale)
                                             : static_cast<double>(kMinNoisyPatchFaces);
    auto crumb = [&](const Region& r) {
      return static_cast<double>(r.faces.size()) < least ||
             (r.fit.shape.type == ShapeType::freeform && r.faces.size() < kFreeformCrumbShare * nf);
    };
    const std::size_t before = seg.regions.size();
    drop_regions(seg, crumb);
    if (seg.regions.size() < before) {
      grow_regions(m, normals, p, seg);
      refit_grown();  // (a split's parts, fitted from warm starts, are fitted afresh)
    }
    seg.absorbed = before - seg.regions.size();
  }

  // Merge neighbours that are one primitive (a plane cut by a spurious crease, a cylinder split
  // in two): same type, and the union still fits within tolerance.
  // A pair that failed to merge is not tried again until one of its regions has grown by more
  // than kRetryGrowth (regions only grow here, and keep their first face, the key): crumbs
  // absorbed one per pass by a large region do not make a union fit that did not, and each retry
  // fits a cylinder to the two regions' samples anew.
  std::map<std::pair<int, int>, std::pair<std::size_t, std::size_t>> refused;  // sizes when refused
  auto was_refused = [&](const Region& A, const Region& B) {
    const auto it = refused.find({A.faces.front(), B.faces.front()});
    auto grown = [](std::size_t now, std::size_t then) { return now > then + kRetryGrowth * then; };
    return it != refused.end() && !grown(A.faces.size(), it->second.first) && !grown(B.faces.size(), it->second.second);
  };
  // Raw samples of the regions that were the first of a pair, kept while they are unchanged.
  std::vector<std::optional<RawSamples>> raw(seg.regions.size());
  // One pass tries the neighbouring pairs in order; a region merged in the pass is not tried
  // again in it. The trials run in rounds: a round evaluates, in parallel, every pending trial
  // whose two regions no earlier pending trial holds, then applies the results in order. Each
  // trial thus sees its regions as the sequential walk would, and the result is the same.
  struct Trial {
    int a, b;
    bool mixed;
    bool ok = false;
    Fit fit;
    std::optional<RawSamples> united;  ///< the union's samples; none when B is a crumb A absorbs
  };
  // A crumb (a few faces beside a large region, kCrumbShare of its size at most) joins the region
  // with the region's shape as it is when the union is within tolerance of that shape: refitting
  // would move the shape by a crumb's worth (and only closer to the union), and a region of a
  // hundred thousand faces took tens of crumbs, one per pass, each with a fit of all its samples.
  // The union's metrics combine the region's and the crumb's by area (the rim vertices they
  // share counted on both sides).
  auto absorbs = [&](const Region& A, const Region& B, Fit& united) {
    if (!(static_cast<double>(B.faces.size()) <= kCrumbShare * static_cast<double>(A.faces.size()))) return false;
    Fit crumb = A.fit;
    fit::finish(crumb, region_samples(m, normals, B.faces));
    const double wa = A.area, wb = B.area;
    if (!crumb.ok || !(wa + wb > 0)) return false;
    auto mean_square = [&](double a, double b) { return std::sqrt((wa * a * a + wb * b * b) / (wa + wb)); };
    united = A.fit;
    united.rms = mean_square(A.fit.rms, crumb.rms);
    united.normal_rms_deg = mean_square(A.fit.normal_rms_deg, crumb.normal_rms_deg);
    united.max_error = std::max(A.fit.max_error, crumb.max_error);
    return acceptable(united, p);
  };
  auto curved = [](ShapeType t) { return t == ShapeType::sphere || t == ShapeType::cylinder || t == ShapeType::cone; };
  // The neighbouring pairs, from the edges once: regions only unite, so after a pass the pairs
  // are those of before with each merged region renamed to the one it joined (a scan of the
  // million edges per pass cost more than the pass's bookkeeping).
  std::vector<std::pair<int, int>> pairs;
  for (const auto& E : m.edges) {
    if (E.f1 < 0) continue;
    const int a = seg.face_region[E.f0], b = seg.face_region[E.f1];
    if (a != b && a >= 0 && b >= 0) pairs.emplace_back(a, b);
  }
  sort_pairs(pairs);
  bool merged = true;
  while (merged) {
    merged = false;
    std::vector<int> joined(seg.regions.size(), -1);  // region merged into another in this pass
    std::vector<Trial> trials;
    for (auto [a, b] : pairs) {
      const Region& A = seg.regions[a];
      const Region& B = seg.regions[b];
      const ShapeType ta = A.fit.shape.type, tb = B.fit.shape.type;
      // On a noisy mesh one narrow band (a chamfer) may come out as a cone and sphere zones side
      // by side: curved neighbours of different types merge when one of their types fits both.
      const bool mixed = p.noisy && ta != tb && curved(ta) && curved(tb);
      if ((ta != tb && !mixed) || ta == ShapeType::freeform) continue;
      // Across a real crease two planes never fit one plane; this guards near-tangent cases.
      if (ta == ShapeType::plane && std::abs(A.fit.shape.dir.dot(B.fit.shape.dir)) < std::cos(2.0 * M_PI / 180))
        continue;
      if (was_refused(A, B)) continue;
      trials.push_back({a, b, mixed, false, {}, std::nullopt});
    }
    auto evaluate = [&](Trial& t) {
      const ShapeType ta = seg.regions[t.a].fit.shape.type, tb = seg.regions[t.b].fit.shape.type;
      if (!t.mixed && absorbs(seg.regions[t.a], seg.regions[t.b], t.fit)) {
        t.ok = true;
        return;
      }
      RawSamples united = *raw[t.a];
      accumulate(m, normals, seg.regions[t.b].faces, united);
      const Samples samples = finished(united);
      Fit own;
      bool may;
      if (t.mixed) {
        may = may_choose(ta, samples, p, own) || may_choose(tb, samples, p, own);
        if (may) t.fit = choose_shape_with(samples, p, &own);
      } else {
        // Screened on a subsample, the union refined from the first region's shape: a large
        // region absorbing its crumbs one by one fitted every type to all its samples each time.
        const Samples screen = thinned(samples, kMergeScreenSamples);
        const Shape& from = seg.regions[t.a].fit.shape;
        Fit own_screen;
        may = may_refit(from, screen, p, own_screen);
        if (may) t.fit = choose_shape_with(screen, p, &own_screen);
        if (may && t.fit.shape.type == ta) {
          may = may_refit(from, samples, p, own);
          t.fit = own;
        }
      }
      t.ok = may && (t.fit.shape.type == ta || (t.mixed && t.fit.shape.type == tb));
      if (t.ok) t.united = std::move(united);
    };
    std::vector<char> touched(seg.regions.size(), 0), done(trials.size(), 0);
    std::vector<int> busy(seg.regions.size(), -1);  // round that holds the region
    std::size_t next = 0;
    for (int round = 0; next < trials.size(); ++round) {
      std::vector<int> ready;
      for (std::size_t k = next; k < trials.size(); ++k) {
        const Trial& t = trials[k];
        if (done[k]) continue;
        if (touched[t.a] || touched[t.b]) {
          done[k] = 1;
          continue;
        }
        if (busy[t.a] != round && busy[t.b] != round) ready.push_back(static_cast<int>(k));
        busy[t.a] = busy[t.b] = round;
      }
      // The first regions' raw samples, kept while they are unchanged (ready trials hold
      // distinct regions, so each is gathered once).
      std::vector<char> gather(ready.size(), 0);
      for (std::size_t i = 0; i < ready.size(); ++i)
        if (!raw[trials[ready[i]].a]) {
          raw[trials[ready[i]].a].emplace();
          gather[i] = 1;
        }
      tbb::parallel_for(0, static_cast<int>(ready.size()), [&](int i) {
        Trial& t = trials[ready[i]];
        if (gather[i]) accumulate(m, normals, seg.regions[t.a].faces, *raw[t.a]);
        evaluate(t);
      });
      for (int k : ready) {
        Trial& t = trials[k];
        done[k] = 1;
        Region& A = seg.regions[t.a];
        Region& B = seg.regions[t.b];
        if (!t.ok) {
          refused[{A.faces.front(), B.faces.front()}] = {A.faces.size(), B.faces.size()};
          continue;
        }
        if (t.united)
          raw[t.a] = std::move(t.united);
        else if (raw[t.a])
          accumulate(m, normals, B.faces, *raw[t.a]);
        A.faces.insert(A.faces.end(), B.faces.begin(), B.faces.end());
        A.fit = t.fit;
        A.area += B.area;
        for (int g : B.faces) seg.face_region[g] = t.a;
        B.faces.clear();
        joined[t.b] = t.a;
        touched[t.a] = touched[t.b] = 1;
        ++seg.merges;
        merged = true;
      }
      while (next < trials.size() && done[next]) ++next;
    }
    if (merged) {
      // The emptied regions stay, unnamed by any pair, until the last pass: dropping them renumbers
      // the rest in the same order, so the pairs sort as they would renumbered, and a renumbering
      // of the million faces per pass (75 passes on the CGAL anchor) is saved.
      for (std::size_t r = 0; r < joined.size(); ++r)
        if (joined[r] >= 0) raw[r].reset();
      // A region that joined another is not joined in the same pass (both are touched), so
      // one step of `joined` names where it went.
      auto renamed = [&](int r) { return joined[r] >= 0 ? joined[r] : r; };
      std::vector<std::pair<int, int>> next_pairs;
      for (auto [a, b] : pairs) {
        const int a2 = renamed(a), b2 = renamed(b);
        if (a2 != b2) next_pairs.emplace_back(a2, b2);
      }
      sort_pairs(next_pairs);
      pairs = std::move(next_pairs);
    }
  }
  drop_regions(seg, [](const Region& r) { return r.faces.empty(); });
  tbb::parallel_for(std::size_t{0}, seg.regions.size(),
                    [&](std::size_t r) { std::sort(seg.regions[r].faces.begin(), seg.regions[r].faces.end()); });
  return seg;
}

}  // namespace s2c::features
