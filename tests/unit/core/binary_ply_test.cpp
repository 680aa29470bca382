// The binary PLY reader (core/src/io/binary_ply.cpp) against OpenMesh's ASCII reading of the
// same records, on layouts CAD and scanner software write, and on malformed records.
#include <algorithm>
#include <cstdint>
#include <cstring>
#include <iomanip>
#include <sstream>

#include "../test_util.h"
#include "s2c/core/errors.h"
#include "s2c/core/io.h"

namespace fs = std::filesystem;
using namespace s2c;
using s2c::test::scratch_dir;
using s2c::test::write_text;

namespace {

/// One PLY written three ways, ASCII and binary in both byte orders, value by value.
class PlyTwins {
 public:
  /// `declarations`: the element and property lines of the header.
  explicit PlyTwins(std::string declarations) : declarations_(std::move(declarations)) {}

  template <class T>
  PlyTwins& put(T v) {
    std::ostringstream s;
    s << std::setprecision(17) << +v << ' ';
    ascii_ += s.str();
    char b[sizeof(T)];
    std::memcpy(b, &v, sizeof(T));
    little_.append(b, sizeof(T));
    std::reverse(b, b + sizeof(T));
    big_.append(b, sizeof(T));
    return *this;
  }
  PlyTwins& end_record() {
    ascii_ += '\n';
    return *this;
  }
  std::string ascii() const { return header("ascii") + ascii_; }
  std::string little() const { return header("binary_little_endian") + little_; }
  std::string big() const { return header("binary_big_endian") + big_; }

 private:
  std::string header(const char* format) const {
    return std::string("ply\nformat ") + format + " 1.0\ncomment written by binary_ply_test\n" + declarations_ +
           "end_header\n";
  }
  std::string declarations_, ascii_, little_, big_;
};

/// A unit cube of six quads: eight vertices (coordinates, normals and colours as CAD exports
/// write them) and six four-corner faces.
template <class Coord, class Count, class Index>
PlyTwins cube(const std::string& coord, const std::string& count, const std::string& index) {
  PlyTwins ply("element vertex 8\nproperty " + coord + " x\nproperty " + coord + " y\nproperty " + coord +
               " z\nproperty float nx\nproperty float ny\nproperty float nz\nproperty uchar red\n"
               "property uchar green\nproperty uchar blue\nelement face 6\nproperty list " + count + " " + index +
               " vertex_indices\n");
  for (int i = 0; i < 8; ++i) {
    const int x = i & 1, y = (i >> 1) & 1, z = (i >> 2) & 1;
    ply.put(Coord(1.25 * x)).put(Coord(-0.5 * y)).put(Coord(1000.125 * z));
    ply.put(x - 0.5f).put(y - 0.5f).put(z - 0.5f);
    ply.put(std::uint8_t{200}).put(std::uint8_t{10}).put(static_cast<std::uint8_t>(i)).end_record();
  }
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads) {
    ply.put(Count{4});
    for (int v : q) ply.put<Index>(static_cast<Index>(v));
    ply.end_record();
  }
  return ply;
}

void expect_same_soup(const TriangleSoup& a, const TriangleSoup& b, const std::string& what) {
  EXPECT_EQ(a.vertices, b.vertices) << what;
  EXPECT_EQ(a.faces, b.faces) << what;
  EXPECT_EQ(a.normals, b.normals) << what;
  EXPECT_EQ(a.polygons_triangulated, b.polygons_triangulated) << what;
  EXPECT_EQ(a.faces_dropped, b.faces_dropped) << what;
}

void expect_invalid(const fs::path& p, const std::string& what) {
  test::expect_invalid_input([&] { read_soup(p); }, {p.string(), what});
}

}  // namespace

TEST(BinaryPly, ReadsAsOpenMeshReadsItsAsciiTwin) {
  const auto dir = scratch_dir();
  struct Layout {
    std::string name;
    PlyTwins ply;
    std::string twin;  ///< the layout whose ASCII file OpenMesh reads for comparison
  };
  // OpenMesh's ASCII reader refuses list lengths other than uchar and short indices: those
  // layouts are compared with the ASCII file of the same values in types it reads.
  const std::vector<Layout> layouts = {
      {"float_uchar_int", cube<float, std::uint8_t, std::int32_t>("float", "uchar", "int"), "float_uchar_int"},
      {"float_ushort_int", cube<float, std::uint16_t, std::int32_t>("float", "ushort", "int"), "float_uchar_int"},
      {"double_uchar_uint", cube<double, std::uint8_t, std::uint32_t>("double", "uchar", "uint"), "double_uchar_uint"},
      {"float_char_short", cube<float, std::int8_t, std::int16_t>("float", "char", "short"), "float_uchar_int"},
      {"int_uchar_int", cube<std::int32_t, std::uint8_t, std::int32_t>("int", "uchar", "int"), "int_uchar_int"},
      {"float64_uint8_int32", cube<double, std::uint8_t, std::int32_t>("float64", "uint8", "int32"),
       "float64_uint8_int32"}};
  for (const Layout& l : layouts) {
    write_text(dir / (l.name + "_ascii.ply"), l.ply.ascii());
    write_text(dir / (l.name + "_le.ply"), l.ply.little());
    write_text(dir / (l.name + "_be.ply"), l.ply.big());
  }
  for (const Layout& l : layouts) {
    const TriangleSoup ascii = read_soup(dir / (l.twin + "_ascii.ply"));
    ASSERT_EQ(ascii.faces.size(), 12u) << l.twin;
    ASSERT_EQ(ascii.normals.size(), 8u) << l.twin;
    expect_same_soup(read_soup(dir / (l.name + "_le.ply")), ascii, l.name + " little endian");
    expect_same_soup(read_soup(dir / (l.name + "_be.ply")), ascii, l.name + " big endian");
  }
  // The quads are fanned, so the corners and their order are the file's.
  const TriangleSoup s = read_soup(dir / "float_uchar_int_le.ply");
  EXPECT_EQ(s.polygons_triangulated, 6u);
  EXPECT_EQ(s.faces[0], (std::array<int, 3>{0, 2, 3}));
  EXPECT_EQ(s.faces[1], (std::array<int, 3>{0, 3, 1}));
  EXPECT_EQ(s.vertices[7], Eigen::Vector3d(1.25, -0.5, 1000.125));
}

