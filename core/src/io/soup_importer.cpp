#include "soup_importer.h"

#include <fmt/format.h>

namespace s2c::io_detail {

void add_polygon(TriangleSoup& soup, const std::int64_t* idx, std::size_t n, std::size_t vertex_count, std::size_t face_no,
                 std::string& first_error) {
  for (std::size_t k = 0; k < n; ++k) {
    if (idx[k] < 0 || static_cast<std::uint64_t>(idx[k]) >= vertex_count) {
      if (first_error.empty())
        first_error = fmt::format("face {} refers to vertex {}, but the file has {} vertices (indices 0..{})", face_no,
                                  idx[k], vertex_count, static_cast<long long>(vertex_count) - 1);
      ++soup.faces_dropped;
      return;
    }
  }
  if (n < 3) {
    if (first_error.empty()) first_error = fmt::format("face {} has {} corners; a face needs at least 3", face_no, n);
    ++soup.faces_dropped;
    return;
  }
  if (n > 3) ++soup.polygons_triangulated;
  // Fan triangulation keeps every input corner; triangles with a repeated corner carry no
  // area and are counted instead of stored.
  for (std::size_t k = 1; k + 1 < n; ++k) {
    const std::array<int, 3> f{static_cast<int>(idx[0]), static_cast<int>(idx[k]), static_cast<int>(idx[k + 1])};
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
      ++soup.faces_dropped;
      continue;
    }
    soup.faces.push_back(f);
  }
}

OpenMesh::FaceHandle SoupImporter::add_face(const VHandles& idx) {
  const std::size_t face_no = face_records++;
  corners_.clear();
  for (const VH& vh : idx) corners_.push_back(vh.idx());
  const std::size_t before = soup.faces.size();
  add_polygon(soup, corners_.data(), corners_.size(), soup.vertices.size(), face_no, first_error);
  return soup.faces.size() > before ? FH(static_cast<int>(soup.faces.size()) - 1) : FH();
}

}  // namespace s2c::io_detail
