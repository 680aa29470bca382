#include "mesh_arrays.h"

#include <algorithm>
#include <atomic>
#include <cmath>

#include <Eigen/Dense>
#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "fit_util.h"
#include "kth_value.h"
#include "s2c/core/errors.h"

namespace s2c::features {
namespace {

constexpr int kWavinessRings = 6;
constexpr int kWavinessSamples = 5000;

/// The positions of the vertices within `rings` rings of v0 (v0 first), through the faces.
std::vector<Eigen::Vector3d> vertex_rings(const MeshArrays& m, int v0, int rings) {
  // Vertices seen, in a per-thread table as long as the mesh; only the entries set here are
  // reset, so the next call (on this mesh or another) starts from a clean table.
  thread_local std::vector<char> seen;
  if (seen.size() < static_cast<std::size_t>(m.vertices())) seen.assign(m.vertices(), 0);
  std::vector<int> verts = {v0};
  seen[v0] = 1;
  std::size_t begin = 0;
  for (int r = 0; r < rings; ++r) {
    const std::size_t end = verts.size();
    for (std::size_t k = begin; k < end; ++k)
      for (int j = m.vf_start[verts[k]]; j < m.vf_start[verts[k] + 1]; ++j)
        for (int u : m.tri[m.vf[j]])
          if (!seen[u]) seen[u] = 1, verts.push_back(u);
    begin = end;
  }
  std::vector<Eigen::Vector3d> points;
  points.reserve(verts.size());
  for (int u : verts) {
    seen[u] = 0;
    points.push_back(m.pos[u]);
  }
  return points;
}

/// RMS distance of the points from the quadric height field z = ax² + bxy + cy² + dx + ey + f
/// fitted to them in their principal frame (z along the smallest principal axis); -1 when too few.
double quadric_residual(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 12) return -1.0;
  const fit::Pca pc = fit::pca(points, {});  // columns by ascending eigenvalue: z first
  Eigen::MatrixXd A(points.size(), 6);
  Eigen::VectorXd z(points.size());
  for (std::size_t k = 0; k < points.size(); ++k) {
    const Eigen::Vector3d q = pc.vectors.transpose() * (points[k] - pc.mean);
    A.row(static_cast<Eigen::Index>(k)) << q[1] * q[1], q[1] * q[2], q[2] * q[2], q[1], q[2], 1.0;
    z[static_cast<Eigen::Index>(k)] = q[0];
  }
  const Eigen::VectorXd coef = A.colPivHouseholderQr().solve(z);
  return std::sqrt((A * coef - z).squaredNorm() / static_cast<double>(points.size()));
}

}  // namespace

