// reconstruct: loading every input kind, registration against known poses, fusion, meshing.
#include <random>

#include <fmt/format.h>

#include "../test_util.h"
#include "s2c/acquire/simulate.h"
#include "s2c/core/check.h"
#include "s2c/core/distance.h"
#include "s2c/core/errors.h"
#include "s2c/core/io.h"
#include "s2c/core/stream.h"
#include "s2c/reconstruct/reconstruct.h"

namespace fs = std::filesystem;
using namespace s2c;

namespace {

// A small simulated scan of a fixture part (fast: 320×240, 8 views).
fs::path small_scan(const fs::path& dir, const char* part, double noise_mm = 0.05) {
  SimulateOptions o;
  o.noise_mm = noise_mm;
  o.views = 8;
  o.width = 320;
  o.height = 240;
  o.focal_px = 262.5;
  simulate_scan(read_soup(test::source_dir() / "fixtures/parts" / (std::string(part) + ".stl")), dir / "scan", o);
  return dir / "scan";
}

}  // namespace

TEST(Reconstruct, LoadsStreamViewsInTheSensorFrameWithPoses) {
  const auto dir = test::scratch_dir();
  const auto views = load_views({small_scan(dir, "bracket")}, {});
  ASSERT_EQ(views.size(), 8u);
  for (const auto& v : views) {
    ASSERT_TRUE(v.pose.has_value());
    EXPECT_GT(v.points.size(), 1000u);
    EXPECT_EQ(v.points.size(), v.to_sensor.size());
    EXPECT_GT(v.spacing_mm, 0.05);
    EXPECT_LT(v.spacing_mm, 1.0);
    for (std::size_t i = 0; i < v.points.size(); i += 997) EXPECT_GT(v.points[i].z(), 0);  // in front of the sensor
  }
}

TEST(Reconstruct, RefinementRecoversPerturbedPoses) {
  const auto dir = test::scratch_dir();
  auto views = load_views({small_scan(dir, "bracket")}, {});
  std::vector<Eigen::Isometry3d> truth;
  std::mt19937 rng(3);
  std::normal_distribution<double> g(0, 1);
  for (std::size_t i = 0; i < views.size(); ++i) {
    truth.push_back(*views[i].pose);
    if (i == 0) continue;  // one view keeps the true frame
    // 0.5° and 0.3 mm of pose error, as a turntable encoder and a rough calibration give.
    const Eigen::Vector3d axis = Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    Eigen::Isometry3d d = Eigen::Isometry3d::Identity();
    d.linear() = Eigen::AngleAxisd(0.5 * M_PI / 180, axis).toRotationMatrix();
    d.translation() = 0.3 * Eigen::Vector3d(g(rng), g(rng), g(rng)).normalized();
    views[i].pose = *views[i].pose * d;
  }
  std::vector<ViewAlignment> report;
  const auto poses = register_views(views, views[0].spacing_mm, {}, report);
  // What fusion needs is views that agree with each other: for neighbouring views i, j, how far
  // view j's points land from where the truth puts them in view i's frame. The frame of the
  // whole set is only as good as the recorded poses, so it is not asked for.
  auto misfit = [&](const std::vector<Eigen::Isometry3d>& P) {
    double worst = 0;
    for (std::size_t i = 0; i < views.size(); ++i)
      for (std::size_t j : {(i + 1) % views.size(), (i + 2) % views.size()})
        for (std::size_t k = 0; k < views[j].points.size(); k += 97) {
          const Eigen::Vector3d p = views[j].points[k];
          worst = std::max(worst, ((P[i].inverse() * P[j]) * p - (truth[i].inverse() * truth[j]) * p).norm());
        }
    return worst;
  };
  std::vector<Eigen::Isometry3d> recorded;
  for (const auto& v : views) recorded.push_back(*v.pose);
  const double before = misfit(recorded), after = misfit(poses);
  EXPECT_GT(before, 1.0);
  EXPECT_LT(after, 0.5 * before) << "before " << before << " mm, after " << after << " mm";
  for (std::size_t i = 0; i < views.size(); ++i) {
    EXPECT_FALSE(report[i].rejected);
    EXPECT_GT(report[i].overlap, 0.8);
    EXPECT_LT(report[i].rms_mm, 0.15);
  }
}