TEST(BinaryPly, SkipsElementsAndPropertiesItDoesNotUse) {
  // An element between the vertices and the faces, lists before and after the corner list, and
  // a vertex list: none of them may shift the records that are read.
  PlyTwins ply(
      "element vertex 3\nproperty list uchar float weights\nproperty double x\nproperty double y\n"
      "property double z\nelement edge 2\nproperty int vertex1\nproperty list uchar int more\n"
      "element face 1\nproperty list uchar float texcoord\nproperty list uchar uint vertex_index\n"
      "property int flags\nelement material 1\nproperty uchar ambient_red\n");
  const double xyz[3][3] = {{0.1, 0.2, 0.3}, {4, 5, 6}, {-7, 8.5, 1e-9}};
  for (int v = 0; v < 3; ++v) {
    ply.put<std::uint8_t>(static_cast<std::uint8_t>(v));  // 0, 1 and 2 weights
    for (int k = 0; k < v; ++k) ply.put<float>(0.5f);
    for (double c : xyz[v]) ply.put(c);
  }
  for (int e = 0; e < 2; ++e) ply.put<std::int32_t>(e).put<std::uint8_t>(2).put<std::int32_t>(7).put<std::int32_t>(8);
  ply.put<std::uint8_t>(6);
  for (int k = 0; k < 6; ++k) ply.put<float>(0.25f);
  ply.put<std::uint8_t>(3).put<std::uint32_t>(2).put<std::uint32_t>(0).put<std::uint32_t>(1).put<std::int32_t>(-1);
  ply.put<std::uint8_t>(9);
  const auto dir = scratch_dir();
  for (const auto& [name, bytes] : {std::pair{"le.ply", ply.little()}, std::pair{"be.ply", ply.big()}}) {
    write_text(dir / name, bytes);
    const TriangleSoup s = read_soup(dir / name);
    ASSERT_EQ(s.vertices.size(), 3u) << name;
    for (int v = 0; v < 3; ++v) EXPECT_EQ(s.vertices[v], Eigen::Vector3d(xyz[v][0], xyz[v][1], xyz[v][2])) << name;
    ASSERT_EQ(s.faces.size(), 1u) << name;
    EXPECT_EQ(s.faces[0], (std::array<int, 3>{2, 0, 1})) << name;
    EXPECT_TRUE(s.normals.empty()) << name;
  }
}

TEST(BinaryPly, MalformedRecordsNameTheRecord) {
  const auto dir = scratch_dir();
  const std::string head =
      "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
      "property float z\nelement face 2\nproperty list char uint vertex_indices\nend_header\n";
  auto body = [](std::int8_t count, std::uint32_t last, std::size_t cut = 0) {
    std::string s;
    auto put = [&s](auto v) { s.append(reinterpret_cast<const char*>(&v), sizeof v); };
    for (float c : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put(c);
    for (int f = 0; f < 2; ++f) {
      put(f == 0 ? std::int8_t{3} : count);
      for (std::uint32_t i : {0u, 1u, f == 0 ? 2u : last}) put(i);
    }
    return s.substr(0, s.size() - cut);
  };
  write_text(dir / "ok.ply", head + body(3, 2));
  EXPECT_EQ(read_soup(dir / "ok.ply").faces.size(), 2u);
  write_text(dir / "index.ply", head + body(3, 0xFFFFFFFFu));
  expect_invalid(dir / "index.ply", "face 1 refers to vertex 4294967295, but the file has 3 vertices");
  write_text(dir / "two.ply", head + body(2, 2) + std::string(4, '\0'));  // as long as the header needs
  expect_invalid(dir / "two.ply", "face 1 has 2 corners");
  write_text(dir / "negative.ply", head + body(-3, 2));
  expect_invalid(dir / "negative.ply", "face 1 of 2: its list 'vertex_indices' has the negative length -3");
  // A longer list than the file holds: the header check cannot see it, the reader must.
  write_text(dir / "long.ply", head + body(120, 2));
  expect_invalid(dir / "long.ply", "face 1 of 2: the file ends inside it");
  // A length of four billion: refused as past the end, not allocated.
  std::string huge = head;
  huge.replace(huge.find("list char uint"), 14, "list uint uint");
  {
    auto put = [&huge](auto v) { huge.append(reinterpret_cast<const char*>(&v), sizeof v); };
    for (float c : {0.f, 0.f, 0.f, 1.f, 0.f, 0.f, 0.f, 1.f, 0.f}) put(c);
    for (std::uint32_t v : {3u, 0u, 1u, 2u, 0xFFFFFFFFu, 0u, 1u, 2u}) put(v);
  }
  write_text(dir / "huge.ply", huge);
  expect_invalid(dir / "huge.ply", "face 1 of 2: the file ends inside it");
  write_text(dir / "cut.ply", head + body(3, 2, 1));
  expect_invalid(dir / "cut.ply", "truncated");
}
