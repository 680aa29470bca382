// The arrays built straight from an indexed triangle list against those built through OpenMesh:
// equal where the list is a manifold surface, the half-edge route taken where it is not.
#include <gtest/gtest.h>

#include "mesh_arrays.h"
#include "s2c/core/errors.h"
#include "s2c/core/io.h"
#include "s2c/features/analyze.h"
#include "test_util.h"

namespace s2c::features {
namespace {

MeshArrays through_openmesh(const TriangleSoup& soup) {
  Mesh m;
  soup_to_mesh(soup, m);
  return build_arrays(m);
}

void expect_same(const MeshArrays& a, const MeshArrays& b) {
  ASSERT_EQ(a.vertices(), b.vertices());
  ASSERT_EQ(a.faces(), b.faces());
  ASSERT_EQ(a.edges.size(), b.edges.size());
  EXPECT_EQ(a.pos, b.pos);
  EXPECT_EQ(a.tri, b.tri);
  EXPECT_EQ(a.fnormal, b.fnormal);
  EXPECT_EQ(a.farea, b.farea);
  EXPECT_EQ(a.vf_start, b.vf_start);
  EXPECT_EQ(a.vf, b.vf);
  for (std::size_t e = 0; e < a.edges.size(); ++e) {
    const auto &x = a.edges[e], &y = b.edges[e];
    ASSERT_TRUE(x.v0 == y.v0 && x.v1 == y.v1 && x.f0 == y.f0 && x.f1 == y.f1) << "edge " << e;
  }
  EXPECT_EQ(a.face_edges, b.face_edges);
  EXPECT_EQ(a.median_edge, b.median_edge);
  EXPECT_EQ(a.mean_edge, b.mean_edge);
  EXPECT_EQ(a.box.min, b.box.min);
  EXPECT_EQ(a.box.max, b.box.max);
}

/// build_arrays on a copy of the soup; `through_mesh` says which route it took.
MeshArrays direct(TriangleSoup soup, bool& through_mesh) { return build_arrays(std::move(soup), &through_mesh); }

TEST(MeshArraysFromFaces, EqualThoseThroughOpenMeshOnTheFixturePartsAndAnOpenSheet) {
  std::vector<TriangleSoup> soups;
  for (const char* part : {"plate", "shaft", "bracket", "pocket"})
    soups.push_back(read_soup(test::source_dir() / "fixtures/parts" / (std::string(part) + ".stl")));
  // Open, with an outer boundary and a hole (half-disk fans), and an unreferenced vertex.
  soups.push_back(test::grid(12, [](int i, int j) { return !(i >= 4 && i < 7 && j >= 5 && j < 7); },
                             [](double x, double y) { return Eigen::Vector3d(x, y, 0.1 * x * y); }));
  soups.back().vertices.emplace_back(100.0, 100.0, 100.0);
  for (const TriangleSoup& s : soups) {
    bool through_mesh = true;
    const MeshArrays a = direct(s, through_mesh);
    EXPECT_FALSE(through_mesh);
    expect_same(a, through_openmesh(s));
  }
}

TEST(MeshArraysFromFaces, NonManifoldListsGoThroughOpenMesh) {
  const TriangleSoup sheet = test::grid(4, [](int, int) { return true; }, [](double x, double y) {
    return Eigen::Vector3d(x, y, 0.0);
  });
  std::vector<TriangleSoup> bad;
  bad.push_back(sheet);  // a third face on an edge
  bad.back().vertices.emplace_back(0.5, 0.5, 1.0);
  bad.back().faces.push_back({sheet.faces[0][0], sheet.faces[0][1], static_cast<int>(sheet.vertices.size())});
  bad.push_back(sheet);  // one face flipped
  std::swap(bad.back().faces[5][0], bad.back().faces[5][1]);
  bad.push_back(sheet);  // the same face twice
  bad.back().faces.push_back(sheet.faces[3]);
  // Two faces running one edge the same way, from the larger vertex to the smaller, and no face
  // the other way (the one kind of side add_manifold_edges looks up only after the others).
  TriangleSoup same_way;
  same_way.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0.5}};
  same_way.faces = {{2, 1, 0}, {2, 1, 3}};
  bad.push_back(same_way);
  // Two tetrahedra sharing one vertex: two closed fans around it.
  TriangleSoup bowtie;
  bowtie.vertices = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, -1, 0}, {0, 0, -1}};
  bowtie.faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}, {0, 5, 4}, {0, 4, 6}, {0, 6, 5}, {4, 5, 6}};
  bad.push_back(bowtie);
  // Squares left out along diagonals: vertices where two open fans touch.
  bad.push_back(test::grid(8, [](int i, int j) { return (i + j) % 4 != 1; }));
  for (std::size_t i = 0; i < bad.size(); ++i) {
    bool through_mesh = false;
    const MeshArrays a = direct(bad[i], through_mesh);
    EXPECT_TRUE(through_mesh) << i;
    expect_same(a, through_openmesh(bad[i]));
  }
  // The analysis of the list is that of the mesh OpenMesh makes of it.
  TriangleSoup copy = bowtie;
  Mesh m;
  soup_to_mesh(bowtie, m);
  const Analysis x = analyze(std::move(copy), {}), y = analyze(m, {});
  EXPECT_EQ(x.face_patch, y.face_patch);
  EXPECT_EQ(x.features.patches.size(), y.features.patches.size());
  EXPECT_EQ(x.features.lines.size(), y.features.lines.size());
}

TEST(MeshArraysFromFaces, AFaceIndexOutOfRangeIsAnError) {
  TriangleSoup s = test::icosphere(Eigen::Vector3d::Zero(), 2.0, 1);
  s.faces[3][1] = static_cast<int>(s.vertices.size());
  EXPECT_THROW(build_arrays(std::move(s)), InvalidInput);
}

TEST(MeshArraysFromFaces, TheSoupIsTakenOver) {
  TriangleSoup s = test::icosphere(Eigen::Vector3d::Zero(), 2.0, 2);
  s.normals = s.vertices;
  const std::size_t nv = s.vertices.size();
  const MeshArrays a = build_arrays(std::move(s));
  EXPECT_EQ(a.vertices(), static_cast<int>(nv));
  EXPECT_TRUE(s.vertices.empty() && s.faces.empty() && s.normals.empty());
}

}  // namespace
}  // namespace s2c::features
