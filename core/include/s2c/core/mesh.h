#pragma once
/// \file The mesh types: OpenMesh's TriMesh with double precision for algorithms, and a plain
/// indexed triangle list ("soup") that can hold anything a file holds (non-manifold edges,
/// duplicate faces) for checking and repair.
#include <array>
#include <cstdint>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <OpenMesh/Core/Mesh/TriMesh_ArrayKernelT.hh>

namespace s2c {

struct MeshTraits : OpenMesh::DefaultTraits {
  using Point = OpenMesh::Vec3d;
  using Normal = OpenMesh::Vec3d;
  VertexAttributes(OpenMesh::Attributes::Normal | OpenMesh::Attributes::Status);
  FaceAttributes(OpenMesh::Attributes::Normal | OpenMesh::Attributes::Status);
  EdgeAttributes(OpenMesh::Attributes::Status);
  HalfedgeAttributes(OpenMesh::Attributes::PrevHalfedge);
};
/// The mesh of every algorithm: coordinates in millimetres, double precision.
using Mesh = OpenMesh::TriMesh_ArrayKernelT<MeshTraits>;

/// An indexed triangle list exactly as read from a file (polygons fan-triangulated).
/// Unlike Mesh it can represent non-manifold and inconsistently oriented input.
struct TriangleSoup {
  std::vector<Eigen::Vector3d> vertices;             ///< #V positions, mm
  std::vector<std::array<int, 3>> faces;              ///< #F vertex indices into `vertices`
  std::vector<Eigen::Vector3d> normals;               ///< #V per-vertex normals, or empty
  std::size_t polygons_triangulated = 0;              ///< input faces with more than 3 corners
  std::size_t faces_dropped = 0;                      ///< faces with repeated corner indices, dropped

  bool empty() const { return faces.empty(); }
};

/// Builds a Mesh from a soup. Faces OpenMesh cannot add (complex edges, non-manifold vertices)
/// are added on duplicated vertices so that no face is lost. Returns how many faces needed that.
std::size_t soup_to_mesh(const TriangleSoup& soup, Mesh& mesh);
/// The indexed triangle list of a Mesh (deleted elements skipped, indices compacted).
TriangleSoup mesh_to_soup(const Mesh& mesh);

/// Axis-aligned bounding box of the referenced vertices.
struct Bounds {
  Eigen::Vector3d min = Eigen::Vector3d::Constant(0.0), max = Eigen::Vector3d::Constant(0.0);
  double diagonal() const { return (max - min).norm(); }
  Eigen::Vector3d center() const { return 0.5 * (min + max); }
};
Bounds bounds(const TriangleSoup& soup);
Bounds bounds(const Mesh& mesh);

/// The median edge length of the faces, mm (0 without faces), from up to ~20 k faces spread over
/// the mesh.
double median_edge_length(const TriangleSoup& mesh);

/// Key of the undirected edge {a, b} (the smaller index in the high 32 bits).
inline std::uint64_t undirected_edge_key(int a, int b) {
  if (a > b) std::swap(a, b);
  return (std::uint64_t(std::uint32_t(a)) << 32) | std::uint32_t(b);
}

inline Eigen::Vector3d to_eigen(const OpenMesh::Vec3d& p) { return {p[0], p[1], p[2]}; }
inline OpenMesh::Vec3d to_om(const Eigen::Vector3d& p) { return {p.x(), p.y(), p.z()}; }

}  // namespace s2c
