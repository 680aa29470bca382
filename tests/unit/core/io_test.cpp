// Reading and writing meshes: round trips and every malformed-input case of issue 2.
#include <cstring>

#include "../test_util.h"
#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "s2c/core/io.h"

namespace fs = std::filesystem;
using namespace s2c;
using s2c::test::scratch_dir;
using s2c::test::write_text;

namespace {

// Expects read_soup to throw InvalidInput whose message names the file and contains `what`.
void expect_invalid(const fs::path& p, const std::string& what) {
  test::expect_invalid_input([&] { read_soup(p); }, {p.string(), what});
}

std::string binary_ply_header(int nv, int nf) {
  return "ply\nformat binary_little_endian 1.0\nelement vertex " + std::to_string(nv) +
         "\nproperty float x\nproperty float y\nproperty float z\nelement face " + std::to_string(nf) +
         "\nproperty list uchar int vertex_indices\nend_header\n";
}

template <class T>
void put(std::string& s, T v) {
  s.append(reinterpret_cast<const char*>(&v), sizeof v);
}

std::string binary_ply_triangle(float nan_at = 0, int bad_index = -1) {
  std::string s = binary_ply_header(3, 1);
  const float v[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
  for (int i = 0; i < 9; ++i) put(s, i == 4 && nan_at != 0 ? nan_at : v[i]);
  put<unsigned char>(s, 3);
  put<int>(s, 0);
  put<int>(s, 1);
  put<int>(s, bad_index >= 0 ? bad_index : 2);
  return s;
}

const char* kAsciiPly =
    "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
    "element face 2\nproperty list uchar int vertex_indices\nend_header\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n";

}  // namespace

TEST(MeshIo, RoundTripEveryFormat) {
  const auto dir = scratch_dir();
  Mesh m;
  soup_to_mesh(test::cube(10), m);
  for (const char* ext : {".ply", ".stl", ".obj", ".off"}) {
    for (bool binary : {true, false}) {
      const fs::path p = dir / (std::string("cube_") + (binary ? "bin" : "txt") + ext);
      write_mesh(m, p, {binary, true});
      const TriangleSoup s = read_soup(p);
      EXPECT_EQ(s.faces.size(), 12u) << p;
      EXPECT_EQ(s.vertices.size(), 8u) << p;  // STL is welded by position
      const Bounds b = bounds(s);
      EXPECT_NEAR(b.diagonal(), std::sqrt(300.0), 1e-5) << p;
    }
  }
}

TEST(MeshIo, WritingAMeshTheCallerIsDoneWithGivesTheSameBytes) {
  const auto dir = scratch_dir();
  Mesh m;
  soup_to_mesh(test::cube(10), m);
  for (const char* ext : {".ply", ".stl", ".obj", ".off"}) {
    Mesh spent = m;
    write_mesh(m, dir / (std::string("kept") + ext));
    write_mesh(std::move(spent), dir / (std::string("spent") + ext));
    EXPECT_EQ(read_file(dir / (std::string("kept") + ext)), read_file(dir / (std::string("spent") + ext))) << ext;
  }
}

TEST(MeshIo, WriteIsAtomicAndLeavesNoTemporaryFile) {
  const auto dir = scratch_dir();
  Mesh m;
  soup_to_mesh(test::cube(), m);
  write_mesh(m, dir / "a.ply");
  int entries = 0;
  for (const auto& e : fs::directory_iterator(dir)) {
    ++entries;
    EXPECT_EQ(e.path().filename(), "a.ply");
  }
  EXPECT_EQ(entries, 1);
  // A folder in the way of the target: the write fails, nothing is left behind.
  fs::create_directories(dir / "b.ply");
  EXPECT_THROW(write_mesh(m, dir / "b.ply"), IoError);
  for (const auto& e : fs::directory_iterator(dir))
    EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos) << e.path();
}

