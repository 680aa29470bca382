// cgal_check: an independent checker for triangle meshes, built only on CGAL (no scan2cad code),
// used to cross-check `scan2cad check` and the exact predicates in core/predicates.
//
//   cgal_check MESH                        one JSON object on stdout (keys below, plus timings)
//   cgal_check --random-tri-tri N SEED     N lines "18 coordinates result" (CGAL's answer, 0/1)
//   cgal_check --random-face-pairs N SEED  N lines "18 coordinates, 6 indices, result"
//
// MESH: .off .ply .stl .obj through CGAL::IO::read_polygon_soup, legacy ASCII VTK POLYDATA
// (.vtk) through the small reader below. CGAL's STL reader already welds vertices by exact
// coordinate equality (std::map<Point_3, int> in IO/STL/STL_reader.h), so STL soups are
// used as read.
//
// Definitions (edges are unordered pairs of distinct vertex indices; a face side whose two
// indices are equal is no edge; "uses" counts face sides, so a face listed twice uses its
// edges twice):
//   vertices              vertices referenced by at least one face (points = all stored)
//   boundary_edges        edges used exactly once
//   boundary_loops        connected components of the graph formed by the boundary edges
//   nonmanifold_edges     edges used more than twice
//   nonmanifold_vertices  vertices whose incident faces form more than one fan: faces around v
//                         are linked when they have a common edge incident to v (whatever the
//                         number of faces on that edge); v counts when the links leave more
//                         than one group. Through a non-manifold edge all its faces are linked,
//                         so a vertex is not counted merely for lying on one. This reproduces
//                         non_manifold_vertices of ../shared/data/real/manifest.json on every
//                         mesh there; the stricter variant (links only through edges used by
//                         exactly two faces) is printed as nonmanifold_vertices_strict
//   components            connected components of faces linked by shared vertices
//                         (unreferenced vertices form no component)
//   closed                boundary_edges == 0 and nonmanifold_edges == 0
//   degenerate_faces      faces whose three points are collinear (CGAL::collinear, exact);
//                         includes faces with a repeated index
//   self_intersections    intersecting face pairs, semantics of
//                         CGAL::Polygon_mesh_processing::self_intersections for
//                         non-degenerate faces: no shared vertex: the closed triangles meet;
//                         one shared vertex: they meet elsewhere too; shared edge: coplanar and
//                         the opposite vertices strictly on the same side of it; duplicate face
//                         (three shared vertices): always. Degenerate faces are NOT skipped (PMP
//                         skips them and reports (f,f) instead): they are tested as the point or
//                         segment they are, and a pair counts when the two point sets meet
//                         outside the hull of the shared vertices (computed with EPECK
//                         constructions, see intersects_outside_hull). Candidate pairs come
//                         from CGAL::box_self_intersection_d on closed face bounding boxes.
//   self_intersections_nondegenerate  the same, counting only pairs of non-degenerate faces
//   cgal_pmp_self_intersections       size of PMP::self_intersections' output on a
//                         Surface_mesh (only when the soup is a valid polygon mesh, else null);
//                         it equals self_intersections_nondegenerate + degenerate_faces.
#include <algorithm>
#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <iostream>
#include <map>
#include <numeric>
#include <random>
#include <set>
#include <string>
#include <utility>
#include <vector>

#include <CGAL/Box_intersection_d/Box_with_info_d.h>
#include <CGAL/Exact_predicates_exact_constructions_kernel.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/IO/polygon_soup_io.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/Polygon_mesh_processing/self_intersections.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/box_intersection_d.h>
#include <CGAL/intersections.h>

