// scan2cad check: meshes with known answers, and agreement with independent checkers on the
// real meshes of ../shared/data/real (its manifest's topology counts, CGAL's self-intersections).
#include <cstdio>
#include <fstream>

#include <nlohmann/json.hpp>

#include "../test_util.h"
#include "s2c/core/check.h"
#include "s2c/core/io.h"

namespace fs = std::filesystem;
using namespace s2c;
using nlohmann::json;

TEST(Check, ClosedCubeIsCadReady) {
  const auto r = check_mesh(test::cube(10));
  EXPECT_TRUE(r.closed);
  EXPECT_TRUE(r.oriented);
  EXPECT_TRUE(r.cad_ready) << ::testing::PrintToString(r.problems);
  EXPECT_EQ(r.boundary_loops, 0u);
  EXPECT_EQ(r.components, 1u);
  EXPECT_EQ(r.self_intersections, 0u);
  EXPECT_NEAR(r.volume, 1000.0, 1e-9);
  EXPECT_NEAR(r.area, 600.0, 1e-9);
}

TEST(Check, CubeWithAHoleHasOneBoundaryLoop) {
  auto s = test::cube(10);
  s.faces.erase(s.faces.begin(), s.faces.begin() + 2);  // remove the bottom square
  const auto r = check_mesh(s);
  EXPECT_FALSE(r.closed);
  EXPECT_EQ(r.boundary_loops, 1u);
  EXPECT_EQ(r.boundary_edges, 4u);
  EXPECT_FALSE(r.cad_ready);
}

TEST(Check, TwoCubesSharingAnEdgeAreNonManifold) {
  TriangleSoup s = test::cube(10);
  test::add_cube(s, Eigen::Vector3d(10, 10, 0), 10);
  // Weld the second cube's vertices onto the first where they coincide (the shared z edge).
  for (auto& f : s.faces)
    for (int& v : f)
      for (int w = 0; w < 8; ++w)
        if (v >= 8 && s.vertices[v] == s.vertices[w]) v = w;
  const auto r = check_mesh(s);
  EXPECT_EQ(r.nonmanifold_edges, 1u);
  EXPECT_FALSE(r.closed);
  EXPECT_FALSE(r.cad_ready);
  EXPECT_EQ(r.components, 1u);
}

TEST(Check, TwoCubesSharingAVertexHaveANonManifoldVertex) {
  TriangleSoup s = test::cube(10);
  test::add_cube(s, Eigen::Vector3d(10, 10, 10), 10);
  for (auto& f : s.faces)
    for (int& v : f)
      if (v == 8) v = 7;  // the second cube's lowest corner is the first's highest
  const auto r = check_mesh(s);
  EXPECT_EQ(r.nonmanifold_vertices, 1u);
  EXPECT_EQ(r.nonmanifold_edges, 0u);
  EXPECT_FALSE(r.cad_ready);
}

TEST(Check, OverlappingCubesSelfIntersect) {
  TriangleSoup s = test::cube(10);
  test::add_cube(s, Eigen::Vector3d(5, 5, 5), 10);
  const auto r = check_mesh(s);
  EXPECT_GT(r.self_intersections, 0u);
  EXPECT_EQ(r.components, 2u);
  EXPECT_FALSE(r.cad_ready);
  // Separate cubes do not.
  TriangleSoup apart = test::cube(10);
  test::add_cube(apart, Eigen::Vector3d(20, 0, 0), 10);
  EXPECT_EQ(check_mesh(apart).self_intersections, 0u);
  EXPECT_TRUE(check_mesh(apart).cad_ready);
}

TEST(Check, TwoTrianglesCrossing) {
  TriangleSoup s;
  s.vertices = {{0, 0, 0}, {2, 0, 0}, {0, 2, 0}, {0.5, 0.5, -1}, {0.5, 0.5, 1}, {1.5, 1.5, 0}};
  s.faces = {{0, 1, 2}, {3, 4, 5}};
  const auto r = check_mesh(s);
  EXPECT_EQ(r.self_intersections, 1u);
  EXPECT_EQ(r.self_intersecting_faces, 2u);
}

TEST(Check, InwardCubeIsNotOriented) {
  TriangleSoup s;
  test::add_cube(s, Eigen::Vector3d::Zero(), 10, /*inward=*/true);
  const auto r = check_mesh(s);
  EXPECT_TRUE(r.closed);
  EXPECT_FALSE(r.oriented);
  EXPECT_FALSE(r.cad_ready);
}

TEST(Check, OneFlippedFaceIsAnOrientationConflict) {
  auto s = test::cube(10);
  std::swap(s.faces[3][1], s.faces[3][2]);
  const auto r = check_mesh(s);
  EXPECT_EQ(r.orientation_conflicts, 3u);
  EXPECT_FALSE(r.oriented);
}

TEST(Check, HollowPartWithInwardCavityIsCadReady) {
  TriangleSoup s = test::cube(30);
  test::add_cube(s, Eigen::Vector3d(10, 10, 10), 10, /*inward=*/true);
  const auto r = check_mesh(s);
  EXPECT_TRUE(r.oriented);
  EXPECT_TRUE(r.cad_ready) << ::testing::PrintToString(r.problems);
  EXPECT_NEAR(r.volume, 27000.0 - 1000.0, 1e-6);
}

