// Shapes and their fits (features/include/s2c/features/shape.h). The surface samples are laid out
// like the caller makes them from OpenSCAD meshes: vertices on rings joined by long skinny
// triangles, each vertex with its faces' mean normal and a third of their area, plus the face
// centroids with face normals and areas.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <random>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Geometry>

#include "s2c/core/errors.h"
#include "s2c/features/shape.h"

namespace {

using namespace s2c::features;
using Eigen::Vector3d;

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double signed_angle_deg(const Vector3d& a, const Vector3d& b) {  // atan2: precise for tiny angles too
  return std::atan2(a.cross(b).norm(), a.dot(b)) * 180.0 / M_PI;
}
double axis_angle_deg(const Vector3d& a, const Vector3d& b) {  // sign-insensitive
  return std::min(signed_angle_deg(a, b), signed_angle_deg(a, -b));
}
double line_distance(const Vector3d& p, const Vector3d& point, const Vector3d& dir) {
  const Vector3d d = p - point;
  return (d - dir.normalized() * dir.normalized().dot(d)).norm();
}

/// A rigid placement, so the fits are tested away from the world axes too.
struct Pose {
  Eigen::Matrix3d R = Eigen::Matrix3d::Identity();
  Vector3d t = Vector3d::Zero();
  Vector3d apply(const Vector3d& p) const { return R * p + t; }
};
Pose tilted() {
  Pose p;
  p.R = Eigen::AngleAxisd(0.7, Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  p.t = Vector3d(12.5, -7.25, 30.0);
  return p;
}

struct Revolution {
  std::vector<std::pair<double, double>> rings;  ///< (z, r) about +z, in mesh order
  int segments = 96;
  double sweep_deg = 360.0;  ///< 360: closed rings
  bool inward = false;       ///< faces turned towards the axis (a hole)
  double noise = 0.0;        ///< Gaussian σ per coordinate of the vertices, mm
  bool centroids = true;     ///< add the face centroids as samples
  bool normals = true;
};

/// The samples of a surface of revolution meshed as OpenSCAD does, placed by `pose`.
Samples revolution_samples(const Revolution& rv, const Pose& pose = {}) {
  const bool closed = rv.sweep_deg >= 360.0;
  const int m = closed ? rv.segments : rv.segments + 1;
  const int rings = static_cast<int>(rv.rings.size());
  std::mt19937 rng(7);
  std::normal_distribution<double> gauss(0.0, rv.noise > 0 ? rv.noise : 1.0);
  std::vector<Vector3d> v;
  for (const auto& [z, r] : rv.rings)
    for (int j = 0; j < m; ++j) {
      const double phi = rv.sweep_deg * M_PI / 180.0 * j / rv.segments;
      Vector3d p = pose.apply(Vector3d(r * std::cos(phi), r * std::sin(phi), z));
      if (rv.noise > 0) p += Vector3d(gauss(rng), gauss(rng), gauss(rng));
      v.push_back(p);
    }
  std::vector<std::array<int, 3>> faces;
  for (int k = 0; k + 1 < rings; ++k)
    for (int j = 0; j < rv.segments; ++j) {
      const int j1 = closed ? (j + 1) % m : j + 1;
      const int a = k * m + j, b = k * m + j1, c = (k + 1) * m + j1, d = (k + 1) * m + j;
      if (rv.inward) {
        faces.push_back({a, c, b});
        faces.push_back({a, d, c});
      } else {
        faces.push_back({a, b, c});
        faces.push_back({a, c, d});
      }
    }
  Samples s;
  s.points = v;
  s.normals.assign(v.size(), Vector3d::Zero());
  s.weights.assign(v.size(), 0.0);
  std::vector<Vector3d> fc, fn;
  std::vector<double> fa;
  for (const auto& f : faces) {
    const Vector3d cr = (v[f[1]] - v[f[0]]).cross(v[f[2]] - v[f[0]]);
    const double area = 0.5 * cr.norm();
    for (int i : f) {
      s.normals[i] += 0.5 * cr;
      s.weights[i] += area / 3.0;
    }
    fc.push_back((v[f[0]] + v[f[1]] + v[f[2]]) / 3.0);
    fn.push_back(cr.normalized());
    fa.push_back(area);
  }
  for (auto& n : s.normals) n.normalize();
  if (rv.centroids) {
    s.points.insert(s.points.end(), fc.begin(), fc.end());
    s.normals.insert(s.normals.end(), fn.begin(), fn.end());
    s.weights.insert(s.weights.end(), fa.begin(), fa.end());
  }
  if (!rv.normals) s.normals.clear();
  return s;
}

/// Hemisphere of radius R about the origin as rings of latitude 0°..80°.
Revolution hemisphere(double R, int segments) {
  Revolution rv;
  rv.segments = segments;
  for (int lat = 0; lat <= 80; lat += 10)
    rv.rings.emplace_back(R * std::sin(lat * M_PI / 180.0), R * std::cos(lat * M_PI / 180.0));
  return rv;
}

void expect_cylinder(const Fit& f, const Pose& pose, double radius, const char* what, double tol_scale = 1.0) {
  ASSERT_TRUE(f.ok) << what;
  ASSERT_EQ(f.shape.type, ShapeType::cylinder);
  const Vector3d axis = pose.R * Vector3d::UnitZ();
  const double da = axis_angle_deg(f.shape.dir, axis), dp = line_distance(pose.t, f.shape.point, f.shape.dir);
  const double dr = std::abs(f.shape.radius - radius) / radius;
  std::printf("[ measured ] %s: axis %.2e deg, axis offset %.2e mm, radius %.2e rel, rms %.2e mm, normal rms %.2f deg\n",
              what, da, dp, dr, f.rms, f.normal_rms_deg);
  EXPECT_LE(da, 0.5 * tol_scale) << what;
  EXPECT_LE(dp, 0.05 * tol_scale) << what;
  EXPECT_LE(dr, 0.01 * tol_scale) << what;
  EXPECT_NEAR(f.shape.dir.norm(), 1.0, 1e-9);
}

void expect_cone(const Fit& f, const Pose& pose, const Vector3d& apex, double half_angle, const char* what,
                 double tol_scale = 1.0) {
  ASSERT_TRUE(f.ok) << what;
  ASSERT_EQ(f.shape.type, ShapeType::cone);
  const Vector3d axis = pose.R * Vector3d::UnitZ();
  const double da = signed_angle_deg(f.shape.dir, axis);  // must point into the opening
  const double dp = (f.shape.point - pose.apply(apex)).norm();
  const double dh = std::abs(f.shape.half_angle_deg - half_angle);
  std::printf("[ measured ] %s: axis %.2e deg, apex %.2e mm, half angle %.2e deg, rms %.2e mm, normal rms %.2f deg\n",
              what, da, dp, dh, f.rms, f.normal_rms_deg);
  EXPECT_LE(da, 0.5 * tol_scale) << what;
  EXPECT_LE(dp, 0.05 * tol_scale) << what;
  EXPECT_LE(dh, 0.5 * tol_scale) << what;
}

Samples points_only(std::vector<Vector3d> p) {
  Samples s;
  s.points = std::move(p);
  return s;
}

// ---------------------------------------------------------------------------------------------
// Shapes

TEST(ShapeNames, RoundTripAndSurfaces) {
  for (ShapeType t : {ShapeType::freeform, ShapeType::plane, ShapeType::cylinder, ShapeType::sphere, ShapeType::cone,
                      ShapeType::line, ShapeType::circle, ShapeType::arc})
    EXPECT_EQ(shape_type(shape_name(t)), t) << shape_name(t);
  EXPECT_STREQ(shape_name(ShapeType::cylinder), "cylinder");
  EXPECT_THROW(shape_type("torus"), s2c::InvalidInput);
  EXPECT_THROW(shape_type(""), s2c::InvalidInput);
  EXPECT_TRUE(is_surface(ShapeType::plane) && is_surface(ShapeType::cylinder) && is_surface(ShapeType::sphere) &&
              is_surface(ShapeType::cone));
  EXPECT_FALSE(is_surface(ShapeType::line) || is_surface(ShapeType::circle) || is_surface(ShapeType::arc) ||
               is_surface(ShapeType::freeform));
}

TEST(ShapeDistance, EveryType) {
  Shape plane;
  plane.type = ShapeType::plane;
  plane.point = {0, 0, 1};
  EXPECT_NEAR(distance(plane, {5, -3, 4}), 3.0, 1e-12);
  EXPECT_NEAR(distance(plane, {5, -3, -1}), 2.0, 1e-12);

  Shape cyl;
  cyl.type = ShapeType::cylinder;
  cyl.point = {1, 1, 0};
  cyl.radius = 2;
  EXPECT_NEAR(distance(cyl, {1, 5, 40}), 2.0, 1e-12);
  EXPECT_NEAR(distance(cyl, {1.5, 1, -3}), 1.5, 1e-12);

  Shape sph;
  sph.type = ShapeType::sphere;
  sph.radius = 5;
  EXPECT_NEAR(distance(sph, {0, 3, 4}), 0.0, 1e-12);
  EXPECT_NEAR(distance(sph, {0, 0, 1}), 4.0, 1e-12);

  // Cone: apex (0,0,-8), opening +z, 45°: the frustum r = 8 at z = 0.
  Shape cone;
  cone.type = ShapeType::cone;
  cone.point = {0, 0, -8};
  cone.half_angle_deg = 45;
  EXPECT_NEAR(distance(cone, {8, 0, 0}), 0.0, 1e-12);
  EXPECT_NEAR(distance(cone, {0, 10, 2}), 0.0, 1e-12);
  EXPECT_NEAR(distance(cone, {0, 0, 0}), 8.0 / std::sqrt(2.0), 1e-12);   // on the axis, inside
  EXPECT_NEAR(distance(cone, {9, 0, 0}), 1.0 / std::sqrt(2.0), 1e-12);   // outside
  EXPECT_NEAR(distance(cone, {0, 0, -10}), 2.0, 1e-12);                  // behind the apex: the apex
  EXPECT_NEAR(distance(cone, {3, 0, -12}), 5.0, 1e-12);                  // the other nappe does not count

  Shape line;
  line.type = ShapeType::line;
  line.point = {0, 0, 0};
  line.dir = {1, 0, 0};
  line.length = 10;
  EXPECT_NEAR(distance(line, {5, 2, 0}), 2.0, 1e-12);
  EXPECT_NEAR(distance(line, {13, 4, 0}), 5.0, 1e-12);  // beyond the end: to the end point
  EXPECT_NEAR(distance(line, {-3, 0, 4}), 5.0, 1e-12);

  Shape circle;
  circle.type = ShapeType::circle;
  circle.radius = 3;
  EXPECT_NEAR(distance(circle, {0, 7, 3}), 5.0, 1e-12);
  EXPECT_NEAR(distance(circle, {0, 0, 4}), 5.0, 1e-12);
  Shape arc = circle;  // arcs measure to the full circle
  arc.type = ShapeType::arc;
  EXPECT_NEAR(distance(arc, {-3, 0, 0}), 0.0, 1e-12);

  Shape freeform;
  EXPECT_EQ(distance(freeform, {1, 2, 3}), 0.0);
}

TEST(ShapeNormal, EveryType) {
  Shape plane;
  plane.type = ShapeType::plane;
  plane.dir = Vector3d(0, 1, 0);
  EXPECT_TRUE(surface_normal(plane, {3, 4, 5}).isApprox(Vector3d(0, 1, 0)));

  Shape cyl;
  cyl.type = ShapeType::cylinder;
  cyl.point = {1, 1, 0};
  cyl.radius = 2;
  EXPECT_TRUE(surface_normal(cyl, {1, -5, 7}).isApprox(Vector3d(0, -1, 0)));  // radial, outward
  EXPECT_TRUE(surface_normal(cyl, {2, 1, -7}).isApprox(Vector3d(1, 0, 0)));   // from inside too

  Shape sph;
  sph.type = ShapeType::sphere;
  sph.point = {1, 0, 0};
  EXPECT_TRUE(surface_normal(sph, {1, 0, -4}).isApprox(Vector3d(0, 0, -1)));

  Shape cone;
  cone.type = ShapeType::cone;
  cone.point = {0, 0, -8};
  cone.half_angle_deg = 45;
  const Vector3d n = surface_normal(cone, {8, 0, 0});
  EXPECT_TRUE(n.isApprox(Vector3d(1, 0, -1).normalized())) << n.transpose();
  EXPECT_NEAR(n.norm(), 1.0, 1e-12);
  EXPECT_EQ(surface_normal(cone, {0, 0, 3}), Vector3d::Zero());  // on the axis: undefined

  Shape line;
  line.type = ShapeType::line;
  EXPECT_EQ(surface_normal(line, {1, 2, 3}), Vector3d::Zero());
  Shape circle;
  circle.type = ShapeType::circle;
  EXPECT_EQ(surface_normal(circle, {1, 2, 3}), Vector3d::Zero());
}

// ---------------------------------------------------------------------------------------------
// Plane

Samples plane_grid(const Pose& pose, double noise, bool flip_normals) {
  std::mt19937 rng(3);
  std::normal_distribution<double> gauss(0.0, noise > 0 ? noise : 1.0);
  Samples s;
  for (int i = 0; i < 25; ++i)
    for (int j = 0; j < 18; ++j) {
      Vector3d p = pose.apply(Vector3d(-20 + 1.7 * i, -10 + 1.3 * j, 0));
      if (noise > 0) p += Vector3d(gauss(rng), gauss(rng), gauss(rng));
      s.points.push_back(p);
      s.normals.push_back((flip_normals ? -1.0 : 1.0) * (pose.R * Vector3d::UnitZ()));
      s.weights.push_back(1.0 + 0.1 * (i % 3));
    }
  return s;
}

TEST(FitPlane, TiltedGridAndNormalOrientation) {
  const Pose pose = tilted();
  const Vector3d n = pose.R * Vector3d::UnitZ();
  for (bool flip : {false, true}) {
    const Fit f = fit_plane(plane_grid(pose, 0.0, flip));
    ASSERT_TRUE(f.ok);
    EXPECT_EQ(f.shape.type, ShapeType::plane);
    EXPECT_LE(signed_angle_deg(f.shape.dir, flip ? Vector3d(-n) : n), 0.5);  // follows the sample normals
    EXPECT_LE(std::abs(n.dot(f.shape.point - pose.t)), 0.05);
    EXPECT_LT(f.rms, 1e-9);
    EXPECT_LT(f.max_error, 1e-9);
    EXPECT_LT(f.normal_rms_deg, 1e-3);
  }
}

TEST(FitPlane, NoisyRmsNearSigma) {
  const double sigma = 0.05;
  const Pose pose = tilted();
  const Fit f = fit_plane(plane_grid(pose, sigma, false));
  ASSERT_TRUE(f.ok);
  EXPECT_LE(axis_angle_deg(f.shape.dir, pose.R * Vector3d::UnitZ()), 0.5);
  EXPECT_LE(std::abs((pose.R * Vector3d::UnitZ()).dot(f.shape.point - pose.t)), 0.05);
  EXPECT_GT(f.rms, 0.8 * sigma);
  EXPECT_LT(f.rms, 1.2 * sigma);
  EXPECT_GT(f.max_error, 2 * sigma);
}

// ---------------------------------------------------------------------------------------------
// Cylinder

TEST(FitCylinder, TwoRingThroughHole) {
  // A through-hole: two rings of 96 vertices at z = 0 and 8, radius 3, faces turned inwards.
  Revolution rv;
  rv.rings = {{0.0, 3.0}, {8.0, 3.0}};
  rv.inward = true;
  for (const Pose& pose : {Pose{}, tilted()}) {
    const Samples s = revolution_samples(rv, pose);
    const Fit f = fit_cylinder(s);
    expect_cylinder(f, pose, 3.0, "two-ring hole");
    EXPECT_LT(f.rms, 0.005);
    EXPECT_LT(f.normal_rms_deg, 2.0);  // inward normals agree (unsigned)
    // The face centroids rule out the sphere through both rings; a plane is far off.
    const Fit sphere = fit_sphere(s), plane = fit_plane(s);
    if (sphere.ok) {
      EXPECT_GT(sphere.rms, 20 * f.rms);
    }
    ASSERT_TRUE(plane.ok);
    EXPECT_GT(plane.rms, 100 * f.rms);
  }
}

TEST(FitCylinder, TwoRingWithoutNormals) {
  Revolution rv;
  rv.rings = {{0.0, 3.0}, {8.0, 3.0}};
  rv.normals = false;
  const Pose pose = tilted();
  expect_cylinder(fit_cylinder(revolution_samples(rv, pose)), pose, 3.0, "two-ring, no normals");
}

TEST(FitCylinder, TwoRingVerticesOnlyAndNoisy) {
  Revolution rv;
  rv.rings = {{0.0, 3.0}, {8.0, 3.0}};
  rv.centroids = false;
  const Pose pose = tilted();
  expect_cylinder(fit_cylinder(revolution_samples(rv, pose)), pose, 3.0, "two-ring hole, vertices");
  rv.centroids = true;
  rv.noise = 0.02;
  expect_cylinder(fit_cylinder(revolution_samples(rv, pose)), pose, 3.0, "two-ring hole, noisy", 2.0);
}

TEST(FitCylinder, ShortWideRing) {
  // Height 2, radius 20: the axis is the smallest principal axis, not the largest.
  Revolution rv;
  rv.rings = {{0.0, 20.0}, {2.0, 20.0}};
  rv.segments = 180;
  const Pose pose = tilted();
  for (bool normals : {true, false}) {
    rv.normals = normals;
    expect_cylinder(fit_cylinder(revolution_samples(rv, pose)), pose, 20.0,
                    normals ? "short wide ring" : "short wide ring, no normals");
  }
}

TEST(FitCylinder, HalfCylinder) {
  Revolution rv;
  rv.rings = {{0.0, 10.0}, {25.0, 10.0}};
  rv.segments = 48;
  rv.sweep_deg = 180;
  const Pose pose = tilted();
  const Fit f = fit_cylinder(revolution_samples(rv, pose));
  expect_cylinder(f, pose, 10.0, "half cylinder");
}

TEST(FitCylinder, QuarterSectorFillet) {
  // A fillet: 90° of radius 4, few segments (its centroids sit 0.4% inside the radius).
  Revolution rv;
  rv.rings = {{0.0, 4.0}, {30.0, 4.0}};
  rv.segments = 8;
  rv.sweep_deg = 90;
  for (bool normals : {true, false}) {
    rv.normals = normals;
    const Pose pose = tilted();
    expect_cylinder(fit_cylinder(revolution_samples(rv, pose)), pose, 4.0,
                    normals ? "90 deg fillet" : "90 deg fillet, no normals");
  }
}

TEST(FitCylinder, NoisyRmsNearSigmaAndPlaneMuchWorse) {
  const double sigma = 0.05;
  Revolution rv;
  for (int k = 0; k <= 40; ++k) rv.rings.emplace_back(k * 1.0, 8.0);
  rv.segments = 120;
  rv.noise = sigma;
  rv.centroids = false;
  const Pose pose = tilted();
  const Samples s = revolution_samples(rv, pose);
  const Fit f = fit_cylinder(s);
  expect_cylinder(f, pose, 8.0, "noisy cylinder");
  EXPECT_GT(f.rms, 0.8 * sigma);
  EXPECT_LT(f.rms, 1.2 * sigma);
  const Fit plane = fit_plane(s);
  ASSERT_TRUE(plane.ok);
  EXPECT_GT(plane.rms, 20 * f.rms);
  EXPECT_GT(plane.normal_rms_deg, 30.0);
}

TEST(FitCylinder, NoisyQuarterSector) {
  const double sigma = 0.03;
  Revolution rv;
  for (int k = 0; k <= 30; ++k) rv.rings.emplace_back(k * 1.0, 6.0);
  rv.segments = 24;
  rv.sweep_deg = 90;
  rv.noise = sigma;
  rv.centroids = false;
  const Pose pose = tilted();
  const Fit f = fit_cylinder(revolution_samples(rv, pose));
  expect_cylinder(f, pose, 6.0, "noisy 90 deg sector");
  EXPECT_GT(f.rms, 0.7 * sigma);
  EXPECT_LT(f.rms, 1.2 * sigma);
}

TEST(FitCylinder, LargePatchIsSubsampled) {
  Revolution rv;
  for (int k = 0; k < 300; ++k) rv.rings.emplace_back(k * 0.1, 12.0);
  rv.segments = 1000;  // 300k vertices
  rv.centroids = false;
  rv.noise = 0.02;
  const Pose pose = tilted();
  const Samples s = revolution_samples(rv, pose);
  const auto t0 = std::chrono::steady_clock::now();
  const Fit f = fit_cylinder(s);
  const double ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0).count();
  std::printf("[ measured ] cylinder fit of %zu samples: %.0f ms\n", s.points.size(), ms);
  expect_cylinder(f, pose, 12.0, "300k-sample cylinder");
  EXPECT_GT(f.rms, 0.8 * 0.02);
  EXPECT_LT(f.rms, 1.2 * 0.02);
}

// ---------------------------------------------------------------------------------------------
// Cone

TEST(FitCone, TwoRingFrustum) {
  // Ring r = 8 at z = 0, ring r = 10 at z = 2: 45°, apex (0, 0, -8), opening +z.
  Revolution rv;
  rv.rings = {{0.0, 8.0}, {2.0, 10.0}};
  for (const Pose& pose : {Pose{}, tilted()}) {
    const Samples s = revolution_samples(rv, pose);
    const Fit f = fit_cone(s);
    expect_cone(f, pose, Vector3d(0, 0, -8), 45.0, "two-ring frustum");
    EXPECT_LT(f.rms, 0.01);
    EXPECT_LT(f.normal_rms_deg, 2.0);
    const Fit cyl = fit_cylinder(s), sphere = fit_sphere(s);
    std::printf("[ measured ] two-ring frustum: cone rms %.2e, cylinder rms %.2e, sphere rms %.2e mm\n", f.rms,
                cyl.rms, sphere.rms);
    if (cyl.ok) {
      EXPECT_GT(cyl.rms, 20 * f.rms);
    }
    if (sphere.ok) {
      EXPECT_GT(sphere.rms, 5 * f.rms);
    }
  }
}

TEST(FitCone, TwoRingVerticesOnlyAndNoisy) {
  // The vertices alone (no centroids), and the same mesh with 0.02 mm of vertex noise (its
  // normals then come from the noisy skinny triangles).
  Revolution rv;
  rv.rings = {{0.0, 8.0}, {2.0, 10.0}};
  rv.centroids = false;
  const Pose pose = tilted();
  expect_cone(fit_cone(revolution_samples(rv, pose)), pose, Vector3d(0, 0, -8), 45.0, "two-ring frustum, vertices");
  rv.centroids = true;
  rv.noise = 0.02;
  expect_cone(fit_cone(revolution_samples(rv, pose)), pose, Vector3d(0, 0, -8), 45.0, "two-ring frustum, noisy", 2.0);
}

TEST(FitCone, NearlyACylinder) {
  const double t = std::tan(3.0 * M_PI / 180.0);
  Revolution rv;
  rv.rings = {{0.0, 5.0}, {20.0, 5.0 + 20.0 * t}};
  const Pose pose = tilted();
  expect_cone(fit_cone(revolution_samples(rv, pose)), pose, Vector3d(0, 0, -5.0 / t), 3.0, "3 deg cone");
}

TEST(FitCone, CountersinkInwardNormals) {
  // A conical hole, faces turned inwards, 30° half angle: apex at z = -3 / tan 30°.
  const double t = std::tan(30.0 * M_PI / 180.0);
  Revolution rv;
  rv.rings = {{0.0, 3.0}, {5.0, 3.0 + 5.0 * t}};
  rv.inward = true;
  rv.segments = 64;
  const Pose pose = tilted();
  const Fit f = fit_cone(revolution_samples(rv, pose));
  expect_cone(f, pose, Vector3d(0, 0, -3.0 / t), 30.0, "countersink");
}

TEST(FitCone, OpeningDownwards) {
  // Rings in the other order and the cone opening towards −z: dir must still point into the opening.
  Revolution rv;
  rv.rings = {{0.0, 10.0}, {6.0, 4.0}};  // apex at z = 10, opening −z, 45°
  const Fit f = fit_cone(revolution_samples(rv));
  ASSERT_TRUE(f.ok);
  EXPECT_LE(signed_angle_deg(f.shape.dir, -Vector3d::UnitZ()), 0.5);
  EXPECT_LE((f.shape.point - Vector3d(0, 0, 10)).norm(), 0.05);
  EXPECT_NEAR(f.shape.half_angle_deg, 45.0, 0.5);
}

TEST(FitCone, NoisyRmsNearSigma) {
  const double sigma = 0.03;
  const double t = std::tan(20.0 * M_PI / 180.0);
  Revolution rv;
  for (int k = 0; k <= 30; ++k) rv.rings.emplace_back(k * 1.0, 5.0 + k * t);  // apex z = -5 / tan 20°
  rv.segments = 120;
  rv.noise = sigma;
  rv.centroids = false;
  const Pose pose = tilted();
  const Fit f = fit_cone(revolution_samples(rv, pose));
  expect_cone(f, pose, Vector3d(0, 0, -5.0 / t), 20.0, "noisy cone", 2.0);
  EXPECT_GT(f.rms, 0.8 * sigma);
  EXPECT_LT(f.rms, 1.2 * sigma);
}

TEST(FitCone, WithoutNormals) {
  // No normals: axis candidates from the principal axes and an algebraic cone start.
  Revolution rv;
  rv.rings = {{0.0, 8.0}, {2.0, 10.0}};
  rv.normals = false;
  const Pose pose = tilted();
  expect_cone(fit_cone(revolution_samples(rv, pose)), pose, Vector3d(0, 0, -8), 45.0, "two-ring frustum, no normals");
  const double t = std::tan(20.0 * M_PI / 180.0);
  Revolution dense;
  for (int k = 0; k <= 30; ++k) dense.rings.emplace_back(k * 1.0, 5.0 + k * t);
  dense.segments = 120;
  dense.noise = 0.03;
  dense.centroids = false;
  dense.normals = false;
  expect_cone(fit_cone(revolution_samples(dense, pose)), pose, Vector3d(0, 0, -5.0 / t), 20.0, "noisy cone, no normals",
              2.0);
}

TEST(FitCone, OfACylinderIsNotAConvincingCone) {
  Revolution rv;
  rv.rings = {{0.0, 3.0}, {8.0, 3.0}};
  const Fit f = fit_cone(revolution_samples(rv));
  if (f.ok) {
    EXPECT_LT(f.shape.half_angle_deg, 1.0);
  }
}

// ---------------------------------------------------------------------------------------------
// Sphere

TEST(FitSphere, HemisphereRings) {
  const Pose pose = tilted();
  const Fit f = fit_sphere(revolution_samples(hemisphere(12.0, 72), pose));
  ASSERT_TRUE(f.ok);
  EXPECT_EQ(f.shape.type, ShapeType::sphere);
  EXPECT_LE((f.shape.point - pose.t).norm(), 0.05);
  EXPECT_NEAR(f.shape.radius, 12.0, 0.12);
  EXPECT_LT(f.normal_rms_deg, 2.0);
}

TEST(FitSphere, NoisyRmsNearSigma) {
  const double sigma = 0.05;
  Revolution rv = hemisphere(20.0, 90);
  rv.rings.clear();
  for (int lat = 0; lat <= 85; lat += 3)
    rv.rings.emplace_back(20.0 * std::sin(lat * M_PI / 180.0), 20.0 * std::cos(lat * M_PI / 180.0));
  rv.noise = sigma;
  rv.centroids = false;
  const Pose pose = tilted();
  const Fit f = fit_sphere(revolution_samples(rv, pose));
  ASSERT_TRUE(f.ok);
  EXPECT_LE((f.shape.point - pose.t).norm(), 0.05);
  EXPECT_NEAR(f.shape.radius, 20.0, 0.2);
  EXPECT_GT(f.rms, 0.8 * sigma);
  EXPECT_LT(f.rms, 1.2 * sigma);
}

// ---------------------------------------------------------------------------------------------
// Refits from an earlier shape (a growing region refits from its fit before the growth)

/// `shape` moved a little: axis tilted by `deg`, point shifted by `mm`, radius and half angle off.
Shape nudged(Shape shape, double deg, double mm) {
  const Vector3d tilt_axis = shape.dir.unitOrthogonal();
  shape.dir = Eigen::AngleAxisd(deg * M_PI / 180.0, tilt_axis) * shape.dir;
  shape.point += mm * Vector3d(0.6, -0.48, 0.64);
  shape.radius *= 1.03;
  if (shape.type == ShapeType::cone) shape.half_angle_deg += 2.0;
  return shape;
}

TEST(FitSurface, RefitFromANearbyStartFindsTheShape) {
  const Pose pose = tilted();
  Revolution cyl;
  for (int k = 0; k <= 30; ++k) cyl.rings.emplace_back(k * 1.0, 6.0);
  cyl.segments = 24;
  cyl.sweep_deg = 120;
  cyl.noise = 0.01;
  const Samples cs = revolution_samples(cyl, pose);
  const Fit cf = fit_cylinder(cs);
  const Fit cr = refit_surface(cs, nudged(cf.shape, 3.0, 0.3));
  expect_cylinder(cr, pose, 6.0, "cylinder refit from a nudged start");
  EXPECT_NEAR(cr.rms, cf.rms, 1e-6 * cf.rms);

  Revolution cone;
  for (int k = 0; k <= 8; ++k) cone.rings.emplace_back(0.25 * k, 8.0 + 0.25 * k);  // 45°, apex (0, 0, −8)
  cone.noise = 0.01;
  const Samples ks = revolution_samples(cone, pose);
  const Fit kf = fit_cone(ks);
  const Fit kr = refit_surface(ks, nudged(kf.shape, 3.0, 0.3));
  expect_cone(kr, pose, Vector3d(0, 0, -8), 45.0, "cone refit from a nudged start");
  EXPECT_NEAR(kr.rms, kf.rms, 1e-6 * kf.rms);
  // A start with the axis reversed and the apex moved past the samples: still this cone.
  Shape beyond = kf.shape;
  beyond.point += 20.0 * beyond.dir;
  beyond.dir = -beyond.dir;
  expect_cone(refit_surface(ks, beyond), pose, Vector3d(0, 0, -8), 45.0, "cone refit, apex beyond the samples");

  const Samples ss = revolution_samples(hemisphere(12.0, 72), pose);
  const Fit sf = fit_sphere(ss);
  const Fit sr = refit_surface(ss, nudged(sf.shape, 0.0, 0.5));
  ASSERT_TRUE(sr.ok);
  EXPECT_LE((sr.shape.point - sf.shape.point).norm(), 1e-6);
  EXPECT_NEAR(sr.shape.radius, sf.shape.radius, 1e-6);

  // A plane is fitted exactly; curves and freeform are no surface starts.
  const Fit pr = refit_surface(cs, fit_plane(cs).shape);
  EXPECT_EQ(pr.shape.type, ShapeType::plane);
  EXPECT_EQ(pr.rms, fit_plane(cs).rms);
  Shape line;
  line.type = ShapeType::line;
  EXPECT_FALSE(refit_surface(cs, line).ok);
  EXPECT_FALSE(refit_surface(cs, Shape{}).ok);
  // Bad samples as for the fits; a start with NaN is no start.
  EXPECT_FALSE(refit_surface(Samples{}, cf.shape).ok);
  Shape nan_start = cf.shape;
  nan_start.radius = kNaN;
  EXPECT_FALSE(refit_surface(cs, nan_start).ok);
}

// ---------------------------------------------------------------------------------------------
// Degenerate input: ok = false, never a crash

TEST(FitSurface, DegenerateInputIsNotOk) {
  using FitFn = Fit (*)(const Samples&);
  const std::pair<const char*, FitFn> fits[] = {
      {"plane", fit_plane}, {"sphere", fit_sphere}, {"cylinder", fit_cylinder}, {"cone", fit_cone}};
  Revolution rv;
  rv.rings = {{0.0, 8.0}, {2.0, 10.0}};  // a frustum: every fit has an answer for it
  const Samples good = revolution_samples(rv);
  for (const auto& [name, fn] : fits) {
    SCOPED_TRACE(name);
    EXPECT_TRUE(fn(good).ok);
    EXPECT_FALSE(fn(Samples{}).ok);
    EXPECT_FALSE(fn(points_only({{0, 0, 0}, {1, 0, 0}})).ok);                       // too few
    EXPECT_FALSE(fn(points_only(std::vector<Vector3d>(50, Vector3d(1, 2, 3)))).ok);  // all equal
    std::vector<Vector3d> line;
    for (int i = 0; i < 50; ++i) line.push_back(Vector3d(1, 2, 3) + i * Vector3d(0.3, -0.1, 0.7));
    EXPECT_FALSE(fn(points_only(line)).ok);  // collinear
    Samples nan_point = good;
    nan_point.points[5].y() = kNaN;
    EXPECT_FALSE(fn(nan_point).ok);
    Samples nan_normal = good;
    nan_normal.normals[7].x() = kNaN;
    EXPECT_FALSE(fn(nan_normal).ok);
    Samples bad_weight = good;
    bad_weight.weights[3] = -1.0;
    EXPECT_FALSE(fn(bad_weight).ok);
    Samples zero_weights = good;
    zero_weights.weights.assign(good.points.size(), 0.0);
    EXPECT_FALSE(fn(zero_weights).ok);
    Samples mismatch = good;
    mismatch.normals.pop_back();
    EXPECT_THROW(fn(mismatch), s2c::InvalidInput);
  }
  // A single ring is a circle: no unique sphere through it.
  Revolution ring;
  ring.rings = {{0.0, 5.0}};
  EXPECT_FALSE(fit_sphere(revolution_samples(ring)).ok);
}

TEST(FitSurface, ZeroNormalsAreUnknownNormals) {
  // The caller normalises summed normals; a vertex whose faces cancel keeps a zero normal.
  Revolution rv;
  rv.rings = {{0.0, 3.0}, {8.0, 3.0}};
  Samples s = revolution_samples(rv);
  for (std::size_t i = 0; i < s.normals.size(); i += 3) s.normals[i] = Vector3d::Zero();
  expect_cylinder(fit_cylinder(s), Pose{}, 3.0, "some zero normals");
}

// ---------------------------------------------------------------------------------------------
// Curves

TEST(FitLine, PcaWithEndsFromFirstAndLastSample) {
  std::mt19937 rng(11);
  std::normal_distribution<double> gauss(0.0, 0.01);
  const Vector3d a(1, 2, 3), d = Vector3d(2, -1, 0.5).normalized();
  Samples s;
  for (int i = 0; i <= 40; ++i) s.points.push_back(a + 0.75 * i * d + Vector3d(gauss(rng), gauss(rng), gauss(rng)));
  const Fit f = fit_line(s);
  ASSERT_TRUE(f.ok);
  EXPECT_EQ(f.shape.type, ShapeType::line);
  EXPECT_LE(signed_angle_deg(f.shape.dir, d), 0.5);  // towards the last sample
  EXPECT_LE((f.shape.point - a).norm(), 0.05);
  EXPECT_NEAR(f.shape.length, 30.0, 0.05);
  EXPECT_LT(f.rms, 0.03);
  // Reversed order: starts at the other end.
  std::reverse(s.points.begin(), s.points.end());
  const Fit r = fit_line(s);
  ASSERT_TRUE(r.ok);
  EXPECT_LE(signed_angle_deg(r.shape.dir, -d), 0.5);
  EXPECT_LE((r.shape.point - (a + 30.0 * d)).norm(), 0.05);
}

TEST(FitLine, DegenerateInputIsNotOk) {
  EXPECT_FALSE(fit_line(points_only({})).ok);
  EXPECT_FALSE(fit_line(points_only({{1, 2, 3}})).ok);
  EXPECT_FALSE(fit_line(points_only({{1, 2, 3}, {1, 2, 3}, {1, 2, 3}})).ok);
  EXPECT_FALSE(fit_line(points_only({{1, 2, 3}, {kNaN, 2, 3}, {4, 2, 3}})).ok);
  EXPECT_TRUE(fit_line(points_only({{1, 2, 3}, {4, 2, 3}})).ok);
}

std::vector<Vector3d> circle_points(const Pose& pose, double r, double from_deg, double sweep_deg, int n, double noise = 0) {
  std::mt19937 rng(5);
  std::normal_distribution<double> gauss(0.0, noise > 0 ? noise : 1.0);
  std::vector<Vector3d> p;
  for (int i = 0; i < n; ++i) {
    const double phi = (from_deg + sweep_deg * i / (n - 1)) * M_PI / 180.0;
    Vector3d q = pose.apply(Vector3d(r * std::cos(phi), r * std::sin(phi), 0));
    if (noise > 0) q += Vector3d(gauss(rng), gauss(rng), gauss(rng));
    p.push_back(q);
  }
  return p;
}

TEST(FitCircle, ClosedTilted) {
  const Pose pose = tilted();
  std::vector<Vector3d> p = circle_points(pose, 7.0, 0, 360, 65);
  p.pop_back();  // a closed chain lists each vertex once
  const Fit f = fit_circle(points_only(p), true);
  ASSERT_TRUE(f.ok);
  EXPECT_EQ(f.shape.type, ShapeType::circle);
  EXPECT_LE((f.shape.point - pose.t).norm(), 0.05);
  EXPECT_LE(axis_angle_deg(f.shape.dir, pose.R * Vector3d::UnitZ()), 0.5);
  EXPECT_NEAR(f.shape.radius, 7.0, 0.07);
  EXPECT_LT(f.rms, 1e-6);
}

TEST(FitCircle, OpenArcs) {
  const Pose pose = tilted();
  const Vector3d n = pose.R * Vector3d::UnitZ();
  for (double sweep : {270.0, 90.0, 200.0}) {
    SCOPED_TRACE(sweep);
    const std::vector<Vector3d> p = circle_points(pose, 5.0, 30, sweep, 40);
    const Fit f = fit_circle(points_only(p), false);
    ASSERT_TRUE(f.ok);
    EXPECT_EQ(f.shape.type, ShapeType::arc);
    EXPECT_NEAR(f.shape.angle_deg, sweep, 0.5);
    EXPECT_LE(signed_angle_deg(f.shape.dir, n), 0.5);  // counter-clockwise about dir
    EXPECT_LE((f.shape.start - p.front()).norm(), 0.05);
    EXPECT_LE((f.shape.end - p.back()).norm(), 0.05);
    EXPECT_LE((f.shape.point - pose.t).norm(), 0.05);
    EXPECT_NEAR(f.shape.radius, 5.0, 0.05);
    // Walking the other way: same arc, normal turned, ends swapped.
    const std::vector<Vector3d> q(p.rbegin(), p.rend());
    const Fit g = fit_circle(points_only(q), false);
    ASSERT_TRUE(g.ok);
    EXPECT_NEAR(g.shape.angle_deg, sweep, 0.5);
    EXPECT_LE(signed_angle_deg(g.shape.dir, -n), 0.5);
    EXPECT_LE((g.shape.start - p.back()).norm(), 0.05);
  }
}

TEST(FitCircle, NoisyArcAndNearlyFullOpenChain) {
  const Pose pose = tilted();
  const Fit noisy = fit_circle(points_only(circle_points(pose, 20.0, 0, 120, 200, 0.02)), false);
  ASSERT_TRUE(noisy.ok);
  EXPECT_EQ(noisy.shape.type, ShapeType::arc);
  EXPECT_LE((noisy.shape.point - pose.t).norm(), 0.1);
  EXPECT_NEAR(noisy.shape.radius, 20.0, 0.2);
  EXPECT_NEAR(noisy.shape.angle_deg, 120.0, 0.5);
  EXPECT_LT(noisy.rms, 0.04);
  // An open chain sweeping 355°: a circle.
  const Fit full = fit_circle(points_only(circle_points(pose, 5.0, 0, 355, 72)), false);
  ASSERT_TRUE(full.ok);
  EXPECT_EQ(full.shape.type, ShapeType::circle);
}

TEST(FitCircle, DegenerateInputIsNotOk) {
  std::vector<Vector3d> line;
  for (int i = 0; i < 10; ++i) line.push_back(Vector3d(i, 2.0 * i, 1));
  EXPECT_FALSE(fit_circle(points_only(line), false).ok);
  EXPECT_FALSE(fit_circle(points_only(line), true).ok);
  EXPECT_FALSE(fit_circle(points_only({{0, 0, 0}, {1, 0, 0}}), false).ok);
  EXPECT_FALSE(fit_circle(points_only(std::vector<Vector3d>(6, Vector3d(1, 1, 1))), true).ok);
  std::vector<Vector3d> p = circle_points(Pose{}, 3.0, 0, 180, 10);
  p[4].z() = kNaN;
  EXPECT_FALSE(fit_circle(points_only(p), false).ok);
  EXPECT_TRUE(fit_circle(points_only({{1, 0, 0}, {0, 1, 0}, {-1, 0, 0}}), false).ok);  // three points: exact
}

}  // namespace