namespace {

using K = CGAL::Exact_predicates_inexact_constructions_kernel;
using KE = CGAL::Exact_predicates_exact_constructions_kernel;
using Point = K::Point_3;
using Segment = K::Segment_3;
using Triangle = K::Triangle_3;
using Face = std::array<std::size_t, 3>;

// ---------------------------------------------------------------------------------------
// Reading

struct Soup {
  std::vector<Point> points;
  std::vector<Face> faces;
};

[[noreturn]] void fail(const std::string& msg) {
  std::cerr << "cgal_check: " << msg << "\n";
  std::exit(2);
}

std::string lower_ext(const std::string& path) {
  const auto dot = path.find_last_of('.');
  std::string e = dot == std::string::npos ? "" : path.substr(dot + 1);
  for (char& c : e) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  return e;
}

// Legacy VTK, ASCII, DATASET POLYDATA: POINTS n type, then any of VERTICES / LINES /
// POLYGONS / TRIANGLE_STRIPS "n size" followed by size integers; only POLYGONS become faces.
// Reading stops at POINT_DATA / CELL_DATA (attributes are not needed here).
Soup read_vtk(const std::string& path) {
  std::ifstream in(path);
  if (!in) fail(path + ": cannot open");
  std::string line;
  for (int i = 0; i < 3 && std::getline(in, line); ++i) {
    if (i == 0 && line.rfind("# vtk DataFile", 0) != 0) fail(path + ": not a legacy VTK file");
    if (i == 2 && line.find("ASCII") == std::string::npos) fail(path + ": only ASCII VTK is supported");
  }
  Soup soup;
  std::vector<std::vector<std::size_t>> polys;
  std::string tok;
  bool polydata = false;
  while (in >> tok) {
    if (tok == "DATASET") {
      in >> tok;
      if (tok != "POLYDATA") fail(path + ": only DATASET POLYDATA is supported, got " + tok);
      polydata = true;
    } else if (tok == "POINTS") {
      std::size_t n;
      std::string type;
      in >> n >> type;
      soup.points.reserve(n);
      for (std::size_t i = 0; i < n; ++i) {
        std::string xs, ys, zs;
        if (!(in >> xs >> ys >> zs)) fail(path + ": truncated POINTS");
        // strtod rounds correctly (the double nearest to the decimal text).
        soup.points.emplace_back(std::strtod(xs.c_str(), nullptr), std::strtod(ys.c_str(), nullptr),
                                 std::strtod(zs.c_str(), nullptr));
      }
    } else if (tok == "VERTICES" || tok == "LINES" || tok == "POLYGONS" || tok == "TRIANGLE_STRIPS") {
      std::size_t n, size;
      in >> n >> size;
      if (tok == "TRIANGLE_STRIPS" && n > 0) fail(path + ": TRIANGLE_STRIPS are not supported");
      for (std::size_t i = 0; i < n; ++i) {
        std::size_t k;
        if (!(in >> k)) fail(path + ": truncated " + tok);
        std::vector<std::size_t> ids(k);
        for (auto& id : ids) in >> id;
        if (tok == "POLYGONS") polys.push_back(std::move(ids));
      }
    } else if (tok == "POINT_DATA" || tok == "CELL_DATA") {
      break;
    } else if (tok == "OFFSETS" || tok == "CONNECTIVITY") {
      fail(path + ": VTK 5.1 cell arrays are not supported");
    }
  }
  if (!polydata) fail(path + ": no DATASET POLYDATA");
  for (const auto& p : polys) {
    if (p.size() != 3) fail(path + ": non-triangle polygon");
    for (std::size_t id : p)
      if (id >= soup.points.size()) fail(path + ": polygon index out of range");
    soup.faces.push_back({p[0], p[1], p[2]});
  }
  return soup;
}

Soup read_mesh(const std::string& path) {
  if (lower_ext(path) == "vtk") return read_vtk(path);
  std::vector<Point> points;
  std::vector<std::vector<std::size_t>> polys;
  if (!CGAL::IO::read_polygon_soup(path, points, polys)) fail(path + ": CGAL could not read it");
  Soup soup;
  soup.points = std::move(points);
  for (const auto& p : polys) {
    if (p.size() != 3) fail(path + ": non-triangle face (only triangle meshes are checked)");
    for (std::size_t id : p)
      if (id >= soup.points.size()) fail(path + ": face index out of range");
    soup.faces.push_back({p[0], p[1], p[2]});
  }
  return soup;
}

// ---------------------------------------------------------------------------------------
// Topology

struct UnionFind {
  std::vector<std::size_t> parent;
  explicit UnionFind(std::size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0); }
  std::size_t find(std::size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  }
  void unite(std::size_t a, std::size_t b) { parent[find(a)] = find(b); }
};

struct Topology {
  std::size_t points = 0, vertices = 0, faces = 0, edges = 0;
  std::size_t boundary_edges = 0, boundary_loops = 0, nonmanifold_edges = 0;
  std::size_t nonmanifold_vertices = 0, components = 0;
  // Alternative definition, printed for comparison only: faces linked around a vertex only
  // through edges used by exactly two faces.
  std::size_t nonmanifold_vertices_strict = 0;
};

