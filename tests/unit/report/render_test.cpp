#include <gtest/gtest.h>

#include <cmath>

#include "s2c/core/files.h"
#include "s2c/report/layers.h"
#include "s2c/report/render.h"
#include "test_util.h"

namespace s2c::report {
namespace {

/// Share of the pixels where red clearly dominates (a red object on the grey background).
double red_share(const Image& im) {
  std::size_t red = 0;
  for (std::size_t i = 0; i < im.rgb.size(); i += 3)
    if (im.rgb[i] > im.rgb[i + 1] + 40 && im.rgb[i] > im.rgb[i + 2] + 40) ++red;
  return double(red) / (im.width * im.height);
}

const std::uint8_t* pixel(const Image& im, int x, int y) { return &im.rgb[(std::size_t(y) * im.width + x) * 3]; }

TEST(Render, SphereSilhouetteHasTheProjectedArea) {
  Scene scene;
  scene.add(MeshLayer{test::icosphere(Eigen::Vector3d::Zero(), 10, 4), {}, {}, Colour(1, 0, 0)});
  RenderOptions o;
  o.width = o.height = 200;
  o.outlines = false;
  const Image im = scene.render(view_named("front"), o);
  ASSERT_EQ(im.rgb.size(), 200u * 200u * 3u);
  // The camera frames the bounding box's sphere (radius √3·10) with 8% margin in a 30° view:
  // distance d = 1.08·√3·10 / sin 15°; the sphere subtends tan(asin(10/d)) / tan 15° of the half height.
  const double d = 1.08 * std::sqrt(3.0) * 10 / std::sin(M_PI / 12);
  const double r_px = std::tan(std::asin(10 / d)) / std::tan(M_PI / 12) * 100;
  const double expected = M_PI * r_px * r_px / (200.0 * 200.0);
  EXPECT_NEAR(red_share(im), expected, 0.03 * expected);
  // Centre: the object; corner: the background (light grey).
  EXPECT_GT(pixel(im, 100, 100)[0], 100);
  EXPECT_GT(pixel(im, 2, 2)[1], 200);
}

TEST(Render, ViewsSeeDifferentSides) {
  // A cube whose +x face is red and the rest grey: visible from the right, not from the left.
  TriangleSoup cube = test::cube(10);
  MeshLayer layer{cube, {}, std::vector<Colour>(cube.faces.size(), kMeshGrey), kMeshGrey};
  for (std::size_t f = 0; f < cube.faces.size(); ++f) {
    bool plus_x = true;
    for (int v : cube.faces[f]) plus_x &= cube.vertices[v].x() > 9.99;
    if (plus_x) layer.face_colours[f] = Colour(1, 0, 0);
  }
  Scene scene;
  scene.add(std::move(layer));
  RenderOptions o;
  o.width = o.height = 96;
  EXPECT_GT(red_share(scene.render(view_named("right"), o)), 0.1);
  EXPECT_EQ(red_share(scene.render(view_named("left"), o)), 0.0);
  EXPECT_GT(red_share(scene.render(view_named("1,0.3,0.2"), o)), 0.05);
}

TEST(Render, FeatureLinesAreHiddenBehindSurfaces) {
  // A red line across the front of a grey sphere is drawn; the same line behind it is not.
  auto scene_with_line = [](double y) {
    auto scene = std::make_unique<Scene>();
    scene->add(MeshLayer{test::icosphere(Eigen::Vector3d::Zero(), 10, 3), {}, {}, kMeshGrey});
    Polyline line;
    line.points = {{-8, y, 0}, {8, y, 0}};
    line.colour = Colour(1, 0, 0);
    scene->add(std::move(line));
    return scene;
  };
  RenderOptions o;
  o.width = o.height = 128;
  EXPECT_GT(red_share(scene_with_line(-11)->render(view_named("front"), o)), 0.002);
  EXPECT_EQ(red_share(scene_with_line(11)->render(view_named("front"), o)), 0.0);
}

TEST(Render, PointCloudsAreDrawnAsDiscs) {
  const TriangleSoup sphere = test::icosphere(Eigen::Vector3d::Zero(), 10, 3);
  TriangleSoup cloud;
  cloud.vertices = sphere.vertices;
  for (const auto& p : cloud.vertices) cloud.normals.push_back(p.normalized());
  PointLayer points = cloud_layer(cloud);
  points.colour = Colour(1, 0, 0);
  ASSERT_EQ(points.points.size(), cloud.vertices.size());
  Scene scene;
  scene.add(std::move(points));
  RenderOptions o;
  o.width = o.height = 160;
  o.outlines = false;
  // Discs of 0.6 spacing leave gaps, but the silhouette is mostly covered.
  EXPECT_GT(red_share(scene.render(view_named("iso"), o)), 0.08);
  const double edge = median_edge_length(sphere);
  EXPECT_GT(point_spacing(cloud.vertices), 0.6 * edge);
  EXPECT_LT(point_spacing(cloud.vertices), 1.05 * edge);
}

TEST(Render, SubsampledCloudKeepsAtMostTheLimit) {
  TriangleSoup cloud;
  for (int i = 0; i < 1000; ++i) cloud.vertices.emplace_back(i, 0, 0);
  EXPECT_LE(cloud_layer(cloud, 300).points.size(), 300u);
  EXPECT_GE(cloud_layer(cloud, 300).points.size(), 250u);
}

TEST(Render, RejectsBadViewsSizesAndEmptyScenes) {
  test::expect_invalid_input([] { view_named("sideways"); }, {"sideways", "iso"});
  test::expect_invalid_input([] { view_named("0,0,0"); }, {"0,0,0"});
  test::expect_invalid_input([] { view_named("1,2"); }, {"1,2"});
  Scene empty;
  EXPECT_THROW(empty.render(view_named("iso")), ProcessingError);
  Scene scene;
  scene.add(MeshLayer{test::cube(), {}, {}, kMeshGrey});
  RenderOptions o;
  o.width = 0;
  EXPECT_THROW(scene.render(view_named("iso"), o), InvalidInput);
}

TEST(Render, RefusesLayersThatDoNotMatchTheirMesh) {
  Scene scene;
  TriangleSoup bad = test::cube();
  bad.faces.push_back({0, 1, 99});
  EXPECT_THROW(scene.add(MeshLayer{bad, {}, {}, kMeshGrey}), InvalidInput);
  EXPECT_THROW(scene.add(MeshLayer{test::cube(), {Colour::Zero()}, {}, kMeshGrey}), InvalidInput);
  EXPECT_THROW(scene.add(MeshLayer{test::cube(), {}, {Colour::Zero()}, kMeshGrey}), InvalidInput);
  PointLayer points;
  points.points = {{0, 0, 0}, {1, 0, 0}};
  points.normals = {{0, 0, 1}};
  EXPECT_THROW(scene.add(points), InvalidInput);
  // After the first render the BVH is built: adding is refused rather than silently not drawn.
  scene.add(MeshLayer{test::cube(), {}, {}, kMeshGrey});
  RenderOptions o;
  o.width = o.height = 16;
  scene.render(view_named("iso"), o);
  EXPECT_THROW(scene.add(Polyline{}), ProcessingError);
}

TEST(Render, HugePicturesAreRefusedBeforeAllocating) {
  Scene scene;
  scene.add(MeshLayer{test::cube(), {}, {}, kMeshGrey});
  RenderOptions o;
  o.width = o.height = 8192;  // 2^26 pixels: beyond the 2^25 budget even at one ray per pixel
  EXPECT_THROW(scene.render(view_named("iso"), o), InvalidInput);
  o.fov_deg = 0;
  o.width = o.height = 16;
  EXPECT_THROW(scene.render(view_named("iso"), o), InvalidInput);
}

TEST(Render, WritesAPng) {
  Scene scene;
  scene.add(MeshLayer{test::cube(), {}, {}, kMeshGrey});
  RenderOptions o;
  o.width = 64;
  o.height = 48;
  const auto path = test::scratch_dir() / "cube.png";
  write_png(scene.render(view_named("iso"), o), path);
  const std::string bytes = read_file(path);
  ASSERT_GT(bytes.size(), 100u);
  EXPECT_EQ(bytes.substr(1, 3), "PNG");
}

}  // namespace
}  // namespace s2c::report
