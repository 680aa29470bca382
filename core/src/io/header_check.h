#pragma once
// Checks of a mesh file's header against its size, made before any reader allocates or loops
// on header counts: a count the file cannot hold is an error, not an allocation.
#include <cstdint>
#include <filesystem>
#include <optional>

#include "s2c/core/io.h"

namespace s2c::io_detail {

struct DeclaredCounts {
  std::optional<std::uint64_t> vertices, faces;  // what the header promises, if it has counts
  bool binary = false;
};

/// \throw InvalidInput naming the file: bad magic, malformed header, counts the file cannot hold,
///        truncated binary data.
DeclaredCounts check_header(const std::filesystem::path& path, MeshFormat format);

/// Replaces OpenMesh's float coordinates by the file's full-precision values (the text formats)
/// when they provably describe the same vertices; otherwise leaves them.
void refine_coordinates(const std::filesystem::path& path, MeshFormat format, TriangleSoup& soup);

/// Legacy VTK (ASCII POLYDATA) reader; OpenMesh has none. \throw InvalidInput with the line.
TriangleSoup read_vtk(const std::filesystem::path& path);

}  // namespace s2c::io_detail
