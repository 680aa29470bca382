// The stream directory: reading, validation messages, deprojection.
#include "../test_util.h"
#include "s2c/core/errors.h"
#include "s2c/core/stream.h"

namespace fs = std::filesystem;
using namespace s2c;
using test::write_text;

namespace {

fs::path make_stream(const fs::path& dir, const std::string& yaml_extra = "", bool with_poses = true) {
  fs::create_directories(dir / "depth");
  write_text(dir / "stream.yaml",
             "%YAML:1.0\n---\nformat: \"scan2cad.stream/1\"\nsensor: depth\ndevice: test\nwidth: 4\nheight: 3\n"
             "depth_unit_mm: 0.5\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
             "   data: [ 2., 0., 1.5, 0., 2., 1., 0., 0., 1. ]\ndist_coeffs: !!opencv-matrix\n   rows: 1\n"
             "   cols: 5\n   dt: d\n   data: [ 0., 0., 0., 0., 0. ]\n" + yaml_extra);
  DepthImage img{4, 3, std::vector<std::uint16_t>(12, 200)};
  img.data[0] = 0;
  write_depth_png(dir / "depth/000000.png", img);
  write_text(dir / "depth.txt", "# comment\n0.0 depth/000000.png\n");
  if (with_poses) write_text(dir / "poses.txt", "0.0 1 2 3 0 0 0 1\n");
  return dir;
}

void expect_invalid(const std::function<void()>& f, const std::string& what) { test::expect_invalid_input(f, {what}); }

}  // namespace

TEST(Stream, ReadsAndDeprojects) {
  const auto dir = make_stream(test::scratch_dir() / "s");
  const Stream s = read_stream(dir);
  ASSERT_EQ(s.frames.size(), 1u);
  const DepthImage d = read_frame(s, 0);
  std::vector<Eigen::Vector3d> dirs;
  const auto pts = deproject(s, 0, d, &dirs);
  ASSERT_EQ(pts.size(), 11u);  // one zero pixel skipped
  // pixel (1,0): z = 100 mm, x = (1-1.5)/2*100 = -25, y = (0-1)/2*100 = -50, then + (1,2,3)
  EXPECT_NEAR(pts[0].x(), -24.0, 1e-9);
  EXPECT_NEAR(pts[0].y(), -48.0, 1e-9);
  EXPECT_NEAR(pts[0].z(), 103.0, 1e-9);
  EXPECT_NEAR(dirs[0].norm(), 1.0, 1e-12);
  EXPECT_LT(dirs[0].z(), 0);  // towards the camera
}

TEST(Stream, MissingAndMalformedKeys) {
  const auto root = test::scratch_dir();
  auto dir = make_stream(root / "a");
  write_text(dir / "stream.yaml", "%YAML:1.0\n---\nformat: \"scan2cad.stream/1\"\nsensor: depth\nwidth: 4\nheight: 3\n");
  expect_invalid([&] { read_stream(dir); }, "missing key 'depth_unit_mm'");
  write_text(dir / "stream.yaml", "%YAML:1.0\n---\nformat: \"other/1\"\n");
  expect_invalid([&] { read_stream(dir); }, "format is 'other/1'");
  write_text(dir / "stream.yaml", "%YAML:1.0\n---\nformat: [unclosed\n");
  expect_invalid([&] { read_stream(dir); }, "stream.yaml");
  fs::remove(dir / "stream.yaml");
  expect_invalid([&] { read_stream(dir); }, "needs stream.yaml");
}

TEST(Stream, BadIndexAndPoses) {
  const auto root = test::scratch_dir();
  auto dir = make_stream(root / "a");
  write_text(dir / "depth.txt", "0.0 depth/000000.png extra\n");
  expect_invalid([&] { read_stream(dir); }, "depth.txt: line 1");
  write_text(dir / "depth.txt", "0.0 depth/000000.png\n");
  write_text(dir / "poses.txt", "0.0 1 2 nan 0 0 0 1\n");
  expect_invalid([&] { read_stream(dir); }, "poses.txt: line 1");
  write_text(dir / "poses.txt", "0.0 1 2 3 0 0 0 2\n");
  expect_invalid([&] { read_stream(dir); }, "quaternion has norm 2");
  write_text(dir / "poses.txt", "0.0 1 2 3 0 0 0\n");
  expect_invalid([&] { read_stream(dir); }, "expected 'timestamp tx ty tz qx qy qz qw'");
  write_text(dir / "depth.txt", "0.0 ../escape.png\n");
  expect_invalid([&] { read_stream(dir); }, "inside the stream directory");
}

TEST(Stream, BadFramesAreNamed) {
  const auto root = test::scratch_dir();
  auto dir = make_stream(root / "a");
  Stream s = read_stream(dir);
  // Wrong size.
  write_depth_png(dir / "depth/000000.png", DepthImage{5, 3, std::vector<std::uint16_t>(15, 1)});
  expect_invalid([&] { read_frame(s, 0); }, "000000.png: frame 0 is 5x3");
  // Truncated PNG.
  write_depth_png(dir / "depth/000000.png", DepthImage{4, 3, std::vector<std::uint16_t>(12, 1)});
  const auto size = fs::file_size(dir / "depth/000000.png");
  fs::resize_file(dir / "depth/000000.png", size / 2);
  expect_invalid([&] { read_frame(s, 0); }, "000000.png");
  // Missing.
  fs::remove(dir / "depth/000000.png");
  expect_invalid([&] { read_frame(s, 0); }, "does not exist");
  // 8-bit image.
  write_text(dir / "depth/000000.png", "");
  expect_invalid([&] { read_frame(s, 0); }, "000000.png");
}
