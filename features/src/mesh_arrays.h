#pragma once
// Flat arrays of a triangle mesh for the feature analysis: positions, faces, face normals and
// areas, vertex→face incidence (CSR) and undirected edges with their faces. Plain arrays make the
// per-vertex loops parallel and cache friendly on million-vertex meshes.
#include <array>
#include <vector>

#include <Eigen/Core>

#include "s2c/core/mesh.h"

namespace s2c::features {

struct MeshArrays {
  struct Edge {
    int v0, v1;  ///< vertices, v0 < v1
    int f0, f1;  ///< the two faces; f1 = -1 on a boundary edge
  };
  std::vector<Eigen::Vector3d> pos;
  std::vector<std::array<int, 3>> tri;
  std::vector<Eigen::Vector3d> fnormal;
  std::vector<double> farea;
  std::vector<int> vf_start, vf;                ///< faces of vertex v: vf[vf_start[v] .. vf_start[v+1])
  std::vector<Edge> edges;
  std::vector<std::array<int, 3>> face_edges;   ///< edge index of side (i, i+1) of each face
  double median_edge = 0, mean_edge = 0;
  Bounds box;

  int vertices() const { return static_cast<int>(pos.size()); }
  int faces() const { return static_cast<int>(tri.size()); }
  /// The centroid of face f, computed when asked: an array of them took 47 MB at two million
  /// faces (on the VMs this runs on a MB of fresh memory costs about 2 ms to fault in), for a few
  /// reads per face.
  Eigen::Vector3d centroid(int f) const { return (pos[tri[f][0]] + pos[tri[f][1]] + pos[tri[f][2]]) / 3.0; }
  /// The face across edge `e` from face `f` (-1 on a boundary).
  int across(int e, int f) const { return edges[e].f0 == f ? edges[e].f1 : edges[e].f0; }
};

/// Builds the arrays of a (manifold, as OpenMesh holds it) mesh. Deleted elements are not expected.
MeshArrays build_arrays(const Mesh& mesh);

/// The same arrays from an indexed triangle list, which they take over (its normals are freed).
/// When the list is a manifold surface with its faces oriented alike (every edge on one or two
/// faces running it in opposite directions, every vertex's faces one fan, no repeated corner),
/// no half-edge mesh is built: the edges are numbered as OpenMesh numbers them. Otherwise the
/// list goes through soup_to_mesh, which gives faces at complex edges or vertices copies of their
/// vertices, and `*through_mesh` is set. Either way the arrays equal
/// build_arrays(soup_to_mesh(soup)). \throw InvalidInput for a face index out of range.
MeshArrays build_arrays(TriangleSoup&& soup, bool* through_mesh = nullptr);

/// Robust normal noise σ (mm): over interior edges, the offset of one face's far vertex from the
/// other face's plane; its lower quartile, scaled to a standard deviation, leaves creases out.
double measure_noise(const MeshArrays& m);

/// Waviness of the surface (mm): the RMS distance of the vertices within kWavinessRings rings of
/// a vertex from the quadric height field fitted to them in their principal frame, lower quartile
/// over about kWavinessSamples vertices. Where measure_noise sees the roughness between
/// neighbouring faces, this sees bumps a few edges wide, which a Poisson surface has at any
/// resolution: its size does not fall with the edge length. Curvature does not count (the
/// quadric absorbs it), creases mostly not (the lower quartile).
double measure_waviness(const MeshArrays& m);

}  // namespace s2c::features