// Global registration without poses is tested on real data (the Stanford bunny against
// bun.conf, tests/e2e/real_data.sh): the fixture parts are symmetric, where FPFH is ambiguous
// by nature and turntable poses are the way in.

TEST(Reconstruct, ViewsThatDoNotOverlapFailWithAMessage) {
  // A small sphere and a flat sheet: no placement makes most of one lie on the other.
  View a, b;
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < 4000; ++i) {
    const double th = std::acos(1 - 2 * u(rng)), ph = 2 * M_PI * u(rng);
    a.points.emplace_back(5 * std::sin(th) * std::cos(ph), 5 * std::sin(th) * std::sin(ph), 5 * std::cos(th));
    b.points.emplace_back(500 + 40 * u(rng), 500 + 40 * u(rng), 0.0);
  }
  a.spacing_mm = b.spacing_mm = 0.4;
  a.name = "a";
  b.name = "b";
  std::vector<ViewAlignment> report;
  EXPECT_THROW(register_views({a, b}, 0.4, {}, report), ProcessingError);
}

TEST(Reconstruct, FusingConsumedViewsGivesTheSameCloudAndReleasesThem) {
  const auto dir = test::scratch_dir();
  ReconstructOptions o;
  std::vector<View> views = load_views({small_scan(dir, "plate")}, o.input);
  ASSERT_GT(views.size(), 1u);
  const std::vector<Eigen::Isometry3d> poses(views.size(), Eigen::Isometry3d::Identity());
  ReconstructReport kept_rep, consumed_rep;
  kept_rep.spacing_mm = consumed_rep.spacing_mm = 0.5;
  const OrientedCloud kept = fuse_views(views, poses, o, kept_rep);
  ASSERT_FALSE(views.empty());
  const OrientedCloud consumed = fuse_views(std::move(views), poses, o, consumed_rep);
  EXPECT_TRUE(views.empty());  // NOLINT(bugprone-use-after-move): emptied on purpose
  EXPECT_EQ(consumed.points, kept.points);
  EXPECT_EQ(consumed.normals, kept.normals);
  EXPECT_EQ(consumed_rep.points_in, kept_rep.points_in);
}

TEST(Reconstruct, MeshesAScanCloseToThePart) {
  const auto dir = test::scratch_dir();
  const auto part = read_soup(test::source_dir() / "fixtures/parts/plate.stl");
  ReconstructOptions o;
  ReconstructReport rep;
  const OrientedCloud cloud = fuse_input({small_scan(dir, "plate")}, o, rep);
  EXPECT_GT(rep.points_fused, 10000u);
  // Normals point out of the part: from a point, stepping along the normal leaves the solid.
  const SurfaceQuery truth(part);
  std::size_t outward = 0, n = 0;
  for (std::size_t i = 0; i < cloud.points.size(); i += 101, ++n) {
    const auto c = truth.closest(cloud.points[i]);
    const auto& f = part.faces[c->face];
    const Eigen::Vector3d fn = (part.vertices[f[1]] - part.vertices[f[0]]).cross(part.vertices[f[2]] - part.vertices[f[0]]).normalized();
    outward += cloud.normals[i].dot(fn) > 0;
  }
  EXPECT_GT(static_cast<double>(outward) / n, 0.97);
  const Mesh mesh = mesh_cloud(cloud, o, rep);
  const TriangleSoup soup = mesh_to_soup(mesh);
  std::vector<double> d;
  for (const auto& v : soup.vertices) d.push_back(truth.closest(v)->distance);
  std::sort(d.begin(), d.end());
  EXPECT_LT(d[d.size() / 2], 0.05);         // median vertex within 0.05 mm of the true part
  EXPECT_LT(d[d.size() * 95 / 100], 0.25);  // and 95% within 0.25 mm
  EXPECT_EQ(check_mesh(soup).nonmanifold_edges, 0u);
}

