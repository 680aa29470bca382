#pragma once
// A reader of binary PLY bodies straight into a TriangleSoup. OpenMesh's PLY reader reads one
// value at a time, through a virtual importer call and an istream read each, and narrows
// coordinates to float (so a second pass had to read doubles again): 0.36 s for the 1.9 M faces
// of a million-vertex mesh whose analysis takes 2 s. This walks the records in one buffered pass:
// 0.08 s (bench/README, "the binary PLY reader"). ASCII PLY and the other formats still go
// through OpenMesh, which also reads fewer layouts (no ushort list lengths, for one).
#include <filesystem>

#include "ply_header.h"
#include "s2c/core/mesh.h"

namespace s2c::io_detail {

/// The vertices (x, y, z as the file has them, of any numeric type; nx, ny, nz when all three
/// are present), and the faces of the first "vertex" and "face" elements of a binary PLY whose
/// header is `header` (either byte order); other elements and properties are skipped. Faces come
/// from the list "vertex_indices" (or "vertex_index"), fan-triangulated as SoupImporter does.
/// `face_records` receives the number of face records.
/// \throw InvalidInput naming the file and the record: data ending inside a record, a face
///        with fewer than three corners or a corner that is no vertex.
TriangleSoup read_binary_ply(const std::filesystem::path& path, const PlyHeader& header, std::size_t& face_records);

}  // namespace s2c::io_detail