using Edge = std::pair<std::size_t, std::size_t>;
Edge make_edge(std::size_t a, std::size_t b) { return a < b ? Edge{a, b} : Edge{b, a}; }

Topology topology(const Soup& s) {
  Topology t;
  t.points = s.points.size();
  t.faces = s.faces.size();
  std::map<Edge, std::size_t> uses;
  std::vector<std::vector<std::size_t>> vertex_faces(s.points.size());
  for (std::size_t f = 0; f < s.faces.size(); ++f) {
    const Face& F = s.faces[f];
    for (int i = 0; i < 3; ++i) {
      if (F[i] != F[(i + 1) % 3]) ++uses[make_edge(F[i], F[(i + 1) % 3])];
      if (std::find(F.begin(), F.begin() + i, F[i]) == F.begin() + i) vertex_faces[F[i]].push_back(f);
    }
  }
  t.edges = uses.size();
  UnionFind boundary(s.points.size());
  std::vector<char> on_boundary(s.points.size(), 0);
  for (const auto& [e, n] : uses) {
    if (n == 1) {
      ++t.boundary_edges;
      boundary.unite(e.first, e.second);
      on_boundary[e.first] = on_boundary[e.second] = 1;
    }
    if (n > 2) ++t.nonmanifold_edges;
  }
  std::set<std::size_t> loop_roots;
  for (std::size_t v = 0; v < s.points.size(); ++v)
    if (on_boundary[v]) loop_roots.insert(boundary.find(v));
  t.boundary_loops = loop_roots.size();

  UnionFind comp(s.points.size());
  for (const Face& F : s.faces) comp.unite(F[0], F[1]), comp.unite(F[1], F[2]);
  std::set<std::size_t> comp_roots;
  for (std::size_t v = 0; v < s.points.size(); ++v)
    if (!vertex_faces[v].empty()) ++t.vertices, comp_roots.insert(comp.find(v));
  t.components = comp_roots.size();

  // Fans around each vertex: union the incident faces that share an edge (v, w).
  for (std::size_t v = 0; v < s.points.size(); ++v) {
    const auto& fs = vertex_faces[v];
    if (fs.size() < 2) continue;
    for (int strict = 0; strict < 2; ++strict) {
      std::map<std::size_t, std::vector<std::size_t>> by_neighbour;  // w -> local face ids
      for (std::size_t i = 0; i < fs.size(); ++i)
        for (std::size_t w : s.faces[fs[i]])
          if (w != v) {
            auto& list = by_neighbour[w];
            if (std::find(list.begin(), list.end(), i) == list.end()) list.push_back(i);
          }
      UnionFind local(fs.size());
      for (const auto& [w, list] : by_neighbour) {
        if (strict && uses[make_edge(v, w)] != 2) continue;
        for (std::size_t i = 1; i < list.size(); ++i) local.unite(list[0], list[i]);
      }
      std::set<std::size_t> fans;
      for (std::size_t i = 0; i < fs.size(); ++i) fans.insert(local.find(i));
      if (fans.size() > 1) ++(strict ? t.nonmanifold_vertices_strict : t.nonmanifold_vertices);
    }
  }
  return t;
}

// ---------------------------------------------------------------------------------------
// Face-pair test

// A possibly degenerate triangle as the point set it is, in the exact-constructions kernel.
struct ExactShape {
  int kind;  // 0 point, 1 segment, 2 triangle
  KE::Point_3 a, b, c;
};

KE::Point_3 to_exact(const Point& p) { return KE::Point_3(p.x(), p.y(), p.z()); }

ExactShape exact_shape(const Point& p, const Point& q, const Point& r) {
  ExactShape s;
  if (!CGAL::collinear(p, q, r)) {
    s.kind = 2, s.a = to_exact(p), s.b = to_exact(q), s.c = to_exact(r);
    return s;
  }
  // Collinear: the extreme points in lexicographic order (monotone along any line).
  Point lo = std::min({p, q, r}), hi = std::max({p, q, r});
  s.a = to_exact(lo), s.b = to_exact(hi);
  s.kind = lo == hi ? 0 : 1;
  return s;
}

// Collects the vertices of whatever CGAL::intersection returned.
struct VertexCollector {
  using result_type = void;
  std::vector<KE::Point_3>* out;
  void operator()(const KE::Point_3& p) const { out->push_back(p); }
  void operator()(const KE::Segment_3& s) const { out->push_back(s.source()), out->push_back(s.target()); }
  void operator()(const KE::Triangle_3& t) const {
    for (int i = 0; i < 3; ++i) out->push_back(t.vertex(i));
  }
  void operator()(const std::vector<KE::Point_3>& ps) const { out->insert(out->end(), ps.begin(), ps.end()); }
};

