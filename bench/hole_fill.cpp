// Hole filling benchmark (bench/README.md, "Hole filling"): cuts curved holes into meshes with a
// known surface, fills each with our rbf, liepa and auto, and with CGAL's
// triangulate_refine_and_fair_hole when CGAL is found, in the same run; prints deviation of
// the new vertices from the true surface and time per hole. Then times the RBF solve alone at
// the paper's sizes (Table 1: 134 and 524 constraint points) and at 1000 and 5000.
//
//   s2c-bench-holefill [--holes N] [--real MESH]     (default MESH: the fandisk CAD part)
//                      [--hole-scale F]              (holes F times the default size)
//   S2C_BENCH_VERBOSE=1 prints every hole's size, method choice and deviation on stderr.
//
// Both sides are timed in the same state: the repetitions of a fill run back to back (ours
// checked CAD-ready only after them), so code and mesh data are in cache on both sides; with
// --cold every core's caches are flushed right before each timed call on both sides. One hole per
// call: both sides start from a mesh with its adjacency built untimed (our HoleFiller, CGAL's
// Surface_mesh), and the set-up times are printed after the table; --one-shot times
// fill_holes instead, which builds its adjacency in the call.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <functional>
#include <map>
#include <optional>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "fill/rbf.h"
#include "s2c/core/check.h"
#include "s2c/core/clock.h"
#include "s2c/core/distance.h"
#include "s2c/core/io.h"
#include "s2c/repair/fill.h"

#ifdef S2C_HAVE_CGAL
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Polygon_mesh_processing/triangulate_hole.h>
#include <CGAL/Surface_mesh.h>
#endif

using namespace s2c;
using Clock = std::chrono::steady_clock;

