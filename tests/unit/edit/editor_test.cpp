// Edits on the fixture parts, each verified by refitting the truth surfaces' vertices after the
// edit (independently of the features the edit updated), plus locality, rollback and CAD-readiness.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "edit_fixture.h"

namespace s2c::test {
namespace {

using features::ShapeType;

const EditPart& plate() {
  static const EditPart p = load_edit_part("plate");
  return p;
}

// The fixture meshes hold 6 significant digits (OpenSCAD's output): their vertices lie on the
// truth surfaces to about 1e-5 mm. Comparisons with the truth use these bounds, far below the
// issue's targets (0.05 mm, 0.1°, constraint residual 0.01° / 1e-3 mm).
constexpr double kMm = 1e-4, kDeg = 1e-3;

double axis_angle_deg(const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  return std::atan2(a.normalized().cross(b.normalized()).norm(), std::abs(a.normalized().dot(b.normalized()))) * 180.0 / M_PI;
}

void expect_cad_ready(const Mesh& m) {
  const CheckResult c = check(m);
  EXPECT_TRUE(c.cad_ready) << (c.problems.empty() ? "" : c.problems.front());
  EXPECT_EQ(c.self_intersections, 0u);
  EXPECT_EQ(c.degenerate_faces, 0u);
}

TEST(Edit, PlateWidenOneHolePropagatesEqualRadius) {
  const EditPart& p = plate();
  edit::Editor ed = run_on(p,
                           "let hole = select cylinder where radius ~ 3 +- 0.5 nearest [22, 12, 4]\n"
                           "set hole.radius = 4\n"
                           "assert hole.radius ~ 4 +- 0.001\n");
  for (const char* id : {"hole_0", "hole_1", "hole_2", "hole_3"}) {
    const auto vs = on_primitive(p, id);
    const auto fit = refit(ed.mesh(), vs, ShapeType::cylinder);
    ASSERT_TRUE(fit.ok) << id;
    EXPECT_NEAR(fit.shape.radius, 4.0, kMm) << id;  // target: within 0.05 mm
    EXPECT_LT(fit.rms, kMm) << id;
    const auto& truth = truth_primitive(p, id).shape;
    EXPECT_LT(axis_angle_deg(fit.shape.dir, truth.dir), kDeg) << id;
    const Eigen::Vector3d d = fit.shape.point - truth.point;
    EXPECT_LT((d - d.dot(truth.dir) * truth.dir).norm(), kMm) << id;
  }
  const auto centre = refit(ed.mesh(), on_primitive(p, "hole_center"), ShapeType::cylinder);
  EXPECT_NEAR(centre.shape.radius, 6.0, kMm);
  // The holes' 1-ring is top and bottom; the sides are the 2-ring: their vertices do not move.
  for (const char* side : {"side_xp", "side_xn", "side_yp", "side_yn"})
    for (int v : on_primitive(p, side)) EXPECT_EQ(displacement(p, ed.mesh(), v), 0.0) << side;
  for (int v : on_primitive(p, "hole_center")) EXPECT_EQ(displacement(p, ed.mesh(), v), 0.0);
  // The features follow: four cylinders of radius 4 in features().
  int fours = 0;
  for (const auto& patch : ed.features().patches)
    if (patch.shape.type == ShapeType::cylinder && std::abs(patch.shape.radius - 4.0) < 1e-9) ++fours;
  EXPECT_EQ(fours, 4);
  // Every hole widened alike keeps every mirror symmetry of the plate (measured, not assumed).
  auto symmetric = [](const features::FeatureSet& f) {
    return std::count_if(f.groups.begin(), f.groups.end(), [](const features::Group& g) {
      return g.constraint && *g.constraint == features::ConstraintKind::symmetric;
    });
  };
  EXPECT_GT(symmetric(p.features), 0);
  EXPECT_EQ(symmetric(ed.features()), symmetric(p.features));
  expect_cad_ready(ed.mesh());
}

TEST(Edit, PlateUnconstrainedHoleChangesAlone) {
  const EditPart& p = plate();
  edit::Editor ed = run_on(p,
                           "let hole = select cylinder where radius ~ 3 +- 0.5 nearest [22, 12, 4]\n"
                           "unconstrain hole\n"
                           "set hole.radius = 4.5\n");
  EXPECT_NEAR(refit(ed.mesh(), on_primitive(p, "hole_2"), ShapeType::cylinder).shape.radius, 4.5, kMm);
  for (const char* id : {"hole_0", "hole_1", "hole_3"})
    for (int v : on_primitive(p, id)) EXPECT_EQ(displacement(p, ed.mesh(), v), 0.0) << id;
  expect_cad_ready(ed.mesh());
}

TEST(Edit, PlateMoveTopKeepsItsNeighboursAndTheBottom) {
  const EditPart& p = plate();
  edit::Editor ed = run_on(p,
                           "let top = select plane where normal ~ +z highest\n"
                           "let bottom = select plane where normal ~ -z\n"
                           "move top by [0, 0, 3]\n"
                           "assert parallel(top, bottom)\n");
  const auto top = refit(ed.mesh(), on_primitive(p, "top"), ShapeType::plane);
  EXPECT_LT(axis_angle_deg(top.shape.dir, Eigen::Vector3d::UnitZ()), kDeg);
  EXPECT_NEAR(top.shape.point.z(), 11.0, kMm);
  for (int v : on_primitive(p, "bottom")) EXPECT_EQ(displacement(p, ed.mesh(), v), 0.0);
  for (const char* id : {"hole_0", "hole_center"}) {
    const auto fit = refit(ed.mesh(), on_primitive(p, id), ShapeType::cylinder);
    EXPECT_NEAR(fit.shape.radius, truth_primitive(p, id).shape.radius, kMm) << id;
  }
  for (const char* side : {"side_xp", "side_yn"}) {
    const auto fit = refit(ed.mesh(), on_primitive(p, side), ShapeType::plane);
    EXPECT_LT(fit.rms, kMm) << side;
    EXPECT_LT(axis_angle_deg(fit.shape.dir, truth_primitive(p, side).shape.dir), kDeg) << side;
  }
  EXPECT_NEAR(bounds(ed.mesh()).max.z(), 11.0, kMm);
  expect_cad_ready(ed.mesh());
}

TEST(Edit, PlateRotateTopPropagatesParallelToBottom) {
  const EditPart& p = plate();
  edit::Editor ed(p.mesh, p.features);
  const auto top = ed.select([&](edit::FeatureRef f) {
    return ed.shape(f).type == ShapeType::plane && ed.shape(f).dir.z() > 0.99;
  });
  ASSERT_EQ(top.size(), 1u);
  const edit::EditReport r = ed.rotate(top, {1, 0, 0}, 2.0);
  ASSERT_FALSE(r.propagated.empty());
  const auto t = refit(ed.mesh(), on_primitive(p, "top"), ShapeType::plane);
  const auto b = refit(ed.mesh(), on_primitive(p, "bottom"), ShapeType::plane);
  EXPECT_NEAR(axis_angle_deg(t.shape.dir, Eigen::Vector3d::UnitZ()), 2.0, kDeg);
  EXPECT_LT(axis_angle_deg(t.shape.dir, b.shape.dir), 0.01);  // target: constraint residual ≤ 0.01°
  // Tilting the top about x breaks the mirror symmetry about y = 0: reported and dropped.
  EXPECT_TRUE(std::any_of(r.broken.begin(), r.broken.end(), [](const std::string& m) { return m.find("symmetric") != std::string::npos; }));
  expect_cad_ready(ed.mesh());
}

TEST(Edit, LockedFeatureMakesAConflictAndNothingChanges) {
  const EditPart& p = plate();
  edit::Editor ed(p.mesh, p.features);
  const auto planes = [&](double z) {
    return ed.select([&, z](edit::FeatureRef f) { return ed.shape(f).type == ShapeType::plane && ed.shape(f).dir.z() * z > 0.99; });
  };
  ed.lock(planes(-1).at(0));
  try {
    ed.rotate(planes(1), {1, 0, 0}, 2.0);
    FAIL() << "no conflict";
  } catch (const ProcessingError& e) {
    EXPECT_NE(std::string(e.what()).find("locked"), std::string::npos) << e.what();
  }
  for (double d : ed.displacement()) ASSERT_EQ(d, 0.0);
  EXPECT_EQ(ed.features().groups.size(), p.features.groups.size());
}

TEST(Edit, ShaftRadiusKeepsCoaxialAndEqualRadius) {
  const EditPart p = load_edit_part("shaft");
  edit::Editor ed = run_on(p,
                           "let body = select cylinder largest\n"
                           "set body.radius = 11\n");
  const auto body = refit(ed.mesh(), on_primitive(p, "shaft_body"), ShapeType::cylinder);
  EXPECT_NEAR(body.shape.radius, 11.0, kMm);
  EXPECT_LT(axis_angle_deg(body.shape.dir, Eigen::Vector3d::UnitZ()), kDeg);
  const auto tip = refit(ed.mesh(), on_primitive(p, "tip"), ShapeType::sphere);
  EXPECT_NEAR(tip.shape.radius, 11.0, kMm);  // equal_radius propagated
  EXPECT_LT((tip.shape.point - Eigen::Vector3d(0, 0, 40)).norm(), kMm);
  for (int v : on_primitive(p, "end")) {
    if (p.before[v].head<2>().norm() < 7.9) {
      EXPECT_EQ(displacement(p, ed.mesh(), v), 0.0);
    }
  }
  expect_cad_ready(ed.mesh());
}

TEST(Edit, PocketFloorMovesDownAndTheCounterboreFollows) {
  const EditPart p = load_edit_part("pocket");
  edit::Editor ed = run_on(p,
                           "let floor = select plane where normal ~ +z and area < 500 largest\n"
                           "move floor by [0, 0, -2]\n");
  const auto floor = refit(ed.mesh(), on_primitive(p, "pocket_floor"), ShapeType::plane);
  EXPECT_NEAR(floor.shape.point.z(), 10.0, kMm);
  for (int v : on_primitive(p, "top")) EXPECT_EQ(displacement(p, ed.mesh(), v), 0.0);
  for (int v : on_primitive(p, "bottom")) EXPECT_EQ(displacement(p, ed.mesh(), v), 0.0);
  const auto cb = refit(ed.mesh(), on_primitive(p, "counterbore"), ShapeType::cylinder);
  EXPECT_NEAR(cb.shape.radius, 6.0, kMm);
  expect_cad_ready(ed.mesh());
}

TEST(Edit, ArapOnARefinedPlateKeepsPlanesAndReusesTheFactorisation) {
  const EditPart p = load_edit_part("plate", 2.0);
  edit::Editor ed(p.mesh, p.features);
  const auto top = ed.select([&](edit::FeatureRef f) { return ed.shape(f).type == ShapeType::plane && ed.shape(f).dir.z() > 0.99; });
  ASSERT_EQ(top.size(), 1u);
  const edit::EditReport r1 = ed.move(top, {0, 0, 1.5});
  EXPECT_GT(r1.free_vertices, 0);
  EXPECT_FALSE(r1.factorization_reused);
  const edit::EditReport r2 = ed.move(top, {0, 0, 0.5});
  EXPECT_TRUE(r2.factorization_reused);
  for (const char* side : {"side_xp", "side_yn"}) {
    const auto fit = refit(ed.mesh(), on_primitive(p, side), ShapeType::plane);
    EXPECT_LT(fit.rms, kMm) << side;
    EXPECT_LT(axis_angle_deg(fit.shape.dir, truth_primitive(p, side).shape.dir), kDeg) << side;
  }
  EXPECT_NEAR(refit(ed.mesh(), on_primitive(p, "top"), ShapeType::plane).shape.point.z(), 10.0, kMm);
  for (int v : on_primitive(p, "bottom")) EXPECT_EQ(displacement(p, ed.mesh(), v), 0.0);
  expect_cad_ready(ed.mesh());
}

TEST(Edit, SnappedPlanesKeepEachVertexOnItsSideOfTheSurface) {
  // A scan's planes carry noise. A side stretched by raising the top goes back onto the plane its
  // border spans with every vertex at its own signed offset from it: a refit returns the plane's
  // normal with either sign, and the offsets, measured along the patch's normal, must go back
  // along the refitted one turned the same way, or a bump becomes a dent (the plate scan's side
  // tilted 0.06° that way). Bumps of up to 0.02 mm on the sides of a refined plate.
  EditPart p = load_edit_part("plate", 2.0);
  const auto bump = [](const Eigen::Vector3d& q) { return 0.02 * std::sin(1.7 * (q.x() + q.y()) + 0.4) * std::sin(0.9 * q.z()); };
  std::vector<std::pair<std::string, std::vector<int>>> sides;
  for (const char* id : {"side_xp", "side_xn", "side_yp", "side_yn"}) {
    std::vector<int> inner;
    const Eigen::Vector3d n = truth_primitive(p, id).shape.dir;
    for (int v : on_primitive(p, id)) {
      Eigen::Vector3d& q = p.before[v];
      // Away from the side's edges (its own normal coordinate is ±30 or ±20 everywhere).
      if (q.z() < 0.5 || q.z() > 7.5 || (n.x() == 0 && std::abs(q.x()) > 29.5) || (n.y() == 0 && std::abs(q.y()) > 19.5)) continue;
      q += bump(q) * n;
      p.mesh.set_point(OpenMesh::VertexHandle(v), to_om(q));
      inner.push_back(v);
    }
    ASSERT_GT(inner.size(), 20u) << id;
    sides.emplace_back(id, inner);
  }
  p.mesh.update_normals();
  p.features = features::analyze(p.mesh, {}).features;
  edit::Editor ed = run_on(p, "let top = select plane where normal ~ +z highest\nmove top by [0, 0, 1.5]\n");
  for (const auto& [id, inner] : sides) {
    const Eigen::Vector3d n = truth_primitive(p, id).shape.dir;
    const auto before = refit(p.mesh, inner, ShapeType::plane), after = refit(ed.mesh(), inner, ShapeType::plane);
    const Eigen::Vector3d nb = before.shape.dir.dot(n) > 0 ? before.shape.dir : Eigen::Vector3d(-before.shape.dir);
    const Eigen::Vector3d na = after.shape.dir.dot(n) > 0 ? after.shape.dir : Eigen::Vector3d(-after.shape.dir);
    double moved = 0, size = 0;
    for (int v : inner) {
      const double d0 = (p.before[v] - before.shape.point).dot(nb);
      const double d1 = (to_eigen(ed.mesh().point(OpenMesh::VertexHandle(v))) - after.shape.point).dot(na);
      moved = std::max(moved, std::abs(d1 - d0));
      size = std::max(size, std::abs(d0));
    }
    EXPECT_GT(size, 0.01) << id;
    // (The plane's own tilt may change: the bumps are stretched with the side.)
    EXPECT_LT(moved, 0.1 * size) << id << ": offsets from the plane changed by up to " << moved << " mm";
  }
  expect_cad_ready(ed.mesh());
}

TEST(Edit, ResizedHoleCarriesTheCrumbsOfItsWall) {
  // A scan's hole wall comes out of the features stage as one cylinder and crumbs: pieces that
  // repair filled a little inside the wall (0.1–0.5 mm on the plate scan) and that fit no shape
  // well enough to merge. Widening the hole must widen them with it; as ARAP neighbours they
  // lagged behind by up to 0.4 mm. Here a piece of a refined plate's hole wall is pushed 0.2 mm
  // inward and made a freeform patch of its own.
  EditPart p = load_edit_part("plate", 1.0);
  const Eigen::Vector2d axis(22, 12);
  int hole = -1;
  for (int q = 0; q < static_cast<int>(p.features.patches.size()); ++q) {
    const auto& s = p.features.patches[q].shape;
    if (s.type == ShapeType::cylinder && std::abs(s.radius - 3) < 0.1 && (s.point.head<2>() - axis).norm() < 0.1) hole = q;
  }
  ASSERT_GE(hole, 0);
  const auto angle_of = [&](const Eigen::Vector3d& q) { return std::atan2(q.y() - axis.y(), q.x() - axis.x()); };
  std::vector<int> kept, crumb;
  for (int f : p.features.patches[hole].faces) {
    bool in = true;
    for (auto v : p.mesh.fv_range(OpenMesh::FaceHandle(f))) {
      const Eigen::Vector3d& q = p.before[v.idx()];
      in = in && q.z() > 2.5 && q.z() < 5.5 && angle_of(q) > 0.0 && angle_of(q) < 1.2;
    }
    (in ? crumb : kept).push_back(f);
  }
  ASSERT_GT(crumb.size(), 10u);
  // Its vertices that touch no other face of the wall go 0.2 mm inward.
  std::set<int> kept_v, dented;
  for (int f : kept)
    for (auto v : p.mesh.fv_range(OpenMesh::FaceHandle(f))) kept_v.insert(v.idx());
  for (int f : crumb)
    for (auto v : p.mesh.fv_range(OpenMesh::FaceHandle(f)))
      if (!kept_v.count(v.idx())) dented.insert(v.idx());
  ASSERT_GT(dented.size(), 3u);
  for (int v : dented) {
    Eigen::Vector3d& q = p.before[v];
    const Eigen::Vector3d radial = Eigen::Vector3d(q.x() - axis.x(), q.y() - axis.y(), 0).normalized();
    q -= 0.2 * radial;
    p.mesh.set_point(OpenMesh::VertexHandle(v), to_om(q));
  }
  p.mesh.update_normals();
  p.features.patches[hole].faces = kept;
  features::Patch piece;
  piece.id = "P_crumb";
  piece.faces = crumb;
  piece.area = 1.0;
  p.features.patches.push_back(piece);

  const std::string script = "let hole = select cylinder where radius ~ 3 +- 0.5 nearest [22, 12, 4]\nunconstrain hole\nset hole.radius = 3.5\n";
  const auto radial_move = [&](const Mesh& m, int v) {
    const Eigen::Vector3d q = to_eigen(m.point(OpenMesh::VertexHandle(v)));
    return Eigen::Vector2d(q.x() - axis.x(), q.y() - axis.y()).norm() - Eigen::Vector2d(p.before[v].x() - axis.x(), p.before[v].y() - axis.y()).norm();
  };
  // The wall moves by the new radius minus the fitted one (the tessellation's is a little below 3).
  const double widened = 3.5 - p.features.patches[hole].shape.radius;
  edit::Editor ed = run_on(p, script);
  for (int v : dented) EXPECT_NEAR(radial_move(ed.mesh(), v), widened, 1e-6) << v;  // offsets kept: still 0.2 inside
  expect_cad_ready(ed.mesh());
  // Without carrying (the band 0), ARAP leaves the piece behind (here, enclosed by the wall, by
  // 0.01 mm; on the scan, where the pieces reach the rims, by up to 0.4 mm).
  edit::EditOptions o;
  o.carry_band_fraction = 0.0;
  edit::Editor lagging = run_on(p, script, o);
  double lag = 0.0;
  for (int v : dented) lag = std::max(lag, std::abs(radial_move(lagging.mesh(), v) - widened));
  EXPECT_GT(lag, 1e-3);
}

TEST(Edit, LowLevelVertexEditBubblesIntoItsPatchOnly) {
  const EditPart p = load_edit_part("plate", 2.0);
  edit::Editor ed(p.mesh, p.features);
  // An interior vertex of the top face, away from every hole and edge.
  int pick = -1;
  for (int v : on_primitive(p, "top"))
    if (std::abs(p.before[v].x()) < 8 && std::abs(p.before[v].y() - 12) < 4 && std::abs(p.before[v].x()) > 1) {
      pick = v;
      break;
    }
  ASSERT_GE(pick, 0);
  const auto top_vs = on_primitive(p, "top");
  const edit::EditReport r = ed.move_vertices({pick}, {p.before[pick] + Eigen::Vector3d(0, 0, 0.3)});
  EXPECT_EQ(r.free.size(), 1u);
  EXPECT_NEAR(displacement(p, ed.mesh(), pick), 0.3, 1e-12);
  const std::set<int> top_set(top_vs.begin(), top_vs.end());
  int moved = 0;
  for (int v = 0; v < static_cast<int>(p.before.size()); ++v) {
    const double d = displacement(p, ed.mesh(), v);
    if (!top_set.count(v)) {
      EXPECT_EQ(d, 0.0) << v;
    }
    moved += d > 0.0;
  }
  EXPECT_GT(moved, 1);  // the patch around the vertex follows
  expect_cad_ready(ed.mesh());
}

TEST(Edit, WholeMeshArapTouchesMoreThanTheRestrictedOne) {
  const EditPart p = load_edit_part("plate", 2.0);
  edit::EditOptions whole;
  whole.whole_mesh = true;
  edit::Editor a(p.mesh, p.features), b(p.mesh, p.features, whole);
  auto pick = [&](edit::Editor& ed) {
    return ed.select([&](edit::FeatureRef f) {
      return ed.shape(f).type == ShapeType::cylinder && (ed.centroid(f) - Eigen::Vector3d(22, 12, 4)).norm() < 1;
    });
  };
  edit::EditOptions o;
  o.propagate = false;
  const auto ra = a.set_radius(pick(a), 3.5);
  const auto rb = b.set_radius(pick(b), 3.5);
  EXPECT_GT(rb.free_vertices, ra.free_vertices);
  EXPECT_GT(rb.free.size(), ra.free.size());
}

TEST(Edit, ConstrainMakesPlanesParallel) {
  const EditPart& p = plate();
  edit::Editor ed = run_on(p,
                           "let top = select plane where normal ~ +z\n"
                           "let bottom = select plane where normal ~ -z\n"
                           "unconstrain parallel(top, bottom)\n"
                           "rotate bottom about [0, 1, 0] by 1.5 deg\n"
                           "constrain parallel(bottom, top)\n"
                           "assert parallel(top, bottom)\n");
  const auto t = refit(ed.mesh(), on_primitive(p, "top"), ShapeType::plane);
  const auto b = refit(ed.mesh(), on_primitive(p, "bottom"), ShapeType::plane);
  EXPECT_LT(axis_angle_deg(t.shape.dir, b.shape.dir), 0.01);
  EXPECT_NEAR(axis_angle_deg(b.shape.dir, Eigen::Vector3d::UnitZ()), 1.5, kDeg);
}

}  // namespace
}  // namespace s2c::test