template <class A, class B>
bool collect(const A& a, const B& b, std::vector<KE::Point_3>& out) {
  auto result = CGAL::intersection(a, b);
  if (!result) return false;
  boost::apply_visitor(VertexCollector{&out}, *result);
  return true;
}

// Exact intersection of two shapes as a list of vertices of the (convex) intersection;
// false when empty.
bool exact_intersection(const ExactShape& s, const ExactShape& t, std::vector<KE::Point_3>& out) {
  if (s.kind < t.kind) return exact_intersection(t, s, out);
  const KE::Triangle_3 st(s.a, s.b, s.c), tt(t.a, t.b, t.c);
  const KE::Segment_3 ss(s.a, s.b), ts(t.a, t.b);
  switch (s.kind * 3 + t.kind) {
    case 8: return collect(st, tt, out);
    case 7: return collect(st, ts, out);
    case 6:
      if (!st.has_on(t.a)) return false;
      out.push_back(t.a);
      return true;
    case 4: return collect(ss, ts, out);
    case 3:
      if (!ss.has_on(t.a)) return false;
      out.push_back(t.a);
      return true;
    default:
      if (s.a != t.a) return false;
      out.push_back(t.a);
      return true;
  }
}

// Reference answer by exact constructions: the faces intersect iff their intersection is not
// contained in the hull of the shared vertices (for |shared| < 3). The intersection is convex,
// so it is contained iff all its vertices are.
bool intersects_outside_hull(const std::array<Point, 3>& p, const std::array<Point, 3>& q,
                             const std::vector<Point>& shared) {
  std::vector<KE::Point_3> verts;
  if (!exact_intersection(exact_shape(p[0], p[1], p[2]), exact_shape(q[0], q[1], q[2]), verts)) return false;
  if (shared.empty()) return true;
  const KE::Point_3 a = to_exact(shared[0]);
  const KE::Point_3 b = to_exact(shared.size() > 1 ? shared[1] : shared[0]);
  for (const auto& v : verts) {
    const bool inside = (a == b) ? v == a : KE::Segment_3(a, b).has_on(v);
    if (!inside) return true;
  }
  return false;
}

struct PairResult {
  bool intersect;
  bool by_predicates;  // decided by the EPICK predicate path (both faces non-degenerate)
};

// The test used for meshes and random face pairs. Non-degenerate faces: CGAL predicates with
// the shared-vertex rules of PMP::self_intersections. Otherwise: exact constructions.
PairResult face_pair_intersect(const std::array<Point, 3>& p, const std::array<std::size_t, 3>& pi, bool p_flat,
                               const std::array<Point, 3>& q, const std::array<std::size_t, 3>& qi, bool q_flat) {
  // Distinct shared indices with a position in each face.
  int sp[3], sq[3], n = 0;
  for (int i = 0; i < 3; ++i) {
    bool seen = false;
    for (int s = 0; s < n; ++s) seen = seen || pi[sp[s]] == pi[i];
    if (seen) continue;
    for (int j = 0; j < 3; ++j)
      if (qi[j] == pi[i]) {
        sp[n] = i, sq[n] = j, ++n;
        break;
      }
  }
  if (n == 3) return {true, !p_flat && !q_flat};
  if (p_flat || q_flat) {
    std::vector<Point> shared;
    for (int s = 0; s < n; ++s) shared.push_back(p[sp[s]]);
    return {intersects_outside_hull(p, q, shared), false};
  }
  const Triangle tp(p[0], p[1], p[2]), tq(q[0], q[1], q[2]);
  if (n == 0) return {CGAL::do_intersect(tp, tq), true};
  if (n == 1) {
    const int i = sp[0], j = sq[0];
    const Segment opposite_p(p[(i + 1) % 3], p[(i + 2) % 3]), opposite_q(q[(j + 1) % 3], q[(j + 2) % 3]);
    return {CGAL::do_intersect(tp, opposite_q) || CGAL::do_intersect(tq, opposite_p), true};
  }
  const Point &a = p[sp[0]], &b = p[sp[1]], &c = p[3 - sp[0] - sp[1]], &d = q[3 - sq[0] - sq[1]];
  return {CGAL::coplanar(a, b, c, d) && CGAL::coplanar_orientation(a, b, c, d) == CGAL::POSITIVE, true};
}