namespace {

/// Face normals and areas from pos and tri, and the vertex→face incidence (CSR).
void add_faces(MeshArrays& m) {
  const int nv = m.vertices(), nf = m.faces();
  m.fnormal.resize(nf);
  m.farea.resize(nf);
  tbb::parallel_for(0, nf, [&](int f) {
    const auto& t = m.tri[f];
    const Eigen::Vector3d n = (m.pos[t[1]] - m.pos[t[0]]).cross(m.pos[t[2]] - m.pos[t[0]]);
    const double len = n.norm();
    m.farea[f] = 0.5 * len;
    m.fnormal[f] = len > 0 ? Eigen::Vector3d(n / len) : Eigen::Vector3d::Zero();
  });
  m.vf_start.assign(nv + 1, 0);
  for (const auto& t : m.tri)
    for (int v : t) ++m.vf_start[v + 1];
  for (int v = 0; v < nv; ++v) m.vf_start[v + 1] += m.vf_start[v];
  m.vf.resize(m.vf_start[nv]);
  std::vector<int> fill(m.vf_start.begin(), m.vf_start.end() - 1);
  for (int f = 0; f < nf; ++f)
    for (int v : m.tri[f]) m.vf[fill[v]++] = f;
}

/// Mean and median edge length, and the bounding box of all vertices (isolated ones included).
void add_sizes(MeshArrays& m) {
  std::vector<double> lengths(m.edges.size());
  tbb::parallel_for(0, static_cast<int>(m.edges.size()),
                    [&](int e) { lengths[e] = (m.pos[m.edges[e].v0] - m.pos[m.edges[e].v1]).norm(); });
  if (!lengths.empty()) {
    double sum = 0;
    for (double l : lengths) sum += l;
    m.mean_edge = sum / lengths.size();
    m.median_edge = kth_value(lengths, lengths.size() / 2);
  }
  for (int v = 0; v < m.vertices(); ++v) {
    if (v == 0) m.box.min = m.box.max = m.pos[0];
    m.box.min = m.box.min.cwiseMin(m.pos[v]);
    m.box.max = m.box.max.cwiseMax(m.pos[v]);
  }
}

/// The position of vertex v in face f (-1 if absent).
int corner_of(const MeshArrays& m, int f, int v) {
  const auto& t = m.tri[f];
  return t[0] == v ? 0 : t[1] == v ? 1 : t[2] == v ? 2 : -1;
}

constexpr int kNoFace = -1, kBadEdge = -2;
/// A side not looked up yet (add_manifold_edges).
constexpr int kUnlooked = -3;

/// The face across side i (t[i] → t[i+1]) of face f, found through the faces of t[i]: kNoFace on
/// a boundary, kBadEdge where the side is not a manifold edge with the faces oriented alike (a
/// third face on it, or a neighbour running it in the same direction).
int face_across_side(const MeshArrays& m, int f, int i) {
  const int a = m.tri[f][i], b = m.tri[f][(i + 1) % 3];
  int across = kNoFace;
  for (int j = m.vf_start[a]; j < m.vf_start[a + 1]; ++j) {
    const int g = m.vf[j];
    if (g == f) continue;
    const int ca = corner_of(m, g, a);
    const auto& t = m.tri[g];
    if (t[(ca + 1) % 3] == b) return kBadEdge;  // a → b again: flipped neighbour or duplicate face
    if (t[(ca + 2) % 3] != b) continue;
    if (across != kNoFace) return kBadEdge;     // a third face on the edge
    across = g;
  }
  return across;
}

/// Whether the faces of vertex v form one fan (a disk, or a half-disk at a boundary): walking from
/// one face across the sides at v reaches all of them. `across[f][i]` is the face across side i
/// of f (kNoFace on a boundary): one lookup per step, where the edge arrays took two.
bool one_fan(const MeshArrays& m, const std::vector<std::array<int, 3>>& across, int v) {
  const int count = m.vf_start[v + 1] - m.vf_start[v];
  if (count == 0) return true;
  const int start = m.vf[m.vf_start[v]];
  int reached = 1;
  // Forward across the side leaving v, then (if that stops at a boundary) backward across the
  // side entering v; orientations agree, so each step lands on the neighbour's other side at v.
  for (int step : {0, 2}) {
    int f = start;
    while (reached <= count) {
      const int g = across[f][(corner_of(m, f, v) + step) % 3];
      if (g < 0) break;
      if (g == start) return reached == count;
      f = g;
      ++reached;
    }
  }
  return reached == count;
}

}  // namespace