namespace {


// ----- test shapes ---------------------------------------------------------------------------

TriangleSoup icosphere(double radius, int levels) {
  TriangleSoup s;
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Eigen::Vector3d> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                    {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (auto& p : v) p.normalize();
  std::vector<std::array<int, 3>> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                                       {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                                       {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<int, int>, int> mid;
    const auto midpoint = [&](int a, int b) {
      const auto key = std::minmax(a, b);
      const auto it = mid.find(key);
      if (it != mid.end()) return it->second;
      v.push_back((v[a] + v[b]).normalized());
      return mid[key] = static_cast<int>(v.size()) - 1;
    };
    std::vector<std::array<int, 3>> g;
    for (const auto& tri : f) {
      const int a = midpoint(tri[0], tri[1]), b = midpoint(tri[1], tri[2]), c = midpoint(tri[2], tri[0]);
      g.insert(g.end(), {{tri[0], a, c}, {tri[1], b, a}, {tri[2], c, b}, {a, b, c}});
    }
    f.swap(g);
  }
  for (auto& p : v) s.vertices.push_back(radius * p);
  s.faces = f;
  return s;
}

// A closed surface from a (u, v) parametrisation periodic in u; `v_periodic` closes v too
// (torus), otherwise the two rims are capped by fans.
TriangleSoup param_surface(int nu, int nv, bool v_periodic, const std::function<Eigen::Vector3d(double, double)>& at) {
  TriangleSoup s;
  const int rows = v_periodic ? nv : nv + 1;
  for (int j = 0; j < rows; ++j)
    for (int i = 0; i < nu; ++i) s.vertices.push_back(at((i + 0.5 * (j % 2)) / nu, double(j) / nv));
  const auto id = [&](int i, int j) { return (j % rows) * nu + (i % nu); };
  for (int j = 0; j < nv; ++j)
    for (int i = 0; i < nu; ++i) {
      if (j % 2 == 0) {
        s.faces.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
        s.faces.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      } else {
        s.faces.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
        s.faces.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
      }
    }
  if (!v_periodic) {
    const int b = static_cast<int>(s.vertices.size());
    Eigen::Vector3d c0 = Eigen::Vector3d::Zero(), c1 = Eigen::Vector3d::Zero();
    for (int i = 0; i < nu; ++i) {
      c0 += s.vertices[id(i, 0)] / nu;
      c1 += s.vertices[id(i, nv)] / nu;
    }
    s.vertices.push_back(c0);
    s.vertices.push_back(c1);
    for (int i = 0; i < nu; ++i) {
      s.faces.push_back({b, id(i + 1, 0), id(i, 0)});
      s.faces.push_back({b + 1, id(i, nv), id(i + 1, nv)});
    }
  }
  return s;
}

// ----- distances -----------------------------------------------------------------------------

using Distance = std::function<double(const Eigen::Vector3d&)>;

// Distance to the removed faces: the true surface of a real mesh inside its hole.
Distance removed_faces_distance(const TriangleSoup& full, const std::vector<int>& removed) {
  std::vector<std::array<Eigen::Vector3d, 3>> tris;
  for (int f : removed)
    tris.push_back({full.vertices[full.faces[f][0]], full.vertices[full.faces[f][1]], full.vertices[full.faces[f][2]]});
  return [tris](const Eigen::Vector3d& p) {
    double best = 1e300;
    for (const auto& t : tris) best = std::min(best, (closest_point_on_triangle(p, t[0], t[1], t[2]) - p).norm());
    return best;
  };
}

// ----- hole cutting --------------------------------------------------------------------------

struct Cut {
  TriangleSoup soup;         // the mesh with the hole
  repair::Hole hole;         // its loop in fill order
  std::vector<int> removed;  // face indices of the original
};

// Grows a hole from a seed face over face neighbours whose centroid lies in an ellipsoid with
// random axes (curved, irregular rim). Accepts it only when its boundary is one simple loop.
bool cut_hole(const TriangleSoup& s, std::mt19937& rng, double size, std::size_t max_faces, Cut& out) {
  std::uniform_int_distribution<int> pick(0, static_cast<int>(s.faces.size()) - 1);
  std::uniform_real_distribution<double> u(-1, 1);
  const int seed = pick(rng);
  const auto centroid = [&](int f) {
    return Eigen::Vector3d((s.vertices[s.faces[f][0]] + s.vertices[s.faces[f][1]] + s.vertices[s.faces[f][2]]) / 3);
  };
  const Eigen::Vector3d c = centroid(seed);
  const Eigen::Matrix3d rot =
      Eigen::AngleAxisd(M_PI * u(rng), Eigen::Vector3d(u(rng), u(rng), u(rng)).normalized()).toRotationMatrix();
  const Eigen::Vector3d axes = size * Eigen::Vector3d(1.0, 0.5 + 0.25 * (u(rng) + 1), 0.4 + 0.2 * (u(rng) + 1));
  const auto inside = [&](int f) {
    return ((rot.transpose() * (centroid(f) - c)).cwiseQuotient(axes)).squaredNorm() < 1;
  };
  std::map<std::pair<int, int>, int> by_edge;
  for (int f = 0; f < static_cast<int>(s.faces.size()); ++f)
    for (int k = 0; k < 3; ++k) by_edge[{s.faces[f][k], s.faces[f][(k + 1) % 3]}] = f;
  std::vector<char> removed(s.faces.size(), 0);
  std::vector<int> stack{seed}, list;
  removed[seed] = 1;
  while (!stack.empty()) {
    const int f = stack.back();
    stack.pop_back();
    list.push_back(f);
    if (list.size() > max_faces) return false;
    for (int k = 0; k < 3; ++k) {
      const auto it = by_edge.find({s.faces[f][(k + 1) % 3], s.faces[f][k]});
      if (it != by_edge.end() && !removed[it->second] && inside(it->second)) {
        removed[it->second] = 1;
        stack.push_back(it->second);
      }
    }
  }
  if (list.size() < 6) return false;
  out = Cut{};
  out.soup.vertices = s.vertices;
  for (int f = 0; f < static_cast<int>(s.faces.size()); ++f)
    if (!removed[f]) out.soup.faces.push_back(s.faces[f]);
  out.removed = list;
  // Loop: boundary half-edges walked backwards; reject anything but one simple loop.
  std::map<int, int> next;
  std::set<std::pair<int, int>> half;
  for (const auto& f : out.soup.faces)
    for (int k = 0; k < 3; ++k) half.insert({f[k], f[(k + 1) % 3]});
  for (const auto& f : out.soup.faces)
    for (int k = 0; k < 3; ++k) {
      const int a = f[k], b = f[(k + 1) % 3];
      if (!half.count({b, a}) && !next.emplace(b, a).second) return false;  // pinched rim
    }
  if (next.empty()) return false;
  int v = next.begin()->first;
  do {
    out.hole.loop.push_back(v);
    v = next[v];
  } while (v != out.hole.loop.front() && out.hole.loop.size() <= next.size());
  return out.hole.loop.size() == next.size();
}

// ----- fillers -------------------------------------------------------------------------------

struct Outcome {
  bool ok = false;
  double seconds = 0;
  std::vector<Eigen::Vector3d> new_points;
  std::string note;
};

bool g_cold = false;  // --cold: every timed fill, ours and CGAL's, starts with the caches flushed
bool g_one_shot = false;  // --one-shot: one hole per call timed with fill_holes, not a HoleFiller

// Flushes every core's caches before a timed fill (--cold): all threads write over a buffer
// larger than this machine's last-level cache, so neither side's code or mesh data is cached.
void evict_caches() {
  static std::vector<char> junk(std::size_t{128} << 20, 1);
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, junk.size(), std::size_t{1} << 16), [](const auto& r) {
    for (std::size_t k = r.begin(); k < r.end(); k += 64) ++junk[k];
  });
}

// Marks `o` failed unless `s` (the filled soup) is CAD-ready. Run after the timed repetitions, so
// that check_mesh (a pass over the whole mesh on both cores) never runs between two of them:
// it would leave our next fill to start with cold caches and CGAL's, which follows its untimed
// mesh construction, with warm ones.
void verify(Outcome& o, const TriangleSoup& s) {
  if (o.ok && !check_mesh(s, CheckOptions{}).cad_ready) {
    o.ok = false;
    o.note = "not cad_ready";
  }
}

// One timed fill of the cut (the soup copied first, untimed); the filled soup is left in `s`.
Outcome fill_ours(const Cut& cut, repair::FillMethod m, TriangleSoup& s) {
  Outcome o;
  s = cut.soup;
  repair::FillOptions opt;
  opt.method = m;
  const std::size_t before = s.vertices.size();
  std::optional<repair::HoleFiller> filler;
  if (!g_one_shot) filler.emplace(s);  // untimed, as CGAL's Surface_mesh
  if (g_cold) evict_caches();
  const auto t0 = Clock::now();
  const auto r = filler ? filler->fill({cut.hole}, opt) : repair::fill_holes(s, {cut.hole}, opt);
  o.seconds = seconds_since(t0);
  o.ok = r[0].filled;
  o.note = r[0].filled ? to_string(r[0].method) : r[0].reason;
  o.new_points.assign(s.vertices.begin() + static_cast<std::ptrdiff_t>(before), s.vertices.end());
  if (std::getenv("S2C_BENCH_VERBOSE"))
    std::fprintf(stderr, "rim %zu, new %zu, %.2f ms, RBF solve %.2f ms (%zu centres), %s%s\n", cut.hole.loop.size(),
                 o.new_points.size(), 1000 * o.seconds, 1000 * r[0].rbf_solve_seconds, r[0].rbf_constraints,
                 r[0].choice.c_str(), r[0].reason.c_str());
  return o;
}

#ifdef S2C_HAVE_CGAL
// CGAL's mesh of a soup, and its fills of holes in it one call each: time, new points, success
// accumulated in `o` (the Surface_mesh construction is not timed).
struct CgalMesh {
  using K = CGAL::Exact_predicates_inexact_constructions_kernel;
  using SM = CGAL::Surface_mesh<K::Point_3>;
  SM m;
  std::vector<SM::Vertex_index> vs;
  bool built = true;