// ---------------------------------------------------------------------------------------
// Mesh mode

std::string json_count(std::size_t n) { return std::to_string(n); }

std::string json_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    if (static_cast<unsigned char>(c) < 0x20) {
      char buf[8];
      std::snprintf(buf, sizeof buf, "\\u%04x", c);
      out += buf;
    } else {
      out += c;
    }
  }
  return out;
}

int check_mesh(const std::string& path) {
  const auto t0 = std::chrono::steady_clock::now();
  const Soup soup = read_mesh(path);
  const auto t_read = std::chrono::steady_clock::now();
  const Topology topo = topology(soup);
  const auto t_topo = std::chrono::steady_clock::now();

  const std::size_t nf = soup.faces.size();
  std::vector<char> flat(nf);
  std::size_t degenerate = 0;
  for (std::size_t f = 0; f < nf; ++f) {
    const Face& F = soup.faces[f];
    flat[f] = CGAL::collinear(soup.points[F[0]], soup.points[F[1]], soup.points[F[2]]);
    degenerate += flat[f];
  }

  using Box = CGAL::Box_intersection_d::Box_with_info_d<double, 3, std::size_t>;
  std::vector<Box> boxes;
  boxes.reserve(nf);
  for (std::size_t f = 0; f < nf; ++f) {
    const Face& F = soup.faces[f];
    boxes.emplace_back(soup.points[F[0]].bbox() + soup.points[F[1]].bbox() + soup.points[F[2]].bbox(), f);
  }
  std::size_t pairs = 0, pairs_nondegenerate = 0, candidates = 0;
  std::vector<char> in_pair(nf, 0);
  auto callback = [&](const Box& x, const Box& y) {
    ++candidates;
    const std::size_t f = x.info(), g = y.info();
    const Face &F = soup.faces[f], &G = soup.faces[g];
    const std::array<Point, 3> p{soup.points[F[0]], soup.points[F[1]], soup.points[F[2]]};
    const std::array<Point, 3> q{soup.points[G[0]], soup.points[G[1]], soup.points[G[2]]};
    if (face_pair_intersect(p, F, flat[f], q, G, flat[g]).intersect) {
      ++pairs;
      if (!flat[f] && !flat[g]) ++pairs_nondegenerate;
      in_pair[f] = in_pair[g] = 1;
    }
  };
  // Closed boxes (the default), so touching faces are candidates too.
  CGAL::box_self_intersection_d(boxes.begin(), boxes.end(), callback);
  const std::size_t si_faces = static_cast<std::size_t>(std::count(in_pair.begin(), in_pair.end(), 1));
  const auto t_si = std::chrono::steady_clock::now();

  // Second, independent path: PMP on a Surface_mesh, when the soup is a polygon mesh.
  std::string pmp = "null";
  std::vector<std::vector<std::size_t>> polys;
  for (const Face& F : soup.faces) polys.push_back({F[0], F[1], F[2]});
  const bool is_mesh = CGAL::Polygon_mesh_processing::is_polygon_soup_a_polygon_mesh(polys);
  if (is_mesh) {
    CGAL::Surface_mesh<Point> mesh;
    CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(soup.points, polys, mesh);
    using FD = CGAL::Surface_mesh<Point>::Face_index;
    std::vector<std::pair<FD, FD>> out;
    CGAL::Polygon_mesh_processing::self_intersections(mesh, std::back_inserter(out));
    pmp = json_count(out.size());
  }
  const auto t_pmp = std::chrono::steady_clock::now();
  auto secs = [](auto a, auto b) { return std::chrono::duration<double>(b - a).count(); };

  std::printf(
      "{\"file\": \"%s\", \"points\": %zu, \"vertices\": %zu, \"unreferenced_vertices\": %zu, \"faces\": %zu, "
      "\"edges\": %zu, \"boundary_edges\": %zu, \"boundary_loops\": %zu, \"nonmanifold_edges\": %zu, "
      "\"nonmanifold_vertices\": %zu, \"nonmanifold_vertices_strict\": %zu, \"components\": %zu, "
      "\"closed\": %s, \"degenerate_faces\": %zu, \"self_intersections\": %zu, "
      "\"self_intersections_nondegenerate\": %zu, \"self_intersecting_faces\": %zu, "
      "\"candidate_pairs\": %zu, \"is_polygon_mesh\": %s, \"cgal_pmp_self_intersections\": %s, "
      "\"seconds\": {\"read\": %.3f, \"topology\": %.3f, \"self_intersections\": %.3f, \"pmp\": %.3f, "
      "\"total\": %.3f}}\n",
      json_escape(path).c_str(), topo.points, topo.vertices, topo.points - topo.vertices, topo.faces, topo.edges,
      topo.boundary_edges, topo.boundary_loops, topo.nonmanifold_edges, topo.nonmanifold_vertices,
      topo.nonmanifold_vertices_strict, topo.components,
      (topo.boundary_edges == 0 && topo.nonmanifold_edges == 0) ? "true" : "false", degenerate, pairs,
      pairs_nondegenerate, si_faces, candidates, is_mesh ? "true" : "false", pmp.c_str(), secs(t0, t_read),
      secs(t_read, t_topo), secs(t_topo, t_si), secs(t_si, t_pmp), secs(t0, t_pmp));
  return 0;
}