TEST(Reconstruct, InputErrorsNameWhatIsWrong) {
  const auto dir = test::scratch_dir();
  fs::create_directories(dir / "tum");
  test::write_text(dir / "tum/depth.txt", "0.0 depth/0.png\n");
  test::expect_invalid_input([&] { load_views({dir / "tum"}, {}); }, {"--intrinsics"});
  test::write_text(dir / "empty.ply", "ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\n"
                                      "property float z\nend_header\n");
  test::expect_invalid_input([&] { load_views({dir / "empty.ply"}, {}); }, {"empty.ply"});
  test::expect_invalid_input([&] { load_views({dir / "missing.pcd"}, {}); }, {"missing.pcd", "no such file"});
  test::expect_invalid_input([&] { parse_intrinsics("525,525,320"); }, {"fx,fy,cx,cy"});
  test::expect_invalid_input([&] { parse_intrinsics("525,-1,320,240"); }, {"positive"});
  fs::create_directories(dir / "nothing");
  test::expect_invalid_input([&] { load_views({dir / "nothing"}, {}); }, {"no stream.yaml"});
}

TEST(Reconstruct, ReadsAPlainFolderOfDepthImagesWithIntrinsics) {
  const auto dir = test::scratch_dir();
  const auto scan = small_scan(dir, "shaft");
  fs::create_directories(dir / "plain");
  fs::copy_file(scan / "depth/000000.png", dir / "plain/a_depth.png");
  InputOptions in;
  in.intrinsics = Eigen::Vector4d(262.5, 262.5, 159.5, 119.5);
  in.depth_unit_mm = read_stream(scan).info.depth_unit_mm;
  const auto views = load_views({dir / "plain"}, in);
  ASSERT_EQ(views.size(), 1u);
  const Stream s = read_stream(scan);
  const auto expected = Deprojector(s.info).sensor_points(read_frame(s, 0));
  ASSERT_EQ(views[0].points.size(), expected.size());
  EXPECT_LT((views[0].points[100] - expected[100]).norm(), 1e-9);
}

TEST(Reconstruct, OrganizedMeshingAndMlsStayOnThePart) {
  const auto dir = test::scratch_dir();
  const auto part = read_soup(test::source_dir() / "fixtures/parts/shaft.stl");
  const SurfaceQuery truth(part);
  const auto scan = small_scan(dir, "shaft");
  for (bool organized : {true, false}) {
    ReconstructOptions o;
    o.method = organized ? MeshMethod::organized : MeshMethod::poisson;
    o.mls_radius_mm = organized ? 0 : -1;  // MLS with the Poisson run
    ReconstructReport rep;
    const Reconstruction r = reconstruct({scan}, o, rep);
    const TriangleSoup soup = mesh_to_soup(r.mesh);
    ASSERT_GT(soup.faces.size(), 1000u);
    std::vector<double> d;
    for (std::size_t i = 0; i < soup.vertices.size(); i += 7) d.push_back(truth.closest(soup.vertices[i])->distance);
    std::sort(d.begin(), d.end());
    EXPECT_LT(d[d.size() / 2], 0.06) << (organized ? "organized" : "poisson+mls");
    if (!organized) {
      EXPECT_GT(rep.mls_radius_mm, 0);
    }
  }
}