  explicit CgalMesh(const TriangleSoup& soup) {
    for (const auto& p : soup.vertices) vs.push_back(m.add_vertex(K::Point_3(p.x(), p.y(), p.z())));
    for (const auto& f : soup.faces) built &= m.add_face(vs[f[0]], vs[f[1]], vs[f[2]]) != SM::null_face();
  }
  /// Fills the hole whose loop starts loop[0] → loop[1]; false with o.note on failure. `flush`:
  /// the caches are flushed before the timed call (--cold).
  bool fill(const std::vector<int>& loop, Outcome& o, bool flush) {
    const auto [h, found] = CGAL::halfedge(vs[loop[0]], vs[loop[1]], m);
    if (!found || !m.is_border(h)) {
      o.note = "no border halfedge";
      return false;
    }
    std::vector<SM::Face_index> faces;
    std::vector<SM::Vertex_index> verts;
    if (flush) evict_caches();
    const auto t0 = Clock::now();
    const auto result = CGAL::Polygon_mesh_processing::triangulate_refine_and_fair_hole(
        m, h, std::back_inserter(faces), std::back_inserter(verts));
    o.seconds += seconds_since(t0);
    for (const auto v : verts) o.new_points.push_back({m.point(v).x(), m.point(v).y(), m.point(v).z()});
    if (!std::get<0>(result)) o.note = "fairing failed";
    return std::get<0>(result);
  }
};

Outcome fill_cgal(const Cut& cut) {
  Outcome o;
  CgalMesh mesh(cut.soup);
  if (!mesh.built) {
    o.note = "CGAL could not build the mesh";
    return o;
  }
  o.ok = mesh.fill(cut.hole.loop, o, g_cold);
  if (o.ok) o.note = "cgal";
  return o;
}
#endif

// ----- the comparison ------------------------------------------------------------------------

struct Tally {
  int tried = 0, ok = 0;
  double seconds = 0, dev_sum = 0, dev_max = 0;
  std::size_t points = 0;
  void add(const Outcome& o, const Distance& d) {
    ++tried;
    if (!o.ok) return;
    ++ok;
    seconds += o.seconds;
    double worst = 0;
    for (const auto& p : o.new_points) {
      const double e = std::abs(d(p));
      dev_sum += e;
      worst = std::max(worst, e);
      ++points;
    }
    dev_max = std::max(dev_max, worst);
    if (std::getenv("S2C_BENCH_VERBOSE")) std::fprintf(stderr, "  %s: max dev %.4f\n", o.note.c_str(), worst);
  }
  double mean_dev() const { return points ? dev_sum / double(points) : 0; }
  double ms() const { return ok ? 1000 * seconds / ok : 0; }
};

std::string g_only;
int g_repeats = 3;  // timings: best of this many runs, ours and CGAL's alike (--repeats)

// One table row per filler (rbf, liepa, auto, CGAL), with the ratios to CGAL in the same run.
void print_rows(const char* name, const Tally (&t)[4]) {
  const char* methods[] = {"rbf", "liepa", "auto", "cgal"};
  const double cgal_dev = t[3].mean_dev(), cgal_ms = t[3].ms();
  for (int m = 0; m < 4; ++m) {
    if (t[m].tried == 0) continue;
    std::printf("| %-8s | %-5s | %2d/%-2d | %10.5f | %10.5f | %8.2f |", name, methods[m], t[m].ok, t[m].tried,
                t[m].mean_dev(), t[m].dev_max, t[m].ms());
    if (t[3].ok && m < 3 && t[m].ok)
      std::printf(" %6.2f | %6.2f |\n", cgal_dev > 0 ? t[m].mean_dev() / cgal_dev : 0, t[m].ms() / cgal_ms);
    else
      std::printf("   —    |   —    |\n");
  }
}

// The set-up both sides do before their timed one-hole calls, timed alone in the same cache
// state as the fills, best of g_repeats: ours the HoleFiller (the vertex → faces index of the
// whole mesh, which fill_holes builds in every call, and the face boxes), CGAL's the Surface_mesh.
struct SetUp {
  double ours = 0, cgal = 0;
};
SetUp setup_time(const TriangleSoup& soup) {
  SetUp best{1e300, 1e300};
  for (int rep = 0; rep < g_repeats; ++rep) {
    TriangleSoup copy = soup;
    if (g_cold) evict_caches();
    auto t0 = Clock::now();
    const repair::HoleFiller filler(copy);
    best.ours = std::min(best.ours, seconds_since(t0));
#ifdef S2C_HAVE_CGAL
    if (g_cold) evict_caches();
    t0 = Clock::now();
    const CgalMesh mesh(soup);
    best.cgal = std::min(best.cgal, seconds_since(t0));
#endif
  }
  return best;
}

std::vector<std::string> g_setup_notes;  // per shape: the set-up times, printed after the table

void run_shape(const char* name, const TriangleSoup& shape, double hole_size, const Distance* exact, int holes,
               std::mt19937& rng) {
  if (!g_only.empty() && g_only != name) {
    // Still cut the holes, so that every shape sees the same random holes with or without --only.
    int made = 0, attempts = 0;
    Cut cut;
    while (made < holes && attempts++ < holes * 50) made += cut_hole(shape, rng, hole_size, 2000, cut);
    return;
  }
  Tally t[4];
  int made = 0, attempts = 0;
  SetUp setup;
  while (made < holes && attempts++ < holes * 50) {
    Cut cut;
    if (!cut_hole(shape, rng, hole_size, 2000, cut)) continue;
    ++made;
    const Distance d = exact ? *exact : removed_faces_distance(shape, cut.removed);
    // Best of g_repeats per hole on both sides (the fills are deterministic; this shared 2-core
    // machine's timing spread is not), the repetitions back to back; ours checked CAD-ready after.
    const auto ours = [&](repair::FillMethod m) {
      TriangleSoup filled, scratch;
      Outcome o = fill_ours(cut, m, filled);
      for (int rep = 1; rep < g_repeats; ++rep) o.seconds = std::min(o.seconds, fill_ours(cut, m, scratch).seconds);
      verify(o, filled);
      return o;
    };
    t[0].add(ours(repair::FillMethod::rbf), d);
    const SetUp one = setup_time(cut.soup);
    setup.ours += one.ours;
    setup.cgal += one.cgal;
    t[1].add(ours(repair::FillMethod::liepa), d);
    t[2].add(ours(repair::FillMethod::automatic), d);
#ifdef S2C_HAVE_CGAL
    Outcome o = fill_cgal(cut);
    for (int rep = 1; rep < g_repeats; ++rep) o.seconds = std::min(o.seconds, fill_cgal(cut).seconds);
    t[3].add(o, d);
#endif
  }
  print_rows(name, t);
  char cgal[32] = "—";  // without CGAL its set-up is never timed (and stays at its start value)
#ifdef S2C_HAVE_CGAL
  std::snprintf(cgal, sizeof cgal, "%.3f", made ? 1000 * setup.cgal / made : 0.0);
#endif
  char note[96];
  std::snprintf(note, sizeof note, "%s %.3f / %s ms", name, made ? 1000 * setup.ours / made : 0.0, cgal);
  g_setup_notes.push_back(note);
}

// The same kind of holes, `holes` of them in one mesh (vertex-disjoint), filled by one
// fill_holes call (how `scan2cad repair` fills a mesh's holes: planned in parallel, committed in
// order) and by CGAL one after the other on one Surface_mesh; time per hole = total / holes.
void run_shape_together(const char* name, const TriangleSoup& shape, double hole_size, const Distance* exact,
                        int holes, std::mt19937& rng) {
  std::vector<Cut> cuts;
  std::set<int> used;
  std::vector<char> removed(shape.faces.size(), 0);
  int attempts = 0;
  while (static_cast<int>(cuts.size()) < holes && attempts++ < holes * 200) {
    Cut cut;
    if (!cut_hole(shape, rng, hole_size, 2000, cut)) continue;
    bool apart = true;
    for (int f : cut.removed)
      for (int c : shape.faces[f]) apart &= !used.count(c);
    if (!apart) continue;
    for (int f : cut.removed) {
      removed[f] = 1;
      for (int c : shape.faces[f]) used.insert(c);
    }
    cuts.push_back(std::move(cut));
  }
  TriangleSoup holed;
  holed.vertices = shape.vertices;
  std::vector<int> all_removed;
  for (int f = 0; f < static_cast<int>(shape.faces.size()); ++f) {
    if (removed[f]) all_removed.push_back(f);
    else holed.faces.push_back(shape.faces[f]);
  }
  std::vector<repair::Hole> list;
  for (const Cut& c : cuts) list.push_back(c.hole);
  const Distance d = exact ? *exact : removed_faces_distance(shape, all_removed);
  Tally t[4];
  // Times are the best of g_repeats runs on both sides (this 2-core machine's timings spread by
  // up to 2× from run to run); deviations are the same in every run.
  for (int m = 0; m < 3; ++m) {
    Outcome o;
    o.seconds = 1e300;
    TriangleSoup s;
    for (int rep = 0; rep < g_repeats; ++rep) {
      s = holed;
      repair::FillOptions opt;
      opt.method = m == 0 ? repair::FillMethod::rbf : m == 1 ? repair::FillMethod::liepa : repair::FillMethod::automatic;
      if (g_cold) evict_caches();
      const auto t0 = Clock::now();
      const auto r = repair::fill_holes(s, list, opt);
      o.seconds = std::min(o.seconds, seconds_since(t0));
      o.ok = std::all_of(r.begin(), r.end(), [](const auto& x) { return x.filled; });
      o.new_points.assign(s.vertices.begin() + static_cast<std::ptrdiff_t>(holed.vertices.size()), s.vertices.end());
    }
    verify(o, s);  // after the timed repetitions (see verify)
    t[m].add(o, d);
    t[m].ok = o.ok ? static_cast<int>(cuts.size()) : 0;
    t[m].tried = static_cast<int>(cuts.size());
  }
#ifdef S2C_HAVE_CGAL
  {
    Outcome o;
    o.seconds = 1e300;
    for (int rep = 0; rep < g_repeats; ++rep) {
      CgalMesh mesh(holed);
      Outcome run;
      run.ok = mesh.built;
      // --cold: flushed before the first fill only, as ours before its one call.
      for (std::size_t k = 0; k < cuts.size(); ++k) run.ok &= mesh.fill(cuts[k].hole.loop, run, g_cold && k == 0);
      o.ok = run.ok;
      o.new_points = std::move(run.new_points);
      o.seconds = std::min(o.seconds, run.seconds);
    }
    t[3].add(o, d);
    t[3].ok = o.ok ? static_cast<int>(cuts.size()) : 0;
    t[3].tried = static_cast<int>(cuts.size());
  }
#endif
  print_rows(name, t);
}

void time_rbf_solve(std::size_t n, std::mt19937& rng) {
  // n centres from a curved surface patch (half of them offsets), like a hole's constraints.
  std::vector<Eigen::Vector3d> c;
  std::vector<double> v;
  std::uniform_real_distribution<double> u(-1, 1);
  while (c.size() < n) {
    Eigen::Vector3d p(u(rng), u(rng), 0);
    p.z() = 0.3 * p.x() * p.x() - 0.2 * p.y() * p.y();
    const Eigen::Vector3d nrm = Eigen::Vector3d(-0.6 * p.x(), 0.4 * p.y(), 1).normalized();
    c.push_back(10 * p);
    v.push_back(0);
    c.push_back(10 * p + 0.2 * nrm);
    v.push_back(0.2);
  }
  c.resize(n);
  v.resize(n);
  for (const auto solver : {s2c::repair::fill::RbfSolver::nullspace_llt, s2c::repair::fill::RbfSolver::lu}) {
    double best = 1e300;
    bool ok = true;
    for (int rep = 0; rep < (n > 2000 ? 1 : 5); ++rep) {
      s2c::repair::fill::CubicRbf f;
      const auto t0 = Clock::now();
      ok &= f.fit(c, v, solver);
      best = std::min(best, seconds_since(t0));
    }
    std::printf("| %5zu | %-13s | %9.2f |%s\n", n, solver == s2c::repair::fill::RbfSolver::lu ? "LU" : "null-space LLT",
                1000 * best, ok ? "" : " (failed)");
  }
}

}  // namespace