// ---------------------------------------------------------------------------------------
// Random modes

// Only the raw mt19937_64 output is standardised; the helpers below make the streams
// identical on every platform (std::uniform_*_distribution is implementation-defined).
struct Rng {
  std::mt19937_64 gen;
  explicit Rng(std::uint64_t seed) : gen(seed) {}
  double uniform() { return static_cast<double>(gen() >> 11) * 0x1p-53; }  // [0, 1)
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  int integer(int lo, int hi) { return lo + static_cast<int>(gen() % static_cast<std::uint64_t>(hi - lo + 1)); }
  bool chance(double p) { return uniform() < p; }
};

using P3 = std::array<double, 3>;
using TriD = std::array<P3, 3>;

P3 grid_point(Rng& r, int lo, int hi) {
  return {double(r.integer(lo, hi)), double(r.integer(lo, hi)), double(r.integer(lo, hi))};
}

// A point on the plane z = a*x + b*y + c (small integers, so exactly representable), with
// the axes permuted by `perm`.
P3 plane_point(Rng& r, const int abc[3], int perm, double scale) {
  const double x = r.integer(-3, 3) * scale, y = r.integer(-3, 3) * scale;
  const double z = abc[0] * x + abc[1] * y + abc[2] * scale;  // exact: small multiples of a power of 2
  P3 p{x, y, z};
  std::rotate(p.begin(), p.begin() + perm, p.end());
  return p;
}

P3 random_point(Rng& r, double lo, double hi) { return {r.uniform(lo, hi), r.uniform(lo, hi), r.uniform(lo, hi)}; }

// Nudges one coordinate of p by a few ulps (or a tiny absolute amount).
void nudge(Rng& r, P3& p) {
  double& x = p[static_cast<std::size_t>(r.integer(0, 2))];
  const int steps = r.integer(1, 2);
  for (int i = 0; i < steps; ++i) x = std::nextafter(x, r.chance(0.5) ? 1e308 : -1e308);
}

// Coordinates like 0.1 + 0.2 (!= 0.3 in doubles): sums of "short decimals" that make naive
// floating-point coplanarity and collinearity tests wrong.
double decimal_sum(Rng& r) {
  const double tenths[] = {0.1, 0.2, 0.3, 0.7, 0.6, 1.1};
  return tenths[r.integer(0, 5)] + tenths[r.integer(0, 5)];
}