TEST(Reconstruct, ImlsMeshesAScanCloseToThePartWithoutInventingSurface) {
  const auto dir = test::scratch_dir();
  const auto part = read_soup(test::source_dir() / "fixtures/parts/plate.stl");
  const SurfaceQuery truth(part);
  const auto scan = small_scan(dir, "plate");
  std::size_t simplified_faces = 0, raw_faces = 0;
  for (double simplify : {-1.0, 0.0}) {
    ReconstructOptions o;
    o.method = MeshMethod::imls;
    o.simplify_mm = simplify;
    ReconstructReport rep;
    const Reconstruction r = reconstruct({scan}, o, rep);
    SCOPED_TRACE(simplify < 0 ? "simplified" : "raw");
    EXPECT_NEAR(rep.voxel_mm, 1.5 * rep.spacing_mm, 1e-12);  // the imls default grid
    EXPECT_NEAR(rep.imls_support_mm, 2.5 * rep.voxel_mm, 1e-12);
    const TriangleSoup soup = mesh_to_soup(r.mesh);
    std::vector<double> d;
    for (const auto& v : soup.vertices) d.push_back(truth.closest(v)->distance);
    std::sort(d.begin(), d.end());
    EXPECT_LT(d[d.size() / 2], 0.05);
    EXPECT_LT(d[d.size() * 99 / 100], 0.25);
    // No surface where the scanner saw nothing: the plate's Ø6 holes' walls are unseen, so the
    // mesh stays open there, as the trimmed Poisson mesh does.
    const CheckResult c = check_mesh(soup);
    EXPECT_GT(c.boundary_loops, 0u);
    EXPECT_EQ(c.nonmanifold_edges, 0u);
    (simplify < 0 ? simplified_faces : raw_faces) = soup.faces.size();
    if (simplify < 0) {
      EXPECT_NEAR(rep.simplify_mm, 0.1 * rep.voxel_mm, 1e-12);
    }
  }
  EXPECT_LT(simplified_faces, raw_faces * 3 / 4);
}

TEST(Reconstruct, PoissonIsDecimatedWithinATenthOfTheVoxel) {
  // PCL's Poisson gives flat faces as many triangles as fillets; --simplify's default decimates
  // it within a tenth of the voxel: far fewer faces, every vertex within the bound of the raw
  // surface, as close to the part, and the unseen regions still open. 0 keeps Poisson's mesh.
  const auto dir = test::scratch_dir();
  const auto part = read_soup(test::source_dir() / "fixtures/parts/plate.stl");
  const SurfaceQuery truth(part);  // (holds the soup: not a temporary)
  const auto scan = small_scan(dir, "plate");
  ReconstructOptions o;  // Poisson, simplify_mm < 0: the default
  ReconstructReport rep;
  const TriangleSoup simplified = mesh_to_soup(reconstruct({scan}, o, rep).mesh);
  o.simplify_mm = 0;
  ReconstructReport raw_rep;
  const TriangleSoup raw = mesh_to_soup(reconstruct({scan}, o, raw_rep).mesh);
  EXPECT_NEAR(rep.simplify_mm, 0.1 * rep.voxel_mm, 1e-12);
  EXPECT_EQ(raw_rep.simplify_mm, 0.0);
  EXPECT_EQ(raw_rep.faces, raw.faces.size());
  EXPECT_LT(simplified.faces.size(), raw.faces.size() * 3 / 5);
  const SurfaceQuery before(raw);
  auto median_to_part = [&](const TriangleSoup& m) {
    std::vector<double> d;
    for (const auto& v : m.vertices) d.push_back(truth.closest(v)->distance);
    std::nth_element(d.begin(), d.begin() + d.size() / 2, d.end());
    return d[d.size() / 2];
  };
  double farthest = 0;
  for (const auto& v : simplified.vertices) farthest = std::max(farthest, before.closest(v)->distance);
  EXPECT_LE(farthest, rep.simplify_mm * 1.001);
  // (vertices: the flat faces lose theirs, the curved keep more, so the median moves a little)
  EXPECT_LT(median_to_part(simplified), median_to_part(raw) + 0.5 * rep.simplify_mm);
  const CheckResult c = check_mesh(simplified), c_raw = check_mesh(raw);
  EXPECT_EQ(c.boundary_loops, c_raw.boundary_loops);
  EXPECT_EQ(c.nonmanifold_edges, 0u);
}

