#pragma once
// An OpenMesh importer that records what a reader delivers into a TriangleSoup instead of
// building a half-edge mesh, so that nothing the file holds (non-manifold edges, duplicate
// faces, bad indices) is silently dropped before we can check it.
#include <OpenMesh/Core/IO/importer/BaseImporter.hh>

#include <cstdint>
#include <string>
#include <vector>

#include "s2c/core/mesh.h"

namespace s2c::io_detail {

/// Adds the face with the `n` corners `idx` (record `face_no` of the file) to `soup`, by fan
/// triangulation; a face with fewer than three corners or a corner not below `vertex_count` is
/// dropped and, if `first_error` is empty, described there.
void add_polygon(TriangleSoup& soup, const std::int64_t* idx, std::size_t n, std::size_t vertex_count, std::size_t face_no,
                 std::string& first_error);

class SoupImporter final : public OpenMesh::IO::BaseImporter {
 public:
  using VH = OpenMesh::VertexHandle;
  using FH = OpenMesh::FaceHandle;
  using HH = OpenMesh::HalfedgeHandle;
  using EH = OpenMesh::EdgeHandle;

  TriangleSoup soup;
  std::string first_error;  // the first problem seen, reported after the reader returns
  std::size_t face_records = 0;  // add_face calls: faces as the file counts them

  VH add_vertex(const OpenMesh::Vec3f& p) override { return add_vertex(OpenMesh::Vec3d(p[0], p[1], p[2])); }
  VH add_vertex(const OpenMesh::Vec3d& p) override {
    soup.vertices.emplace_back(p[0], p[1], p[2]);
    return VH(static_cast<int>(soup.vertices.size()) - 1);
  }
  VH add_vertex() override { return add_vertex(OpenMesh::Vec3d(0, 0, 0)); }
  FH add_face(const VHandles& idx) override;
  void set_point(VH vh, const OpenMesh::Vec3f& p) override {
    if (valid(vh)) soup.vertices[vh.idx()] = Eigen::Vector3d(p[0], p[1], p[2]);
  }
  void set_normal(VH vh, const OpenMesh::Vec3f& n) override { set_normal(vh, OpenMesh::Vec3d(n[0], n[1], n[2])); }
  void set_normal(VH vh, const OpenMesh::Vec3d& n) override {
    if (!valid(vh)) return;
    if (soup.normals.size() < soup.vertices.size()) soup.normals.resize(soup.vertices.size(), Eigen::Vector3d::Zero());
    soup.normals[vh.idx()] = Eigen::Vector3d(n[0], n[1], n[2]);
  }
  size_t n_vertices() const override { return soup.vertices.size(); }
  size_t n_faces() const override { return soup.faces.size(); }
  size_t n_edges() const override { return 0; }
  // reserve() is deliberately a no-op: header counts are not trusted before validation.
  void reserve(unsigned int, unsigned int, unsigned int) override {}

  // Everything below carries information we do not keep (colours, texture, status).
  HH add_edge(VH, VH) override { return HH(); }
  FH add_face(HH) override { return FH(); }
  void add_face_texcoords(FH, VH, const std::vector<OpenMesh::Vec2f>&) override {}
  void add_face_texcoords(FH, VH, const std::vector<OpenMesh::Vec3f>&) override {}
  void set_face_texindex(FH, int) override {}
  void set_halfedge(VH, HH) override {}
  void set_color(VH, const OpenMesh::Vec3uc&) override {}
  void set_color(VH, const OpenMesh::Vec4uc&) override {}
  void set_color(VH, const OpenMesh::Vec3f&) override {}
  void set_color(VH, const OpenMesh::Vec4f&) override {}
  void set_texcoord(VH, const OpenMesh::Vec2f&) override {}
  void set_status(VH, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_next(HH, HH) override {}
  void set_face(HH, FH) override {}
  void request_face_texcoords2D() override {}
  void set_texcoord(HH, const OpenMesh::Vec2f&) override {}
  void set_texcoord(VH, const OpenMesh::Vec3f&) override {}
  void set_texcoord(HH, const OpenMesh::Vec3f&) override {}
  void set_status(HH, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_color(EH, const OpenMesh::Vec3uc&) override {}
  void set_color(EH, const OpenMesh::Vec4uc&) override {}
  void set_color(EH, const OpenMesh::Vec3f&) override {}
  void set_color(EH, const OpenMesh::Vec4f&) override {}
  void set_status(EH, const OpenMesh::Attributes::StatusInfo&) override {}
  void set_normal(FH, const OpenMesh::Vec3f&) override {}
  void set_normal(FH, const OpenMesh::Vec3d&) override {}
  void set_color(FH, const OpenMesh::Vec3uc&) override {}
  void set_color(FH, const OpenMesh::Vec4uc&) override {}
  void set_color(FH, const OpenMesh::Vec3f&) override {}
  void set_color(FH, const OpenMesh::Vec4f&) override {}
  void set_status(FH, const OpenMesh::Attributes::StatusInfo&) override {}
  void add_texture_information(int, std::string) override {}

 private:
  std::vector<std::int64_t> corners_;  // add_face's corner indices, kept to save an allocation per face
  bool valid(VH vh) const { return vh.idx() >= 0 && static_cast<std::size_t>(vh.idx()) < soup.vertices.size(); }
};

}  // namespace s2c::io_detail