// One triangle pair; several families so that touching, coplanar, degenerate and
// nearly-degenerate cases are frequent.
void random_pair(Rng& r, TriD& p, TriD& q, int family) {
  if (family < 18) {  // small integer grid: coincidences, coplanarity, degeneracy
    const int hi = r.chance(0.5) ? 2 : 3;
    for (auto& v : p) v = grid_point(r, 0, hi);
    for (auto& v : q) v = grid_point(r, 0, hi);
  } else if (family < 33) {  // both on one integer plane (coplanar), or on a parallel one
    int abc[3] = {r.integer(-1, 2), r.integer(-1, 1), r.integer(-2, 2)};
    const int perm = r.integer(0, 2);
    for (auto& v : p) v = plane_point(r, abc, perm, 1.0);
    if (r.chance(0.3)) abc[2] += r.chance(0.5) ? 1 : -1;
    for (auto& v : q) v = plane_point(r, abc, perm, 1.0);
  } else if (family < 43) {  // coplanar, then one vertex nudged by an ulp
    int abc[3] = {r.integer(-1, 2), r.integer(-1, 1), r.integer(-2, 2)};
    const int perm = r.integer(0, 2);
    const double scale = r.chance(0.5) ? 1.0 : 0.125;
    for (auto& v : p) v = plane_point(r, abc, perm, scale);
    for (auto& v : q) v = plane_point(r, abc, perm, scale);
    nudge(r, q[static_cast<std::size_t>(r.integer(0, 2))]);
  } else if (family < 53) {  // sharing one or two vertex positions, the rest on a grid
    for (auto& v : p) v = grid_point(r, -2, 2);
    const int shared = r.integer(1, 2);
    for (int i = 0; i < 3; ++i) q[i] = i < shared ? p[static_cast<std::size_t>((i + r.integer(0, 2)) % 3)] : grid_point(r, -2, 2);
    std::swap(q[0], q[static_cast<std::size_t>(r.integer(0, 2))]);
  } else if (family < 63) {  // decimal sums like 0.1 + 0.2 on a small lattice
    for (auto& v : p) v = {decimal_sum(r), decimal_sum(r), decimal_sum(r)};
    for (auto& v : q) v = {decimal_sum(r), decimal_sum(r), decimal_sum(r)};
    if (r.chance(0.5)) q[0] = p[static_cast<std::size_t>(r.integer(0, 2))];
  } else if (family < 70) {  // degenerate triangles: collinear or repeated points
    for (TriD* t : {&p, &q}) {
      const P3 o = grid_point(r, -2, 2), d = grid_point(r, -1, 1);
      for (auto& v : *t) {
        const int s = r.integer(-2, 2);
        v = {o[0] + s * d[0], o[1] + s * d[1], o[2] + s * d[2]};
      }
      if (t == &q && r.chance(0.5)) q = {grid_point(r, -2, 2), grid_point(r, -2, 2), grid_point(r, -2, 2)};
    }
  } else if (family < 85) {  // random doubles, q near p so that crossings are common
    for (auto& v : p) v = random_point(r, -1, 1);
    const P3 c{(p[0][0] + p[1][0] + p[2][0]) / 3, (p[0][1] + p[1][1] + p[2][1]) / 3, (p[0][2] + p[1][2] + p[2][2]) / 3};
    for (auto& v : q) {
      v = random_point(r, -0.7, 0.7);
      for (int k = 0; k < 3; ++k) v[static_cast<std::size_t>(k)] += c[static_cast<std::size_t>(k)];
    }
  } else {  // extreme magnitudes: another family scaled by 2^-1000, 1e-300 or 2^900
    random_pair(r, p, q, r.integer(0, 84));
    const double scales[] = {0x1p-1000, 1e-300, 0x1p+900, 0x1p-1000};
    const double s = scales[r.integer(0, 3)];
    for (TriD* t : {&p, &q})
      for (auto& v : *t)
        for (double& x : v) x *= s;
  }
}

void random_pair(Rng& r, TriD& p, TriD& q) { random_pair(r, p, q, r.integer(0, 99)); }

std::array<Point, 3> to_points(const TriD& t) {
  return {Point(t[0][0], t[0][1], t[0][2]), Point(t[1][0], t[1][1], t[1][2]), Point(t[2][0], t[2][1], t[2][2])};
}

void print_coords(const TriD& t) {
  for (const auto& v : t)
    for (double x : v) std::printf("%.17g ", x);
}

int random_tri_tri(long n, std::uint64_t seed) {
  Rng r(seed);
  long disagreements = 0, hits = 0;
  const std::array<std::size_t, 3> pi{0, 1, 2}, qi{3, 4, 5};  // no shared index
  for (long i = 0; i < n; ++i) {
    TriD p, q;
    random_pair(r, p, q);
    const auto pp = to_points(p), qq = to_points(q);
    const bool pf = CGAL::collinear(pp[0], pp[1], pp[2]), qf = CGAL::collinear(qq[0], qq[1], qq[2]);
    const PairResult res = face_pair_intersect(pp, pi, pf, qq, qi, qf);
    // Cross-check the predicate path against exact constructions.
    if (res.by_predicates && res.intersect != intersects_outside_hull(pp, qq, {})) ++disagreements;
    hits += res.intersect;
    print_coords(p);
    print_coords(q);
    std::printf("%d\n", res.intersect ? 1 : 0);
  }
  std::fprintf(stderr, "cgal_check: %ld pairs, %ld intersecting, %ld predicate/construction disagreements\n", n, hits,
               disagreements);
  return disagreements == 0 ? 0 : 3;
}

