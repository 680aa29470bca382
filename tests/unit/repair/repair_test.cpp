// The repair driver and its cleaning/defect steps: inputs with known defects → CAD-ready meshes.
#include <gtest/gtest.h>

#include "s2c/core/check.h"
#include "s2c/repair/defects.h"
#include "s2c/repair/repair.h"
#include "../test_util.h"

namespace s2c::repair {
namespace {

TEST(Repair, CadReadyInputPassesThroughUnchanged) {
  const TriangleSoup s = test::cube(10);
  const RepairResult r = repair_mesh(s);
  EXPECT_TRUE(r.cad_ready);
  EXPECT_EQ(r.path, "unchanged");
  EXPECT_EQ(r.mesh.faces, s.faces);
}

TEST(Repair, SphereWithHolesFlippedAndDuplicateFacesIsRepairedOnTheSurface) {
  TriangleSoup s = test::icosphere({0, 0, 0}, 10, 3);
  const std::size_t n = s.faces.size();
  s.faces.erase(s.faces.begin() + 40, s.faces.begin() + 43);  // a hole
  s.faces.erase(s.faces.begin() + 200);                       // another one
  for (int i = 300; i < 310; ++i) std::swap(s.faces[i][1], s.faces[i][2]);  // a flipped patch
  s.faces.push_back(s.faces[500]);                                          // a duplicate
  const DefectReport before = find_defects(s);
  EXPECT_GT(before.check.boundary_loops, 0u);
  EXPECT_GT(before.check.orientation_conflicts, 0u);
  EXPECT_EQ(before.check.duplicate_faces, 1u);
  const RepairResult r = repair_mesh(s);
  ASSERT_TRUE(r.cad_ready) << r.problem;
  EXPECT_EQ(r.path, "surface");
  EXPECT_GE(r.mesh.faces.size(), n - 4);
  for (const auto& v : r.mesh.vertices) EXPECT_NEAR(v.norm(), 10, 0.6);  // patches stay near the sphere
  EXPECT_TRUE(r.report["defects_after"]["cad_ready"].get<bool>());
  // Each hole in the report says how it was filled and why that way.
  const auto& list = r.report["surface"]["holes"].at(0)["list"];
  ASSERT_GE(list.size(), 2u);
  for (const auto& h : list) {
    EXPECT_TRUE(h["filled"].get<bool>());
    EXPECT_FALSE(h["choice"].get<std::string>().empty()) << h.dump();  // e.g. "3-vertex hole: one triangle"
  }
}

TEST(Repair, OverlappingShellsBecomeOneCadReadySolid) {
  TriangleSoup s;
  test::add_cube(s, {0, 0, 0}, 10);
  test::add_cube(s, {5, 5, 5}, 10);  // intersects the first cube
  EXPECT_GT(find_defects(s).check.self_intersections, 0u);
  const RepairResult r = repair_mesh(s);
  ASSERT_TRUE(r.cad_ready) << r.problem;
  const CheckResult c = check_mesh(r.mesh);
  EXPECT_EQ(c.components, 1u);
  EXPECT_NEAR(c.volume, 2000 - 125, 60);  // the union
}

TEST(Repair, NonManifoldEdgeIsResolved) {
  // Two cubes sharing one edge (cube 2's corners 0 and 4 are cube 1's corners 3 and 7): that
  // edge has four faces.
  TriangleSoup s;
  test::add_cube(s, {0, 0, 0}, 10);
  test::add_cube(s, {10, 10, 0}, 10);
  for (std::size_t f = 12; f < s.faces.size(); ++f)
    for (int& v : s.faces[f]) {
      if (v == 8) v = 3;
      if (v == 12) v = 7;
    }
  EXPECT_GT(find_defects(s).check.nonmanifold_edges, 0u) << to_json(find_defects(s).check);
  const RepairResult r = repair_mesh(s);
  ASSERT_TRUE(r.cad_ready) << r.problem;
  // The faces around the edge are cut out and the figure-eight hole this leaves is patched as one
  // nested hole, which bridges the two cubes with a sliver wedge (at most 1/6 of a cube).
  const double volume = check_mesh(r.mesh).volume;
  EXPECT_GT(volume, 1990);
  EXPECT_LT(volume, 2170);
}

TEST(Repair, SurfaceOnlyStrategyReportsWhatIsLeft) {
  TriangleSoup s;
  test::add_cube(s, {0, 0, 0}, 10);
  test::add_cube(s, {5, 5, 5}, 10);
  RepairOptions o;
  o.strategy = Strategy::surface;
  o.fill_holes = false;
  const RepairResult r = repair_mesh(s, o);
  EXPECT_FALSE(r.cad_ready);
  EXPECT_NE(r.problem.find("--strategy"), std::string::npos) << r.problem;
}

TEST(Repair, VolumetricStrategyWithDualContouringKeepsTheCubeSharp) {
  TriangleSoup s = test::cube(10);
  RepairOptions o;
  o.strategy = Strategy::volumetric;
  o.volumetric.extract = Extract::dc;
  o.volumetric.voxel = 0.37;
  const RepairResult r = repair_mesh(s, o);
  ASSERT_TRUE(r.cad_ready) << r.problem;
  EXPECT_EQ(r.path, "volumetric");
  EXPECT_NEAR(check_mesh(r.mesh).volume, 1000, 5);
  EXPECT_LT(r.mesh.faces.size(), 5000u);  // decimated: flat faces need few triangles
}

TEST(Clean, CavityPointsInwardAndDuplicatesGo) {
  TriangleSoup s;
  test::add_cube(s, {0, 0, 0}, 20, /*inward=*/true);  // outer shell written inside out
  test::add_cube(s, {5, 5, 5}, 10);                   // cavity written outward
  s.faces.push_back(s.faces[0]);
  const CleanStats st = clean(s);
  EXPECT_EQ(st.duplicate_faces_removed, 1u);
  EXPECT_EQ(st.faces_flipped, 24u);
  const CheckResult c = check_mesh(s);
  EXPECT_TRUE(c.cad_ready) << to_json(c);
  EXPECT_NEAR(c.volume, 8000 - 1000, 1e-9);
}

TEST(Defects, CountsNeedlesCapsZeroAreaAndTinyComponents) {
  TriangleSoup s = test::cube(10);
  const int b = static_cast<int>(s.vertices.size());
  s.vertices.insert(s.vertices.end(), {{20, 0, 0}, {30, 0, 0}, {40, 0, 0},        // zero area
                                       {20, 5, 0}, {30, 5, 0}, {20, 5.001, 0.05},  // needle
                                       {20, 9, 0}, {30, 9, 0}, {25, 9.05, 0}});    // cap
  s.faces.push_back({b, b + 1, b + 2});
  s.faces.push_back({b + 3, b + 4, b + 5});
  s.faces.push_back({b + 6, b + 7, b + 8});
  const DefectReport d = find_defects(s, false);
  EXPECT_EQ(d.zero_area_faces, 1u);
  EXPECT_EQ(d.needles, 1u);
  EXPECT_EQ(d.caps, 1u);
  EXPECT_EQ(d.tiny_components, 3u);
}

TEST(Repair, EmptyInputIsRejected) {
  test::expect_invalid_input([] { repair_mesh(TriangleSoup{}); }, {"no faces"});
}

}  // namespace
}  // namespace s2c::repair