int main(int argc, char** argv) {
  int holes = 8;
  bool rbf_only = false, solve_table = true;
  std::string only;  // one shape: sphere, cylinder, torus or real
  std::string protocol = "both";  // each (one hole per call), together (one call), both
  double hole_scale = 1;          // holes this many times the default size
  std::string real = std::string(S2C_SHARED_DIR) + "/data/real/cad/cgal_fandisk.off";
  for (int i = 1; i < argc; ++i) {
    if (!std::strcmp(argv[i], "--holes") && i + 1 < argc) holes = std::atoi(argv[++i]);
    else if (!std::strcmp(argv[i], "--real") && i + 1 < argc) real = argv[++i];
    else if (!std::strcmp(argv[i], "--rbf-only")) rbf_only = true;
    else if (!std::strcmp(argv[i], "--no-solve-table")) solve_table = false;
    else if (!std::strcmp(argv[i], "--only") && i + 1 < argc) only = argv[++i];
    else if (!std::strcmp(argv[i], "--protocol") && i + 1 < argc) protocol = argv[++i];
    else if (!std::strcmp(argv[i], "--repeats") && i + 1 < argc) g_repeats = std::max(1, std::atoi(argv[++i]));
    else if (!std::strcmp(argv[i], "--cold")) g_cold = true;
    else if (!std::strcmp(argv[i], "--one-shot")) g_one_shot = true;
    else if (!std::strcmp(argv[i], "--hole-scale") && i + 1 < argc) hole_scale = std::atof(argv[++i]);
    else {
      std::fprintf(stderr, "usage: s2c-bench-holefill [--holes N] [--real MESH] [--only sphere|cylinder|torus|real] [--protocol each|together|both] [--repeats N] [--cold] [--one-shot] [--hole-scale F] [--rbf-only | --no-solve-table]\n");
      return 2;
    }
  }
  std::mt19937 rng(2024);
  g_only = only;
  if (rbf_only) {
    std::printf("|     N | solver        |        ms |\n|-------|---------------|-----------|\n");
    for (const std::size_t n : {134u, 268u, 524u, 1000u, 1048u}) time_rbf_solve(n, rng);
    return 0;
  }
#ifdef S2C_HAVE_CGAL
  std::printf("CGAL %s: triangulate_refine_and_fair_hole with default parameters\n", CGAL_VERSION_STR);
#else
  std::printf("CGAL not found: no comparison column\n");
#endif
  std::printf("Timing: best of %d, %s\n", g_repeats,
              g_cold ? "caches flushed before every timed call on both sides (--cold)"
                     : "repetitions back to back on both sides (warm caches)");
  struct Shape {
    const char* name;
    TriangleSoup soup;
    double hole_size;
    Distance distance;  // empty: distance to the removed faces
  };
  std::vector<Shape> shapes;
  {
    const double R = 20;
    shapes.push_back({"sphere", icosphere(R, 5), 6 * hole_scale, [R](const Eigen::Vector3d& p) { return p.norm() - R; }});
  }
  {
    const double R = 10, H = 60;
    const auto d = [R, H](const Eigen::Vector3d& p) {  // to the closed cylinder (side and caps)
      const double dr = std::hypot(p.x(), p.y()) - R, dz = std::max(-p.z(), p.z() - H);
      return dr <= 0 && dz <= 0 ? std::max(dr, dz) : std::hypot(std::max(dr, 0.0), std::max(dz, 0.0));
    };
    shapes.push_back({"cylinder", param_surface(96, 60, false, [R, H](double a, double h) {
                        return Eigen::Vector3d(R * std::cos(2 * M_PI * a), R * std::sin(2 * M_PI * a), H * h);
                      }), 5 * hole_scale, d});
  }
  {
    const double Rt = 20, r = 7;
    shapes.push_back({"torus", param_surface(160, 64, true, [Rt, r](double a, double b) {
                        const double ua = 2 * M_PI * a, vb = 2 * M_PI * b;
                        return Eigen::Vector3d((Rt + r * std::cos(vb)) * std::cos(ua),
                                               (Rt + r * std::cos(vb)) * std::sin(ua), r * std::sin(vb));
                      }), 4 * hole_scale,
                      [Rt, r](const Eigen::Vector3d& p) { return std::hypot(std::hypot(p.x(), p.y()) - Rt, p.z()) - r; }});
  }
  try {
    TriangleSoup s = read_soup(real);
    const double size = 0.06 * hole_scale * bounds(s).diagonal();
    shapes.push_back({"real", std::move(s), size, {}});
  } catch (const std::exception& e) {
    std::printf("real mesh skipped: %s\n", e.what());
  }
  const char* header =
      "| shape    | fill  | ok    | mean dev   | max dev    | ms/hole  | dev/CGAL | time/CGAL |\n"
      "|----------|-------|-------|------------|------------|----------|--------|--------|\n";
  std::printf("\nDeviation of the new vertices from the true surface (mm; real: %s, hole size %g × diagonal, "
              "distance to the removed faces), time per hole (ms)\n\n",
              real.c_str(), 0.06 * hole_scale);
  if (hole_scale != 1) {
    std::printf("Holes %g times the default size:", hole_scale);
    for (const Shape& sh : shapes) std::printf(" %s %g mm", sh.name, sh.hole_size);
    std::printf("\n\n");
  }
  if (protocol != "together") {
    std::printf("One hole per call, %d holes per shape:\n\n%s", holes, header);
    for (const Shape& sh : shapes) run_shape(sh.name, sh.soup, sh.hole_size, sh.distance ? &sh.distance : nullptr, holes, rng);
    std::printf("\nSet-up per mesh, not in the times above (%s): our HoleFiller (vertex → faces index and face "
                "boxes) / CGAL's Surface_mesh:",
                g_one_shot ? "--one-shot: ours is in them, as fill_holes builds its index in every call"
                           : "both sides' calls start from it");
    for (std::size_t k = 0; k < g_setup_notes.size(); ++k) std::printf("%s %s", k ? "," : "", g_setup_notes[k].c_str());
    std::printf("\n");
  }
  if (protocol != "each") {
    std::printf("\n%d vertex-disjoint holes in one mesh, one fill_holes call (CGAL: one call per hole):\n\n%s", holes,
                header);
    for (std::size_t k = 0; k < shapes.size(); ++k) {  // each shape its own seed: the same holes with --only
      const Shape& sh = shapes[k];
      if (!g_only.empty() && g_only != sh.name) continue;
      std::mt19937 rng_together(2025 + static_cast<unsigned>(k));
      run_shape_together(sh.name, sh.soup, sh.hole_size, sh.distance ? &sh.distance : nullptr, holes, rng_together);
    }
  }
  if (!solve_table) return 0;
  std::printf("\nRBF solve (fit of N centres: Φ, factorisation, weights), best of 5, ms\n\n");
  std::printf("|     N | solver        |        ms |\n|-------|---------------|-----------|\n");
  for (const std::size_t n : {134u, 268u, 524u, 1000u, 1048u, 5000u}) time_rbf_solve(n, rng);
  return 0;
}
