// Feature-preserving decimation with OpenMesh's Decimater: quadric error (Garland & Heckbert)
// bounded by a distance, so sharp edges (where planes meet) keep their vertices, and no collapse
// that turns a face normal by more than 15° (no flips, no folds).
#include <algorithm>
#include <array>
#include <vector>

#include <OpenMesh/Core/Utils/vector_traits.hh>  // before QuadricT.hh, which uses it undeclared
#include <OpenMesh/Core/Geometry/QuadricT.hh>
#include <OpenMesh/Tools/Decimater/DecimaterT.hh>
#include <OpenMesh/Tools/Decimater/ModAspectRatioT.hh>
#include <OpenMesh/Tools/Decimater/ModNormalFlippingT.hh>

#include "s2c/repair/repair.h"

namespace s2c::repair {
namespace {

/// The mesh the Decimater runs on: the Decimater's templates call is_collapse_ok on the mesh
/// type they are given, so this one's hides the library's (the same test, compiled here:
/// collapse_keeps_topology).
struct DecimationMesh : Mesh {
  bool is_collapse_ok(HalfedgeHandle h) const { return collapse_keeps_topology(*this, h); }
};

/// Garland–Heckbert quadrics with one unit-weight plane per face, bounded by the squared
/// tolerance: the error of a collapse is the sum of squared distances from the merged vertex to
/// every plane its two vertices have absorbed, so a legal collapse leaves each of those planes
/// within the tolerance (conservative: k planes at once may each be within tolerance / √k only).
/// OpenMesh's ModQuadricT weights each plane by its face's area, which makes the bound mm⁴
/// against mm²: the distance allowed depends on the mesh's scale (on a sphere of radius 2 mm with
/// faces of 0.003 mm², faces ended 3.8 tolerances deep; see the unit tests).
///
/// The error is clamped at zero: within a plane it is zero in exact arithmetic but vᵀQv rounds
/// to ±1e-26, and the Decimater takes any negative priority for an illegal collapse. On a flat
/// face about half the collapses were refused by the sign of their rounding error, and which half
/// decided where the greedy decimation got stuck: the plate's repaired mesh ended at 5,490 to
/// 39,906 faces for voxels one ulp apart (6,082 to 6,138 now).
template <class MeshT>
class ModPlaneDistanceT : public OpenMesh::Decimater::ModBaseT<MeshT> {
 public:
  DECIMATING_MODULE(ModPlaneDistanceT, MeshT, PlaneDistance);
  explicit ModPlaneDistanceT(MeshT& mesh) : Base(mesh, false) { Base::mesh().add_property(quadric_); }
  ~ModPlaneDistanceT() override { Base::mesh().remove_property(quadric_); }

  /// Largest distance (mm) a collapse may leave between the merged vertex and any of its planes.
  void set_tolerance(double tolerance) { max_error_ = tolerance * tolerance; }

  void initialize() override {
    MeshT& m = Base::mesh();
    for (auto v : m.vertices()) m.property(quadric_, v).clear();
    for (auto f : m.faces()) {
      std::array<typename MeshT::VertexHandle, 3> corner;
      int k = 0;
      for (auto v : m.fv_range(f)) corner[k++] = v;
      const auto& p = m.point(corner[0]);
      const auto e1 = m.point(corner[1]) - p, e2 = m.point(corner[2]) - p;
      auto n = e1 % e2;
      const double length = n.norm();
      // A face whose normal is rounding (zero area to 1e-12 of its longest edge squared) has no
      // plane: at full weight a plane at an arbitrary angle would block collapses around it.
      const double longest2 = std::max({e1.sqrnorm(), e2.sqrnorm(), (e2 - e1).sqrnorm()});
      if (!(length > 1e-12 * longest2)) continue;
      n /= length;
      const OpenMesh::Geometry::Quadricd plane(n[0], n[1], n[2], -(p | n));
      for (auto v : corner) m.property(quadric_, v) += plane;
    }
  }

  float collapse_priority(const CollapseInfo& ci) override {
    const MeshT& m = Base::mesh();
    auto q = m.property(quadric_, ci.v0);
    q += m.property(quadric_, ci.v1);
    const double error = q(ci.p1);
    if (!(error < max_error_)) return float(Base::ILLEGAL_COLLAPSE);
    return error > 0 ? float(error) : 0.0f;
  }

