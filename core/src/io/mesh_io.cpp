#include "s2c/core/io.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <fstream>

#include <OpenMesh/Core/IO/MeshIO.hh>
#include <fmt/format.h>

#include "binary_ply.h"
#include "header_check.h"
#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "soup_importer.h"

namespace fs = std::filesystem;

namespace s2c {
namespace {

void silence_openmesh() {
  // OpenMesh prints its own diagnostics to stderr; ours name the file and the problem instead.
  static const bool once = [] {
    omerr().disable();
    omlog().disable();
    omout().disable();
    return true;
  }();
  (void)once;
}

void validate_soup(const fs::path& path, const TriangleSoup& soup, const io_detail::DeclaredCounts& declared,
                   std::size_t face_records, bool allow_empty) {
  if (declared.vertices && soup.vertices.size() != *declared.vertices)
    throw InvalidInput(fmt::format("{}: truncated or malformed: the header declares {} vertices but {} could be read",
                                   path.string(), *declared.vertices, soup.vertices.size()));
  if (declared.faces && face_records != *declared.faces && !declared.binary)
    throw InvalidInput(fmt::format("{}: truncated or malformed: the header declares {} faces but {} could be read",
                                   path.string(), *declared.faces, face_records));
  for (std::size_t i = 0; i < soup.vertices.size(); ++i)
    if (!soup.vertices[i].allFinite())
      throw InvalidInput(fmt::format("{}: vertex {} has a non-finite coordinate ({}, {}, {})", path.string(), i,
                                     soup.vertices[i].x(), soup.vertices[i].y(), soup.vertices[i].z()));
  if (soup.faces.empty() && !allow_empty)
    throw InvalidInput(fmt::format("{}: the mesh has no faces ({} vertices){}", path.string(), soup.vertices.size(),
                                   soup.vertices.empty() ? "" : "; is it a point cloud?"));
}

}  // namespace

MeshFormat mesh_format(const fs::path& path) {
  std::string ext = path.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), [](unsigned char c) { return std::tolower(c); });
  if (ext == ".ply") return MeshFormat::ply;
  if (ext == ".stl") return MeshFormat::stl;
  if (ext == ".obj") return MeshFormat::obj;
  if (ext == ".off") return MeshFormat::off;
  if (ext == ".vtk") return MeshFormat::vtk;
  throw InvalidInput(fmt::format("{}: unknown mesh extension '{}' (use .ply, .stl, .obj or .off)", path.string(), ext));
}

std::size_t estimated_faces(const fs::path& path) {
  std::error_code ec;
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) return 0;
  MeshFormat format;
  try {
    format = mesh_format(path);
  } catch (const InvalidInput&) {
    return 0;
  }
  std::ifstream in(path, std::ios::binary);
  char head[512] = {};
  in.read(head, sizeof head);
  const std::string start(head, static_cast<std::size_t>(in.gcount()));
  // Bytes per face, with the vertex records shared out (a closed mesh has half as many vertices
  // as faces): binary PLY 12–24 per vertex (with normals) and 13 per face; binary STL 50 per
  // face; text 25–40 per vertex line and 15–25 per face line; ASCII STL about 250 per facet.
  double bytes_per_face = 40;
  if (format == MeshFormat::ply && start.find("format ascii") == std::string::npos) bytes_per_face = 22;
  if (format == MeshFormat::stl) bytes_per_face = start.rfind("solid", 0) == 0 && start.find("facet") != std::string::npos ? 250 : 50;
  return static_cast<std::size_t>(static_cast<double>(size) / bytes_per_face);
}

void check_mesh_header(const fs::path& path) { io_detail::check_header(path, mesh_format(path)); }

TriangleSoup read_soup(const fs::path& path, bool allow_empty) {
  silence_openmesh();
  const MeshFormat format = mesh_format(path);
  const io_detail::DeclaredCounts declared = io_detail::check_header(path, format);
  if (format == MeshFormat::vtk) {
    TriangleSoup soup = io_detail::read_vtk(path);
    validate_soup(path, soup, {}, soup.faces.size(), allow_empty);
    return soup;
  }
  // Binary PLY, what the stages write and scanners export: our reader (binary_ply.h says why).
  io_detail::PlyHeader ply;
  if (format == MeshFormat::ply && declared.binary && io_detail::read_ply_header(path, ply)) {
    std::size_t face_records = 0;
    TriangleSoup soup = io_detail::read_binary_ply(path, ply, face_records);
    validate_soup(path, soup, declared, face_records, allow_empty);
    return soup;
  }
  io_detail::SoupImporter importer;
  OpenMesh::IO::Options opt = OpenMesh::IO::Options::VertexNormal;
  if (!OpenMesh::IO::IOManager().read(path.string(), importer, opt))
    throw InvalidInput(fmt::format("{}: {}", path.string(),
                                   importer.first_error.empty() ? "malformed file (the reader rejected it)" : importer.first_error));
  if (!importer.first_error.empty()) throw InvalidInput(fmt::format("{}: {}", path.string(), importer.first_error));
  TriangleSoup soup = std::move(importer.soup);
  io_detail::refine_coordinates(path, format, soup);
  if (!soup.normals.empty()) soup.normals.resize(soup.vertices.size(), Eigen::Vector3d::Zero());
  validate_soup(path, soup, declared, importer.face_records, allow_empty);
  return soup;
}

Mesh read_mesh(const fs::path& path) {
  Mesh mesh;
  read_mesh(path, mesh);
  return mesh;
}

void read_mesh(const fs::path& path, Mesh& mesh) { soup_to_mesh(read_soup(path), mesh); }

