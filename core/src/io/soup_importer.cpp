#include "soup_importer.h"

#include <fmt/format.h>

namespace s2c::io_detail {

OpenMesh::FaceHandle SoupImporter::add_face(const VHandles& idx) {
  const std::size_t face_no = face_records++;
  for (const VH& vh : idx) {
    if (!valid(vh)) {
      if (first_error.empty())
        first_error = fmt::format("face {} refers to vertex {}, but the file has {} vertices (indices 0..{})",
                                  face_no, vh.idx(), soup.vertices.size(),
                                  static_cast<long long>(soup.vertices.size()) - 1);
      ++soup.faces_dropped;
      return FH();
    }
  }
  if (idx.size() < 3) {
    if (first_error.empty()) first_error = fmt::format("face {} has {} corners; a face needs at least 3", face_no, idx.size());
    ++soup.faces_dropped;
    return FH();
  }
  if (idx.size() > 3) ++soup.polygons_triangulated;
  // Fan triangulation keeps every input corner; triangles with a repeated corner carry no
  // area and are counted instead of stored.
  for (std::size_t k = 1; k + 1 < idx.size(); ++k) {
    std::array<int, 3> f{idx[0].idx(), idx[k].idx(), idx[k + 1].idx()};
    if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) {
      ++soup.faces_dropped;
      continue;
    }
    soup.faces.push_back(f);
  }
  return FH(static_cast<int>(soup.faces.size()) - 1);
}

}  // namespace s2c::io_detail