TEST(Files, AtomicStreamShowsItsPiecesOnlyOnCommit) {
  const auto dir = scratch_dir();
  const fs::path target = dir / "out.json";
  auto only_target_or_nothing = [&] {
    for (const auto& e : fs::directory_iterator(dir))
      if (e.path() != target) return false;
    return true;
  };
  // Pieces of half a megabyte, past the writeback step (4 MB); the old file stays until the commit.
  write_file_atomic(target, "old");
  std::string expected;
  {
    AtomicStream out(target);
    for (int k = 0; k < 9; ++k) {
      const std::string piece(1 << 19, static_cast<char>('a' + k));
      out.write(piece);
      expected += piece;
    }
    out.write("");
    EXPECT_EQ(read_file(target), "old");
    out.commit();
  }
  EXPECT_EQ(read_file(target), expected);
  EXPECT_TRUE(only_target_or_nothing());
  // Not committed (an error on the way): the target stays as it was, no temporary is left.
  {
    AtomicStream out(target);
    out.write("partial");
  }
  EXPECT_EQ(read_file(target), expected);
  EXPECT_TRUE(only_target_or_nothing());
  // Under a file, where no folder can be made.
  EXPECT_THROW(AtomicStream(target / "x.json"), IoError);
}

TEST(MeshIo, ReadsPolygonsByFanTriangulation) {
  const auto dir = scratch_dir();
  write_text(dir / "quad.obj", "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n");
  const auto s = read_soup(dir / "quad.obj");
  EXPECT_EQ(s.faces.size(), 2u);
  EXPECT_EQ(s.polygons_triangulated, 1u);
  write_text(dir / "quad.ply", kAsciiPly);
  EXPECT_EQ(read_soup(dir / "quad.ply").faces.size(), 2u);
}

TEST(MeshIo, MissingEmptyAndUnknownFiles) {
  const auto dir = scratch_dir();
  expect_invalid(dir / "nope.ply", "no such file");
  write_text(dir / "empty.stl", "");
  expect_invalid(dir / "empty.stl", "empty file");
  write_text(dir / "mesh.xyz", "1 2 3\n");
  expect_invalid(dir / "mesh.xyz", "unknown mesh extension");
  write_text(dir / "noply.ply", "hello\n");
  expect_invalid(dir / "noply.ply", "not a PLY file");
}

TEST(MeshIo, TruncatedFiles) {
  const auto dir = scratch_dir();
  std::string ply = binary_ply_triangle();
  write_text(dir / "trunc_bin.ply", ply.substr(0, ply.size() - 7));
  expect_invalid(dir / "trunc_bin.ply", "truncated");
  std::string ascii = kAsciiPly;
  write_text(dir / "trunc_ascii.ply", ascii.substr(0, ascii.find("3 0 2 3")));
  expect_invalid(dir / "trunc_ascii.ply", "truncated");

  std::string stl(80, ' ');
  put<std::uint32_t>(stl, 10);  // declares 10 triangles, holds one
  stl.append(50, '\0');
  write_text(dir / "trunc.stl", stl);
  expect_invalid(dir / "trunc.stl", "truncated binary STL");
  write_text(dir / "trunc_ascii.stl",
             "solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\n");
  expect_invalid(dir / "trunc_ascii.stl", "no 'endsolid'");

  write_text(dir / "trunc.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n");
  expect_invalid(dir / "trunc.off", "truncated");
  write_text(dir / "trunc.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0\n");
  expect_invalid(dir / "trunc.vtk", "truncated");
}