MeshArrays build_arrays(const Mesh& mesh) {
  MeshArrays m;
  const int nv = static_cast<int>(mesh.n_vertices()), nf = static_cast<int>(mesh.n_faces());
  // Every step but the prefix sums runs over vertices, faces or edges in parallel (OpenMesh is
  // only read); ids and order are those of the sequential walk.
  m.pos.resize(nv);
  tbb::parallel_for(0, nv, [&](int v) { m.pos[v] = to_eigen(mesh.point(Mesh::VertexHandle(v))); });
  m.tri.resize(nf);
  tbb::parallel_for(0, nf, [&](int f) {
    int k = 0;
    for (auto fv : mesh.fv_range(Mesh::FaceHandle(f))) m.tri[f][k++] = fv.idx();
  });
  add_faces(m);

  // Edges with at least one face, numbered in OpenMesh's order (isolated edges skipped).
  const int ne_all = static_cast<int>(mesh.n_edges());
  std::vector<int> id(ne_all + 1, 0);
  tbb::parallel_for(0, ne_all, [&](int e) {
    const Mesh::EdgeHandle eh(e);
    id[e + 1] = mesh.face_handle(mesh.halfedge_handle(eh, 0)).is_valid() ||
                mesh.face_handle(mesh.halfedge_handle(eh, 1)).is_valid();
  });
  for (int e = 0; e < ne_all; ++e) id[e + 1] += id[e];
  const int ne = id[ne_all];
  m.edges.resize(ne);
  m.face_edges.assign(nf, {-1, -1, -1});
  tbb::parallel_for(0, ne_all, [&](int e) {
    if (id[e + 1] == id[e]) return;  // an isolated edge without faces
    const Mesh::EdgeHandle eh(e);
    const auto h0 = mesh.halfedge_handle(eh, 0), h1 = mesh.halfedge_handle(eh, 1);
    const int a = mesh.to_vertex_handle(h0).idx(), b = mesh.from_vertex_handle(h0).idx();
    int f0 = mesh.face_handle(h0).idx(), f1 = mesh.face_handle(h1).idx();
    if (f0 < 0) std::swap(f0, f1);
    const int k = id[e];
    m.edges[k] = {std::min(a, b), std::max(a, b), f0, f1};
    // Each edge writes its own slot of its faces' edge triples.
    for (int f : {f0, f1}) {
      if (f < 0) continue;
      for (int i = 0; i < 3; ++i) {
        const int p = m.tri[f][i], q = m.tri[f][(i + 1) % 3];
        if ((p == a && q == b) || (p == b && q == a)) m.face_edges[f][i] = k;
      }
    }
  });
  add_sizes(m);
  return m;
}

namespace {

/// Completes arrays holding pos and tri only, with the edges numbered as OpenMesh numbers them
/// (an edge when its first face is added, sides in order), if the faces form a manifold surface
/// oriented alike; false otherwise.
bool add_manifold_edges(MeshArrays& m) {
  const int nv = m.vertices(), nf = m.faces();
  for (const auto& t : m.tri)
    for (int k = 0; k < 3; ++k)
      if (t[k] == t[(k + 1) % 3]) return false;
  add_faces(m);
  // The faces across the sides. Each side a → b with a < b is looked up and, when it finds a
  // face g across, sets g's side b → a too: that is the one face whose lookup would find f (any
  // other face on the edge makes f's lookup a bad edge), and only f's lookup writes it. The
  // sides left unlooked (a boundary, or b → a with no a → b) are looked up after. Half the
  // lookups: they were half the arrays' time on the 1.7 M faces of a scan's Poisson mesh.
  std::vector<std::array<int, 3>> across(nf, {kUnlooked, kUnlooked, kUnlooked});
  std::atomic<bool> manifold{true};
  tbb::parallel_for(0, nf, [&](int f) {
    for (int i = 0; i < 3; ++i) {
      const int a = m.tri[f][i], b = m.tri[f][(i + 1) % 3];
      if (a > b) continue;
      const int g = face_across_side(m, f, i);
      across[f][i] = g;
      if (g == kBadEdge) manifold = false;
      if (g >= 0) across[g][corner_of(m, g, b)] = f;
    }
  });
  if (!manifold) return false;
  std::vector<int> first_edge(nf + 1, 0);
  tbb::parallel_for(0, nf, [&](int f) {
    int fresh = 0;
    for (int i = 0; i < 3; ++i) {
      if (across[f][i] == kUnlooked) {
        across[f][i] = face_across_side(m, f, i);
        if (across[f][i] == kBadEdge) manifold = false;
      }
      fresh += !(across[f][i] >= 0 && across[f][i] < f);
    }
    first_edge[f + 1] = fresh;
  });
  if (!manifold) return false;
  for (int f = 0; f < nf; ++f) first_edge[f + 1] += first_edge[f];
  m.edges.resize(first_edge[nf]);
  m.face_edges.resize(nf);
  tbb::parallel_for(0, nf, [&](int f) {
    int k = first_edge[f];
    for (int i = 0; i < 3; ++i) {
      const int g = across[f][i];
      if (g >= 0 && g < f) continue;
      const int a = m.tri[f][i], b = m.tri[f][(i + 1) % 3];
      m.edges[k] = {std::min(a, b), std::max(a, b), f, g};
      m.face_edges[f][i] = k++;
    }
  });
  tbb::parallel_for(0, nf, [&](int f) {
    for (int i = 0; i < 3; ++i) {
      const int g = across[f][i];
      if (g < 0 || g > f) continue;
      // The side of g that runs the other way: its end is this side's start.
      m.face_edges[f][i] = m.face_edges[g][(corner_of(m, g, m.tri[f][i]) + 2) % 3];
    }
  });
  std::atomic<bool> fans{true};
  tbb::parallel_for(0, nv, [&](int v) {
    if (!one_fan(m, across, v)) fans = false;
  });
  return fans;
}

}  // namespace