int random_face_pairs(long n, std::uint64_t seed) {
  Rng r(seed);
  long disagreements = 0, hits = 0;
  long by_shared[4] = {0, 0, 0, 0};
  for (long i = 0; i < n; ++i) {
    TriD p, q;
    random_pair(r, p, q);
    // Indices 0..2 for p; q shares 0..3 of them, the others get 3..5. Shared indices take
    // p's positions, so index -> position stays a function.
    int shared = 0;  // about 15 % none, 8 % all three, the rest one or two
    if (!r.chance(0.15)) shared = (r.integer(1, 3) == 3 && r.chance(0.3)) ? 3 : r.integer(1, 2);
    std::array<std::size_t, 3> pi{0, 1, 2}, qi{3, 4, 5};
    std::array<int, 3> order{0, 1, 2};
    std::shuffle(order.begin(), order.end(), r.gen);
    for (int s = 0; s < shared; ++s) {
      qi[static_cast<std::size_t>(s)] = pi[static_cast<std::size_t>(order[static_cast<std::size_t>(s)])];
      q[static_cast<std::size_t>(s)] = p[static_cast<std::size_t>(order[static_cast<std::size_t>(s)])];
    }
    // Rarely a repeated index inside a face (a flat face by construction).
    if (r.chance(0.03)) {
      qi[2] = qi[0];
      q[2] = q[0];
    }
    // Random rotation and orientation of q.
    const int rot = r.integer(0, 2);
    std::rotate(qi.begin(), qi.begin() + rot, qi.end());
    std::rotate(q.begin(), q.begin() + rot, q.end());
    if (r.chance(0.5)) std::swap(qi[1], qi[2]), std::swap(q[1], q[2]);
    const auto pp = to_points(p), qq = to_points(q);
    const bool pf = CGAL::collinear(pp[0], pp[1], pp[2]), qf = CGAL::collinear(qq[0], qq[1], qq[2]);
    const PairResult res = face_pair_intersect(pp, pi, pf, qq, qi, qf);
    if (res.by_predicates) {
      std::set<std::size_t> common;
      for (std::size_t a : pi)
        for (std::size_t b : qi)
          if (a == b) common.insert(a);
      std::vector<Point> hull;
      for (std::size_t c : common) hull.push_back(pp[c]);  // indices 0..2 are p's positions
      const bool reference = common.size() == 3 ? true : intersects_outside_hull(pp, qq, hull);
      if (reference != res.intersect) ++disagreements;
    }
    std::set<std::size_t> distinct_shared;
    for (std::size_t a : pi)
      for (std::size_t b : qi)
        if (a == b) distinct_shared.insert(a);
    ++by_shared[distinct_shared.size()];
    hits += res.intersect;
    print_coords(p);
    print_coords(q);
    for (std::size_t x : pi) std::printf("%zu ", x);
    for (std::size_t x : qi) std::printf("%zu ", x);
    std::printf("%d\n", res.intersect ? 1 : 0);
  }
  std::fprintf(stderr,
               "cgal_check: %ld face pairs (shared 0/1/2/3: %ld/%ld/%ld/%ld), %ld intersecting, %ld "
               "predicate/construction disagreements\n",
               n, by_shared[0], by_shared[1], by_shared[2], by_shared[3], hits, disagreements);
  return disagreements == 0 ? 0 : 3;
}

void usage() {
  std::cerr << "usage: cgal_check MESH            (.off .ply .stl .obj .vtk)\n"
               "       cgal_check --random-tri-tri N SEED\n"
               "       cgal_check --random-face-pairs N SEED\n";
}

}  // namespace

int main(int argc, char** argv) {
  if (argc == 2 && std::strcmp(argv[1], "--help") != 0) return check_mesh(argv[1]);
  if (argc == 4 && (std::strcmp(argv[1], "--random-tri-tri") == 0 || std::strcmp(argv[1], "--random-face-pairs") == 0)) {
    const long n = std::strtol(argv[2], nullptr, 10);
    const std::uint64_t seed = std::strtoull(argv[3], nullptr, 10);
    if (n <= 0) return usage(), 2;
    return std::strcmp(argv[1], "--random-tri-tri") == 0 ? random_tri_tri(n, seed) : random_face_pairs(n, seed);
  }
  usage();
  return argc == 2 ? 0 : 2;
}