  void postprocess_collapse(const CollapseInfo& ci) override {
    MeshT& m = Base::mesh();
    m.property(quadric_, ci.v1) += m.property(quadric_, ci.v0);
  }

 private:
  double max_error_ = 0;
  OpenMesh::VPropHandleT<OpenMesh::Geometry::Quadricd> quadric_;
};

}  // namespace

// The conditions, for v0 → v1 along h: the edge and both vertices alive; neither triangle beside
// the edge with both its other edges on the boundary; two different opposite vertices vl and vr;
// no common neighbour of v0 and v1 but vl and vr; no interior edge between two boundary
// vertices. In libOpenMeshCore each status flag read checks the property's type by building and
// comparing its name (a malloc and a memcmp): 21 % of a volumetric repair's time went to that
// inside is_collapse_ok (plate, dual contouring at 320 cells).
bool collapse_keeps_topology(const Mesh& m, Mesh::HalfedgeHandle h) {
  if (m.status(m.edge_handle(h)).deleted()) return false;
  const Mesh::HalfedgeHandle o = m.opposite_halfedge_handle(h);
  const Mesh::VertexHandle v0 = m.to_vertex_handle(o), v1 = m.to_vertex_handle(h);
  if (m.status(v0).deleted() || m.status(v1).deleted()) return false;
  // The far vertex of the triangle on halfedge a's side (none on a boundary side); false when that
  // triangle's two other edges are both boundary edges (the collapse would leave it dangling).
  auto side = [&](Mesh::HalfedgeHandle a, Mesh::VertexHandle& apex) {
    if (m.is_boundary(a)) return true;
    const Mesh::HalfedgeHandle n1 = m.next_halfedge_handle(a), n2 = m.next_halfedge_handle(n1);
    apex = m.to_vertex_handle(n1);
    return !(m.is_boundary(m.opposite_halfedge_handle(n1)) && m.is_boundary(m.opposite_halfedge_handle(n2)));
  };
  Mesh::VertexHandle vl, vr;
  if (!side(h, vl) || !side(o, vr) || vl == vr) return false;
  thread_local std::vector<Mesh::VertexHandle> ring1;
  ring1.clear();
  for (Mesh::ConstVertexVertexIter it = m.cvv_iter(v1); it.is_valid(); ++it) ring1.push_back(*it);
  for (Mesh::ConstVertexVertexIter it = m.cvv_iter(v0); it.is_valid(); ++it)
    if (*it != vl && *it != vr && std::find(ring1.begin(), ring1.end(), *it) != ring1.end()) return false;
  return !(m.is_boundary(v0) && m.is_boundary(v1) && !m.is_boundary(h) && !m.is_boundary(o));
}

std::size_t decimate(TriangleSoup& soup, double tolerance, const std::vector<char>* locked, double max_aspect) {
  if (!(tolerance > 0) || soup.faces.empty()) return 0;
  DecimationMesh mesh;
  soup_to_mesh(soup, mesh);
  mesh.update_face_normals();
  // soup_to_mesh keeps vertex indices (duplicates for non-manifold corners come after them).
  if (locked)
    for (std::size_t v = 0; v < locked->size() && v < mesh.n_vertices(); ++v)
      if ((*locked)[v]) mesh.status(Mesh::VertexHandle(static_cast<int>(v))).set_locked(true);
  using Decimater = OpenMesh::Decimater::DecimaterT<DecimationMesh>;
  Decimater dec(mesh);
  ModPlaneDistanceT<DecimationMesh>::Handle distance;
  OpenMesh::Decimater::ModNormalFlippingT<DecimationMesh>::Handle flipping;
  OpenMesh::Decimater::ModAspectRatioT<DecimationMesh>::Handle aspect;
  dec.add(distance);
  dec.add(flipping);
  dec.add(aspect);
  // Non-binary: the quadric is the priority; collapses beyond the bound are illegal.
  dec.module(distance).set_tolerance(tolerance);
  dec.module(flipping).set_max_normal_deviation(15.0);
  dec.module(aspect).set_aspect_ratio(max_aspect);
  if (!dec.initialize()) return 0;
  const std::size_t before = mesh.n_faces();
  dec.decimate();
  mesh.garbage_collection();
  soup = mesh_to_soup(mesh);
  return before - mesh.n_faces();
}

}  // namespace s2c::repair
