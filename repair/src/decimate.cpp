// Feature-preserving decimation with OpenMesh's Decimater: quadric error (Garland & Heckbert)
// bounded by a distance, so sharp edges (where planes meet) keep their vertices, and no collapse
// that turns a face normal by more than 45° (no flips, no folds).
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>
#include <OpenMesh/Tools/Decimater/ModQuadricT.hh>

#include "s2c/repair/repair.h"

namespace s2c::repair {

std::size_t decimate(TriangleSoup& soup, double tolerance, const std::vector<char>* locked) {
  if (!(tolerance > 0) || soup.faces.empty()) return 0;
  Mesh mesh;
  soup_to_mesh(soup, mesh);
  mesh.update_face_normals();
  // soup_to_mesh keeps vertex indices (duplicates for non-manifold corners come after them).
  if (locked)
    for (std::size_t v = 0; v < locked->size() && v < mesh.n_vertices(); ++v)
      if ((*locked)[v]) mesh.status(Mesh::VertexHandle(static_cast<int>(v))).set_locked(true);
  using Decimater = OpenMesh::Decimater::DecimaterT<Mesh>;
  Decimater dec(mesh);
  OpenMesh::Decimater::ModQuadricT<Mesh>::Handle quadric;
  OpenMesh::Decimater::ModNormalFlippingT<Mesh>::Handle flipping;
  OpenMesh::Decimater::ModAspectRatioT<Mesh>::Handle aspect;
  dec.add(quadric);
  dec.add(flipping);
  dec.add(aspect);
  // Non-binary: the quadric is the priority; collapses beyond the bound are illegal.
  dec.module(quadric).set_max_err(tolerance * tolerance, false);  // squared distance to the planes
  dec.module(flipping).set_max_normal_deviation(15.0);
  dec.module(aspect).set_aspect_ratio(8.0);
  if (!dec.initialize()) return 0;
  const std::size_t before = mesh.n_faces();
  dec.decimate();
  mesh.garbage_collection();
  soup = mesh_to_soup(mesh);
  return before - mesh.n_faces();
}

}  // namespace s2c::repair