namespace {

/// Writes `mesh` as it is to `path` in `format`; `normals` says whether its vertex normals are to
/// be written (they are current then).
void write_as_is(const Mesh& mesh, const fs::path& path, MeshFormat format, const WriteOptions& options, bool normals) {
  OpenMesh::IO::Options opt;
  if (options.binary && (format == MeshFormat::ply || format == MeshFormat::stl)) {
    opt += OpenMesh::IO::Options::Binary;
    opt += OpenMesh::IO::Options::LSB;
  }
  if (normals) opt += OpenMesh::IO::Options::VertexNormal;
  AtomicFile out(path);
  if (!OpenMesh::IO::write_mesh(mesh, out.temp_path().string(), opt))
    throw IoError(fmt::format("{}: writing failed (disk full or not writable?)", path.string()));
  out.commit();
}

/// The format `path` is written in. \throw InvalidInput for formats that cannot be written.
MeshFormat writable_format(const fs::path& path) {
  silence_openmesh();
  const MeshFormat format = mesh_format(path);
  if (format == MeshFormat::vtk) throw InvalidInput(fmt::format("{}: writing .vtk is not supported", path.string()));
  return format;
}

bool wants_normals(MeshFormat format, const WriteOptions& options) {
  return options.vertex_normals && format != MeshFormat::stl;
}

}  // namespace

void write_mesh(const Mesh& mesh, const fs::path& path, const WriteOptions& options) {
  const MeshFormat format = writable_format(path);
  if (!wants_normals(format, options)) return write_as_is(mesh, path, format, options, false);
  Mesh with_normals = mesh;
  with_normals.update_normals();
  write_as_is(with_normals, path, format, options, true);
}

void write_mesh(Mesh&& mesh, const fs::path& path, const WriteOptions& options) {
  const MeshFormat format = writable_format(path);
  const bool normals = wants_normals(format, options);
  if (normals) mesh.update_normals();
  write_as_is(mesh, path, format, options, normals);
}

// ---------------------------------------------------------------------------------------------

std::size_t soup_to_mesh(const TriangleSoup& soup, Mesh& mesh) {
  mesh.clear();
  // 3F/2 edges when closed, more with boundaries (an open scan surface); beyond its capacity the
  // edge array would double (a reserve only costs address space until it is written).
  mesh.reserve(soup.vertices.size(), soup.faces.size() * 7 / 4 + 64, soup.faces.size());
  std::vector<Mesh::VertexHandle> vh(soup.vertices.size());
  for (std::size_t i = 0; i < soup.vertices.size(); ++i) vh[i] = mesh.add_vertex(to_om(soup.vertices[i]));
  if (!soup.normals.empty())
    for (std::size_t i = 0; i < soup.vertices.size(); ++i) mesh.set_normal(vh[i], to_om(soup.normals[i]));
  std::size_t duplicated = 0;
  for (const auto& f : soup.faces) {
    std::array<Mesh::VertexHandle, 3> h{vh[f[0]], vh[f[1]], vh[f[2]]};
    if (mesh.add_face(h[0], h[1], h[2]).is_valid()) continue;
    // A complex edge or a non-manifold vertex: keep the face on its own copies of the
    // vertices so nothing is lost; repair merges them back where it can.
    for (auto& x : h) {
      const Mesh::Point p = mesh.point(x);  // a copy: add_vertex may reallocate the points it refers to
      x = mesh.add_vertex(p);
    }
    mesh.add_face(h[0], h[1], h[2]);
    ++duplicated;
  }
  return duplicated;
}

TriangleSoup mesh_to_soup(const Mesh& mesh) {
  TriangleSoup soup;
  std::vector<int> index(mesh.n_vertices(), -1);
  for (auto v : mesh.vertices()) {
    index[v.idx()] = static_cast<int>(soup.vertices.size());
    soup.vertices.push_back(to_eigen(mesh.point(v)));
  }
  for (auto f : mesh.faces()) {
    std::array<int, 3> t{};
    int k = 0;
    for (auto v : f.vertices()) t[k++] = index[v.idx()];
    soup.faces.push_back(t);
  }
  return soup;
}

double median_edge_length(const TriangleSoup& mesh) {
  std::vector<double> lengths;
  const std::size_t stride = std::max<std::size_t>(1, mesh.faces.size() / 20000);
  for (std::size_t f = 0; f < mesh.faces.size(); f += stride) {
    const auto& t = mesh.faces[f];
    for (int k = 0; k < 3; ++k) lengths.push_back((mesh.vertices[t[k]] - mesh.vertices[t[(k + 1) % 3]]).norm());
  }
  if (lengths.empty()) return 0;
  std::nth_element(lengths.begin(), lengths.begin() + lengths.size() / 2, lengths.end());
  return lengths[lengths.size() / 2];
}

Bounds bounds(const TriangleSoup& soup) {
  Bounds b;
  bool first = true;
  for (const auto& f : soup.faces)
    for (int i : f) {
      const auto& p = soup.vertices[i];
      if (first) { b.min = b.max = p; first = false; }
      b.min = b.min.cwiseMin(p);
      b.max = b.max.cwiseMax(p);
    }
  return b;
}

Bounds bounds(const Mesh& mesh) {
  Bounds b;
  bool first = true;
  for (auto v : mesh.vertices()) {
    const Eigen::Vector3d p = to_eigen(mesh.point(v));
    if (first) { b.min = b.max = p; first = false; }
    b.min = b.min.cwiseMin(p);
    b.max = b.max.cwiseMax(p);
  }
  return b;
}

}  // namespace s2c