TEST(Check, DegenerateAndDuplicateFaces) {
  auto s = test::cube(10);
  s.faces.push_back(s.faces[0]);
  s.vertices.push_back({5, 0, 0});  // on the edge 0-1: a zero-area sliver
  s.faces.push_back({0, 1, static_cast<int>(s.vertices.size()) - 1});
  const auto r = check_mesh(s);
  EXPECT_EQ(r.duplicate_faces, 1u);
  EXPECT_EQ(r.degenerate_faces, 1u);
  EXPECT_FALSE(r.cad_ready);
}

TEST(Check, JsonHasTheKeysOfTheDesign) {
  const json j = json::parse(to_json(check_mesh(test::cube())));
  for (const char* k : {"closed", "boundary_loops", "nonmanifold_edges", "nonmanifold_vertices", "components",
                        "self_intersections", "degenerate_faces", "oriented", "cad_ready"})
    EXPECT_TRUE(j.contains(k)) << k;
}

// ---------------------------------------------------------------------------------------------
// Agreement with independent checkers on real meshes.

namespace {

std::vector<fs::path> real_meshes() {
  std::vector<fs::path> out;
  const fs::path real = test::shared_dir() / "data/real";
  for (const char* sub : {"defective", "cad"}) {
    if (!fs::exists(real / sub)) continue;
    for (const auto& e : fs::directory_iterator(real / sub)) {
      const std::string name = e.path().filename().string(), ext = e.path().extension().string();
      if (name.find("_points") != std::string::npos || ext == ".txt" || ext == ".xyzc") continue;
      out.push_back(e.path());
    }
  }
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

TEST(Check, AgreesWithTheRealDataManifestOnTopology) {
  const fs::path manifest_path = test::shared_dir() / "data/real/manifest.json";
  if (!fs::exists(manifest_path)) GTEST_SKIP() << "no manifest";
  std::ifstream in(manifest_path);
  const json files = json::parse(in)["files"];
  int compared = 0;
  for (const auto& p : real_meshes()) {
    const std::string key = p.parent_path().filename().string() + "/" + p.filename().string();
    ASSERT_TRUE(files.contains(key)) << key;
    const json& m = files[key];
    const auto r = check_mesh(read_soup(p), {/*self_intersections=*/true, 0});
    SCOPED_TRACE(key);
    EXPECT_EQ(r.boundary_edges, m["boundary_edges"].get<std::size_t>());
    EXPECT_EQ(r.boundary_loops, m["boundary_loops"].get<std::size_t>());
    EXPECT_EQ(r.nonmanifold_edges, m["non_manifold_edges"].get<std::size_t>());
    EXPECT_EQ(r.nonmanifold_vertices, m["non_manifold_vertices"].get<std::size_t>());
    EXPECT_EQ(r.orientation_conflicts, m["orientation_conflict_edges"].get<std::size_t>());
    EXPECT_EQ(r.components, m["connected_components"].get<std::size_t>());
    EXPECT_EQ(r.closed, m["boundary_edges"] == 0 && m["non_manifold_edges"] == 0);
    // The manifest's self-intersection count only tests vertex-disjoint, non-coplanar pairs:
    // a lower bound for ours.
    if (m.contains("self_intersecting_faces")) {
      EXPECT_GE(r.self_intersecting_faces, m["self_intersecting_faces"].get<std::size_t>());
    }
    ++compared;
  }
  EXPECT_GE(compared, 20);
}

TEST(Check, AgreesWithCgalOnRealMeshes) {
  const fs::path cgal = test::bin_dir() / "cgal_check";
  if (!fs::exists(cgal)) GTEST_SKIP() << "cgal_check not built (libcgal-dev missing)";
  if (real_meshes().empty()) GTEST_SKIP() << "no ../shared/data/real";
  int compared = 0;
  for (const auto& p : real_meshes()) {
    SCOPED_TRACE(p.filename().string());
    const std::string cmd = cgal.string() + " '" + p.string() + "'";
    FILE* pipe = ::popen(cmd.c_str(), "r");
    ASSERT_NE(pipe, nullptr);
    std::string out;
    char buf[4096];
    while (std::size_t n = std::fread(buf, 1, sizeof buf, pipe)) out.append(buf, n);
    ASSERT_EQ(::pclose(pipe), 0) << out;
    const json c = json::parse(out);
    const auto r = check_mesh(read_soup(p));
    EXPECT_EQ(r.closed, c["closed"].get<bool>());
    EXPECT_EQ(r.boundary_loops, c["boundary_loops"].get<std::size_t>());
    EXPECT_EQ(r.nonmanifold_edges, c["nonmanifold_edges"].get<std::size_t>());
    EXPECT_EQ(r.nonmanifold_vertices, c["nonmanifold_vertices"].get<std::size_t>());
    EXPECT_EQ(r.components, c["components"].get<std::size_t>());
    EXPECT_EQ(r.self_intersections, c["self_intersections"].get<std::size_t>());
    EXPECT_EQ(r.self_intersecting_faces, c["self_intersecting_faces"].get<std::size_t>());
    ++compared;
  }
  EXPECT_GE(compared, 20);
}

TEST(Check, FixturePartsAreCadReady) {
  for (const char* part : {"plate", "shaft", "bracket", "pocket"}) {
    const auto r = check_mesh(read_soup(test::source_dir() / "fixtures/parts" / (std::string(part) + ".stl")));
    EXPECT_TRUE(r.cad_ready) << part << ": " << ::testing::PrintToString(r.problems);
  }
}