TEST(MeshIo, NonFiniteCoordinates) {
  const auto dir = scratch_dir();
  write_text(dir / "nan.ply", binary_ply_triangle(std::numeric_limits<float>::quiet_NaN()));
  expect_invalid(dir / "nan.ply", "non-finite");
  write_text(dir / "inf.ply", binary_ply_triangle(std::numeric_limits<float>::infinity()));
  expect_invalid(dir / "inf.ply", "non-finite");
  // Text "nan" cannot be parsed as a coordinate: also an error, never a silent zero.
  write_text(dir / "nan.off", "OFF\n3 1 0\n0 0 0\nnan 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_THROW(read_soup(dir / "nan.off"), InvalidInput);
}

TEST(MeshIo, FaceIndicesOutOfRange) {
  const auto dir = scratch_dir();
  write_text(dir / "badidx.ply", binary_ply_triangle(0, 7));
  expect_invalid(dir / "badidx.ply", "refers to vertex 7");
  write_text(dir / "badidx.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 5\n");
  expect_invalid(dir / "badidx.off", "vertex 5");
  write_text(dir / "badidx.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
  EXPECT_THROW(read_soup(dir / "badidx.obj"), InvalidInput);
  write_text(dir / "badidx.vtk",
             "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 3 float\n0 0 0 1 0 0 0 1 0\nPOLYGONS 1 4\n3 0 1 3\n");
  expect_invalid(dir / "badidx.vtk", "out of range");
}

TEST(MeshIo, AbsurdHeaderCountsAreRejectedBeforeAllocating) {
  const auto dir = scratch_dir();
  write_text(dir / "huge.ply", binary_ply_header(2000000000, 2000000000) + std::string(100, '\0'));
  expect_invalid(dir / "huge.ply", "truncated or corrupt");
  write_text(dir / "huge_ascii.ply",
             "ply\nformat ascii 1.0\nelement vertex 999999999999999\nproperty float x\nproperty float y\n"
             "property float z\nend_header\n0 0 0\n");
  expect_invalid(dir / "huge_ascii.ply", "truncated or corrupt");
  write_text(dir / "huge.off", "OFF\n999999999999 1 0\n0 0 0\n");
  expect_invalid(dir / "huge.off", "more than");
  write_text(dir / "neg.off", "OFF\n-3 1 0\n0 0 0\n");
  expect_invalid(dir / "neg.off", "not a non-negative integer");
  // OpenMesh reads counts from the line after the keyword: here it would take "3" vertices and
  // "-70" faces and loop for 2^32 faces (fuzzing found it); refused up front instead.
  write_text(dir / "sameline.off", "OFF 0 0 39\n3\n-70 )\n");
  expect_invalid(dir / "sameline.off", "on the line after 'OFF'");
  write_text(dir / "huge.vtk", "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 99999999999 float\n");
  expect_invalid(dir / "huge.vtk", "cannot fit");
}

// OpenMesh's ASCII reader reads as many values as a list's length says; a length of 3.4e16 held
// it for good (fuzzing): list lengths are checked against their type and the values that follow.
// A list property without a name sent it into a loop too.
TEST(MeshIo, PlyListsAreCheckedBeforeOpenMeshReadsThem) {
  const auto dir = scratch_dir();
  // kAsciiPly with its face list declared as `list` and the length of face 1 as `length`.
  auto with_length = [](const std::string& length, const std::string& list = "list uchar int") {
    std::string text = kAsciiPly;
    text.replace(text.find("list uchar int"), 14, list);
    text.replace(text.find("3 0 2 3"), 1, length);
    return text;
  };
  auto refused = [&](const char* name, const std::string& text, const std::string& message) {
    write_text(dir / name, text);
    expect_invalid(dir / name, message);
  };
  refused("huge.ply", with_length("34444444444444444"),
          "line 15: face 1: list 'vertex_indices' has the length '34444444444444444'");
  refused("negative.ply", with_length("-3"), "has the length '-3'");
  std::string unnamed = binary_ply_triangle();
  unnamed.replace(unnamed.find(" vertex_indices"), 15, "");
  refused("unnamed.ply", unnamed, "header line 8: the list property has no name");
  refused("wide.ply", with_length("4000000000", "list uint int"),
          "face 1 of 2 ends inside its list 'vertex_indices' (3 values of 4000000000)");
  // A length past what its type holds: 256 for uchar, 65536 for ushort.
  refused("byte_length.ply", with_length("256"), "has the length '256', not a count of 0 to 255");
  refused("short_length.ply", with_length("65536", "list ushort int"),
          "has the length '65536', not a count of 0 to 65535");
}

TEST(MeshIo, EmptyMeshesAndPointClouds) {
  const auto dir = scratch_dir();
  write_text(dir / "cloud.ply",
             "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
             "end_header\n0 0 0\n1 1 1\n");
  expect_invalid(dir / "cloud.ply", "no faces");
  EXPECT_EQ(read_soup(dir / "cloud.ply", /*allow_empty=*/true).vertices.size(), 2u);
  write_text(dir / "none.off", "OFF\n0 0 0\n");
  expect_invalid(dir / "none.off", "no faces");
}

TEST(MeshIo, InputIsNeverOverwritten) {
  const auto dir = scratch_dir();
  write_text(dir / "in.ply", kAsciiPly);
  EXPECT_THROW(refuse_same_file(dir / "in.ply", dir / "in.ply"), InvalidInput);
  EXPECT_THROW(refuse_same_file(dir / "in.ply", dir / "." / "in.ply"), InvalidInput);
  EXPECT_NO_THROW(refuse_same_file(dir / "in.ply", dir / "out.ply"));
}

TEST(MeshIo, Sha256MatchesKnownVector) {
  EXPECT_EQ(sha256_bytes("abc"), "ba7816bf8f01cfea414140de5dae2223b00361a396177a9cb410ff61f20015ad");
}

TEST(MeshIo, ReadsEveryRealMesh) {
  // Every mesh in ../shared/data/real reads without error (OFF, OBJ, PLY with extra properties,
  // ASCII and binary STL, legacy VTK).
  const fs::path real = test::shared_dir() / "data/real";
  if (!fs::exists(real)) GTEST_SKIP() << "no ../shared/data/real";
  int n = 0;
  for (const char* sub : {"defective", "cad"})
    for (const auto& e : fs::directory_iterator(real / sub)) {
      const std::string name = e.path().filename().string();
      const std::string ext = e.path().extension().string();
      if (name.find("_points") != std::string::npos || ext == ".txt" || ext == ".xyzc") continue;
      const TriangleSoup s = read_soup(e.path());
      EXPECT_GT(s.faces.size(), 0u) << name;
      ++n;
    }
  EXPECT_GE(n, 20);
}

TEST(MeshIo, KeepsFullDoublePrecision) {
  // OpenMesh parses floats; coordinates must still come back exactly as written.
  const auto dir = scratch_dir();
  const double x = 0.123456789012345, y = 1000.000000123, z = -7.25e-3;
  const std::string v = "0.123456789012345 1000.000000123 -7.25e-3";
  write_text(dir / "p.obj", "v " + v + "\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  write_text(dir / "p.off", "OFF\n3 1 0\n" + v + "\n1 0 0\n0 1 0\n3 0 1 2\n");
  write_text(dir / "p.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                            "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n" +
                                v + "\n1 0 0\n0 1 0\n3 0 1 2\n");
  std::string bin = "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
                    "property double z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n";
  for (double c : {x, y, z, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0}) put(bin, c);
  put<unsigned char>(bin, 3);
  for (int i : {0, 1, 2}) put(bin, i);
  write_text(dir / "pb.ply", bin);
  for (const char* f : {"p.obj", "p.off", "p.ply", "pb.ply"}) {
    const auto s = read_soup(dir / f);
    ASSERT_EQ(s.vertices.size(), 3u) << f;
    EXPECT_EQ(s.vertices[0], Eigen::Vector3d(x, y, z)) << f;
  }
}

// The face count guessed from a file's size and format, binary or text, within a factor of two
// on a mesh large enough for the header not to count; 0 where there is nothing to guess from.
TEST(MeshIo, EstimatedFacesFromSizeAndFormat) {
  const auto dir = scratch_dir();
  Mesh m;
  soup_to_mesh(test::icosphere(Eigen::Vector3d::Zero(), 10.0, 5), m);  // 20,480 faces
  const double faces = static_cast<double>(m.n_faces());
  for (const char* ext : {".ply", ".stl", ".obj", ".off"}) {
    for (bool binary : {true, false}) {
      const fs::path p = dir / (std::string("sphere_") + (binary ? "bin" : "txt") + ext);
      write_mesh(m, p, {binary, false});
      const double guess = static_cast<double>(estimated_faces(p));
      EXPECT_GT(guess, 0.5 * faces) << p;
      EXPECT_LT(guess, 2.0 * faces) << p;
    }
  }
  EXPECT_EQ(estimated_faces(dir / "missing.ply"), 0u);
  write_text(dir / "notes.txt", "not a mesh");
  EXPECT_EQ(estimated_faces(dir / "notes.txt"), 0u);
}
