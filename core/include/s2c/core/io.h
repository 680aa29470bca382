#pragma once
/// \file Reading and writing meshes by extension (.ply .stl .obj .off, and legacy .vtk for reading),
/// with the validation OpenMesh's readers do not do, and atomic output.
#include <filesystem>
#include <string>

#include "s2c/core/mesh.h"

namespace s2c {

enum class MeshFormat { ply, stl, obj, off, vtk };

/// The format implied by a file's extension (case-insensitive).
/// \throw InvalidInput naming the file when the extension is not a mesh format.
MeshFormat mesh_format(const std::filesystem::path& path);

/// Reads every face and vertex of a mesh file as stored (STL vertices welded by exact position;
/// polygons fan-triangulated; unreferenced vertices kept).
/// \throw InvalidInput naming the file and the problem: unknown extension, truncated data,
///        NaN/inf coordinates, face indices out of range, header counts the file cannot hold,
///        no faces at all (unless allow_empty).
/// \throw IoError when the file cannot be opened.
TriangleSoup read_soup(const std::filesystem::path& path, bool allow_empty = false);

/// About how many faces a mesh file holds, from its size and format alone (binary or text is told
/// from its first bytes), for sizing memory before reading it: within a factor of about two on
/// ordinary files, 0 for a file that cannot be opened or an unknown extension. Never throws.
std::size_t estimated_faces(const std::filesystem::path& path);

/// Checks a mesh or cloud file's header against its size before any reader allocates on its
/// counts (what read_soup does first; clouds read by other libraries need it too).
/// \throw InvalidInput naming the file: bad magic, malformed header, counts the file cannot hold.
void check_mesh_header(const std::filesystem::path& path);

/// Checks a PCD header (fields, sizes, types, counts, width × height = points, data kind) against
/// the file's size. \throw InvalidInput naming the file and the header line.
void check_pcd_header(const std::filesystem::path& path);

/// read_soup followed by soup_to_mesh.
Mesh read_mesh(const std::filesystem::path& path);
/// The same into `mesh` (empty): an OpenMesh mesh has no move assignment, so `m = read_mesh(p)`
/// on a mesh declared earlier copies all of it (at a million vertices: 49 MB more peak, 24 k more
/// page faults).
void read_mesh(const std::filesystem::path& path, Mesh& mesh);

struct WriteOptions {
  bool binary = true;          ///< PLY and STL: binary little-endian (ASCII otherwise)
  bool vertex_normals = true;  ///< PLY/OBJ/OFF: write per-vertex normals (computed if absent)
};

/// Writes atomically (temporary file + rename in the target folder): a failed or killed write
/// leaves no partial file. \throw IoError on failure, InvalidInput for an unknown extension.
void write_mesh(const Mesh& mesh, const std::filesystem::path& path, const WriteOptions& options = {});
/// The same for a mesh the caller is done with: its vertex normals are computed in place rather
/// than on a copy (a copy of a scan's mesh was the reconstruct stage's memory peak).
void write_mesh(Mesh&& mesh, const std::filesystem::path& path, const WriteOptions& options = {});

}  // namespace s2c