MeshArrays build_arrays(TriangleSoup&& soup, bool* through_mesh) {
  const int nv = static_cast<int>(soup.vertices.size());
  for (std::size_t f = 0; f < soup.faces.size(); ++f)
    for (int v : soup.faces[f])
      if (v < 0 || v >= nv)
        throw InvalidInput(fmt::format("face {} refers to vertex {}, but the mesh has {} vertices", f, v, nv));
  MeshArrays m;
  m.pos = std::move(soup.vertices);
  m.tri = std::move(soup.faces);
  soup = TriangleSoup{};  // its normals too: the memory is handed out again below
  const bool manifold = add_manifold_edges(m);
  if (through_mesh) *through_mesh = !manifold;
  if (manifold) {
    add_sizes(m);
    return m;
  }
  // Complex edges or vertices: OpenMesh gives the faces it cannot attach copies of their
  // vertices, and the analysis sees the mesh as it does everywhere else.
  TriangleSoup faces;
  faces.vertices = std::move(m.pos);
  faces.faces = std::move(m.tri);
  m = MeshArrays{};
  Mesh mesh;
  soup_to_mesh(faces, mesh);
  faces = TriangleSoup{};
  return build_arrays(mesh);
}

double measure_noise(const MeshArrays& m) {
  // Per interior edge: distance of the far vertex of one face from the plane of the other. On a
  // noisy surface it is about 2σ (four noisy vertices, the far one extrapolated); creases make it
  // large but they are a minority, and on CAD tessellations most edges are exactly flat. The lower
  // quartile keeps creases out: P25 of |N(0, s)| = 0.3186 s.
  const int ne = static_cast<int>(m.edges.size());
  std::vector<double> offsets(ne, -1.0);
  tbb::parallel_for(0, ne, [&](int e) {
    const auto& E = m.edges[e];
    if (E.f1 < 0 || m.farea[E.f0] <= 0) return;
    int far = -1;
    for (int u : m.tri[E.f1])
      if (u != E.v0 && u != E.v1) far = u;
    if (far < 0) return;
    offsets[e] = std::abs(m.fnormal[E.f0].dot(m.pos[far] - m.pos[E.v0]));
  });
  offsets.erase(std::remove(offsets.begin(), offsets.end(), -1.0), offsets.end());
  if (offsets.empty()) return 0.0;
  return kth_value(offsets, offsets.size() / 4) / 0.3186 / 2.0;
}

double measure_waviness(const MeshArrays& m) {
  const int nv = m.vertices();
  const int stride = std::max(1, nv / kWavinessSamples);
  std::vector<double> rms((nv + stride - 1) / stride, -1.0);
  tbb::parallel_for(0, static_cast<int>(rms.size()), [&](int i) {
    rms[i] = quadric_residual(vertex_rings(m, i * stride, kWavinessRings));
  });
  rms.erase(std::remove_if(rms.begin(), rms.end(), [](double r) { return !(r >= 0); }), rms.end());
  if (rms.empty()) return 0.0;
  std::nth_element(rms.begin(), rms.begin() + rms.size() / 4, rms.end());
  return rms[rms.size() / 4];
}

}  // namespace s2c::features