TEST(Reconstruct, AnOrganizedCloudIsSeenFromItsViewpoint) {
  // A 4×3 organized PCD (one NaN) with the sensor at (0, 0, -100) mm: each point's direction to
  // the sensor orients its normal; a PLY cloud, organized or not, has no sensor (empty).
  const auto dir = test::scratch_dir();
  std::string pcd = "# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 4\nHEIGHT 3\n"
                    "VIEWPOINT 0 0 -100 1 0 0 0\nPOINTS 12\nDATA ascii\n";
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 4; ++c) pcd += (r == 1 && c == 2) ? "nan nan nan\n" : fmt::format("{} {} 50\n", c * 10, r * 10);
  test::write_text(dir / "organized.pcd", pcd);
  const auto views = load_views({dir / "organized.pcd"}, {});
  ASSERT_EQ(views.size(), 1u);
  const View& v = views[0];
  ASSERT_EQ(v.points.size(), 11u);
  ASSERT_EQ(v.to_sensor.size(), 11u);
  for (std::size_t i = 0; i < v.points.size(); ++i) {
    const Eigen::Vector3d expected = (Eigen::Vector3d(0, 0, -100) - v.points[i]).normalized();
    EXPECT_LT((v.to_sensor[i] - expected).norm(), 1e-9) << i;
  }
  test::write_text(dir / "loose.ply", "ply\nformat ascii 1.0\nelement vertex 12\nproperty float x\nproperty float y\n"
                                       "property float z\nend_header\n" +
                                           [] {
                                             std::string s;
                                             for (int k = 0; k < 12; ++k) s += fmt::format("{} {} 50\n", k % 4, k / 4);
                                             return s;
                                           }());
  EXPECT_TRUE(load_views({dir / "loose.ply"}, {})[0].to_sensor.empty());
}

TEST(Reconstruct, ImlsWidensItsSupportOnANoisyScan) {
  // σ = 0.4 mm at about 0.3 mm spacing: the noise of an RGB-D frame relative to its sampling. At
  // 2.5 voxels the band breaks up into bubbles; the support follows the measured noise instead.
  const auto dir = test::scratch_dir();
  const auto scan = small_scan(dir, "plate", 0.4);
  ReconstructOptions o;
  o.method = MeshMethod::imls;
  o.simplify_mm = 0;
  ReconstructReport adaptive;
  const CheckResult wide = check_mesh(mesh_to_soup(reconstruct({scan}, o, adaptive).mesh));
  EXPECT_GT(adaptive.imls_noise_mm, 0.45 * adaptive.voxel_mm);
  EXPECT_NEAR(adaptive.imls_support_mm, std::min(10 * adaptive.imls_noise_mm, 7.5 * adaptive.voxel_mm), 1e-9);
  o.imls_support_mm = 2.5 * adaptive.voxel_mm;
  ReconstructReport fixed;
  const CheckResult narrow = check_mesh(mesh_to_soup(reconstruct({scan}, o, fixed).mesh));
  EXPECT_LT(wide.components * 4, narrow.components) << "adaptive " << wide.components << ", 2.5 voxels " << narrow.components;
  EXPECT_LT(wide.boundary_loops * 4, narrow.boundary_loops) << "adaptive " << wide.boundary_loops << ", 2.5 voxels " << narrow.boundary_loops;
  // The clean scan keeps 2.5 voxels.
  ReconstructReport clean;
  o.imls_support_mm = 0;
  reconstruct({small_scan(dir / "clean", "plate")}, o, clean);
  EXPECT_LT(clean.imls_noise_mm, 0.45 * clean.voxel_mm);
  EXPECT_NEAR(clean.imls_support_mm, 2.5 * clean.voxel_mm, 1e-12);
}
