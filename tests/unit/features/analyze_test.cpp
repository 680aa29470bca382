// The feature analysis against the fixture parts' ground truth (fixtures/parts/*.truth.json) and
// on real CAD meshes: primitives, feature lines and constraints, clean and noisy.
#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <cmath>
#include <random>
#include <set>

#include <Eigen/Eigenvalues>

#include "s2c/core/distance.h"
#include "s2c/core/io.h"
#include "s2c/core/disjoint_sets.h"
#include "s2c/features/analyze.h"
#include "features_eval.h"
#include "mesh_arrays.h"
#include "tensor_voting.h"
#include "test_util.h"
#include "truth_match.h"

namespace s2c::features {
namespace {

using test::read_truth;

Mesh fixture(const std::string& part) { return read_mesh(test::source_dir() / "fixtures/parts" / (part + ".stl")); }
test::Truth truth(const std::string& part) {
  return read_truth((test::source_dir() / "fixtures/parts" / (part + ".truth.json")).string());
}

/// Truth constraints implied by the detected groups (through the id matches); equivalence kinds
/// through their classes, the others as direct pairs. Returns {implied pairs, truth pairs}.
std::pair<int, int> constraint_recall(const FeatureSet& f, const test::Truth& t,
                                      const std::map<std::string, std::string>& ids) {
  static const std::set<std::string> equivalence = {"parallel", "coaxial", "concentric", "equal_radius",
                                                    "equal_length", "collinear"};
  int found = 0, total = 0;
  for (const auto& c : t.constraints) {
    const std::string kind = c["kind"];
    std::vector<std::string> members;
    for (const auto& m : c["members"]) members.push_back(ids.count(m) ? ids.at(m) : std::string("?") + m.get<std::string>());
    // Detected classes/pairs of this kind.
    std::map<std::string, int> index;
    DisjointSets sets(4096);
    auto id_of = [&](const std::string& s) { return index.emplace(s, static_cast<int>(index.size())).first->second; };
    std::set<std::pair<std::string, std::string>> pairs;
    for (const auto& g : f.groups) {
      if (!g.constraint || constraint_name(*g.constraint) != kind) continue;
      for (std::size_t i = 1; i < g.members.size(); ++i) {
        sets.unite(id_of(g.members[0]), id_of(g.members[i]));
        pairs.emplace(std::min(g.members[0], g.members[i]), std::max(g.members[0], g.members[i]));
      }
    }
    for (std::size_t i = 0; i < members.size(); ++i)
      for (std::size_t j = i + 1; j < members.size(); ++j) {
        ++total;
        const auto& a = members[i];
        const auto& b = members[j];
        const bool ok = equivalence.count(kind)
                            ? index.count(a) && index.count(b) && sets.find(index[a]) == sets.find(index[b])
                            : pairs.count({std::min(a, b), std::max(a, b)}) > 0;
        if (ok) ++found;
        else ADD_FAILURE() << "missing " << kind << " " << c["members"].dump();
      }
  }
  return {found, total};
}

struct PartCase {
  const char* part;
};

class FixturePart : public ::testing::TestWithParam<const char*> {};

TEST_P(FixturePart, FindsEveryPrimitiveLineAndConstraintOfTheCleanPart) {
  const std::string part = GetParam();
  const Mesh mesh = fixture(part);
  const auto t = truth(part);
  const Analysis a = analyze(mesh, {});
  const auto& f = a.features;
  const auto prims = test::match(t.primitives, f.patches);
  for (const auto& p : t.primitives) EXPECT_TRUE(prims.count(p.id)) << part << ": primitive " << p.id << " not found";
  const auto lines = test::match(t.lines, f.lines);
  for (const auto& l : t.lines) EXPECT_TRUE(lines.count(l.id)) << part << ": line " << l.id << " not found";
  // Every patch is one truth primitive: no spurious patches on a clean part.
  EXPECT_EQ(f.patches.size(), t.primitives.size()) << part;
  EXPECT_EQ(f.lines.size(), t.lines.size()) << part;
  std::map<std::string, std::string> ids = prims;
  ids.insert(lines.begin(), lines.end());
  const auto [found, total] = constraint_recall(f, t, ids);
  EXPECT_GE(found, 0.9 * total) << part << ": " << found << "/" << total << " truth constraint pairs implied";
  // Every face belongs to exactly one patch.
  std::vector<int> owner(mesh.n_faces(), 0);
  for (const auto& p : f.patches)
    for (int face : p.faces) ++owner[face];
  for (int c : owner) ASSERT_EQ(c, 1);
}

INSTANTIATE_TEST_SUITE_P(Parts, FixturePart, ::testing::Values("plate", "shaft", "bracket", "pocket"));

/// The benchmark's noisy inputs (bench/features_eval.h: Delaunay-legalised longest-edge
/// bisection to diagonal/100, then isotropic Gaussian noise of σ = 0.2 mean edge lengths), with
/// fixed thresholds: the σ = 0.2h target, checked here against the truth.
class NoisyPart : public ::testing::TestWithParam<const char*> {};

TEST_P(NoisyPart, KeepsItsPrimitivesAtSigmaPointTwoEdgeLengths) {
  const std::string part = GetParam();
  const Mesh clean = fixture(part);
  Mesh m = bench::refine_mesh(clean, bounds(clean).diagonal() / 100.0);
  const double h = bench::mean_edge_length(m);
  bench::add_noise(m, 0.2 * h, 1);
  const Analysis a = analyze(m, {});
  const auto t = truth(part);
  const auto prims = test::match(t.primitives, a.features.patches);
  EXPECT_GE(prims.size(), 0.9 * t.primitives.size()) << part << ": " << prims.size() << "/" << t.primitives.size();
  EXPECT_GT(a.noise, 0.1 * h);
  EXPECT_LT(a.noise, 0.4 * h);
}

INSTANTIATE_TEST_SUITE_P(Parts, NoisyPart, ::testing::Values("plate", "shaft", "bracket", "pocket"));

/// The vote is two edges wide on a mesh as noisy as a scan's Poisson surface (noise 1–2 % of the
/// edge) and three from 4 % on (the sweep's σ = 0.1h and up), where the shaft's chamfer needs it.
TEST(NoisyShaft, VoteIsTwoEdgesWideOnScanNoiseAndThreeFromFourPerCent) {
  const Mesh clean = fixture("shaft");
  auto radius_over_edge = [&](double sigma_per_edge) {
    Mesh m = bench::refine_mesh(clean, bounds(clean).diagonal() / 100.0);
    const double h = bench::mean_edge_length(m);
    bench::add_noise(m, sigma_per_edge * h, 1);
    FeatureOptions o;
    o.constraints = false;
    const Analysis a = analyze(m, o);
    return std::pair(a.radius / h, a.noise / h);
  };
  const auto [scan_radius, scan_noise] = radius_over_edge(0.015);
  const auto [sweep_radius, sweep_noise] = radius_over_edge(0.1);
  EXPECT_LT(scan_noise, 0.04);
  EXPECT_GT(sweep_noise, 0.04);
  // In mean edges (the radius is in median edges, within a few per cent of them here).
  EXPECT_NEAR(scan_radius, 2.0, 0.15);
  EXPECT_NEAR(sweep_radius, 3.0, 0.2);
}

/// At σ = 0.1h the shaft's 45° chamfer band used to come out as a cone beside a sphere zone, and
/// the two were stated at a fixed angle to each other: curved neighbours of different types now
/// merge when one type fits both, so every patch is a truth primitive and every constraint holds
/// between truth features.
TEST(NoisyShaft, ChamferIsOneConeAndNoConstraintJoinsAnUnmatchedPatch) {
  const Mesh clean = fixture("shaft");
  Mesh m = bench::refine_mesh(clean, bounds(clean).diagonal() / 100.0);
  bench::add_noise(m, 0.1 * bench::mean_edge_length(m), 1);
  const Analysis a = analyze(m, {});
  const auto t = truth("shaft");
  const auto prims = test::match(t.primitives, a.features.patches);
  EXPECT_EQ(prims.size(), t.primitives.size());
  EXPECT_EQ(a.features.patches.size(), t.primitives.size());
  std::set<std::string> matched;
  for (const auto& [truth_id, patch_id] : prims) matched.insert(patch_id);
  for (const auto& g : a.features.groups) {
    if (!g.constraint || *g.constraint == ConstraintKind::connected) continue;
    for (const auto& member : g.members)
      if (member[0] == 'P') {
        EXPECT_TRUE(matched.count(member)) << g.id << " joins unmatched patch " << member;
      }
  }
}

TEST(FeaturesReal, CgalFandiskHasPlanesCylindersAndLines) {
  const Mesh mesh = read_mesh(test::shared_dir() / "data/real/cad/cgal_fandisk.off");
  const Analysis a = analyze(mesh, {});
  std::map<ShapeType, int> types;
  for (const auto& p : a.features.patches) ++types[p.shape.type];
  EXPECT_GE(types[ShapeType::plane], 5);
  EXPECT_GE(types[ShapeType::cylinder] + types[ShapeType::cone], 2);
  EXPECT_GE(a.features.lines.size(), 10u);
}

/// Tensor voting's search (a breadth-first walk over faces, pruned by bounding balls and squared
/// distances) must find exactly the faces within the radius: compared with a sum over every face.
/// The tensors are kept in float: 2e-7 is four times the rounding of a ratio ≤ 1, and a face left
/// out moves the ratios by far more (its weight is at least e⁻³ of its area's share).
void expect_vote_matches_all_faces(const TriangleSoup& soup, double radius, double tolerance = 2e-7,
                                   std::size_t stride = 1) {
  Mesh mesh;
  soup_to_mesh(soup, mesh);
  const TriangleSoup s = mesh_to_soup(mesh);  // the mesh's own numbering
  const std::vector<VertexTensor> got = vote_tensors(mesh, radius, 20.0, 0.0);
  ASSERT_EQ(got.size(), s.vertices.size());
  const double disc = M_PI * radius * radius;
  int checked = 0;
  for (std::size_t v = 0; v < s.vertices.size(); v += stride) {
    const Eigen::Vector3d& p = s.vertices[v];
    Eigen::Matrix3d T = Eigen::Matrix3d::Zero();
    for (const auto& t : s.faces) {
      const Eigen::Vector3d& a = s.vertices[t[0]], & b = s.vertices[t[1]], & c = s.vertices[t[2]];
      const Eigen::Vector3d cross = (b - a).cross(c - a);
      if (!(cross.norm() > 0)) continue;
      const bool incident = t[0] == int(v) || t[1] == int(v) || t[2] == int(v);
      const double d = incident ? 0.0 : (closest_point_on_triangle(p, a, b, c) - p).norm();
      if (d > radius) continue;
      const Eigen::Vector3d n = cross.normalized();
      T += std::min(0.5 * cross.norm(), disc) / disc * std::exp(-3.0 * d / radius) * n * n.transpose();
    }
    Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
    es.computeDirect(T);
    const Eigen::Vector3d ev = es.eigenvalues();
    if (!(ev[2] > 0)) continue;
    const Eigen::Vector3d lambda(1.0, std::max(ev[1], 0.0) / ev[2], std::max(ev[0], 0.0) / ev[2]);
    EXPECT_NEAR(got[v].lambda[1], lambda[1], tolerance) << "vertex " << v;
    EXPECT_NEAR(got[v].lambda[2], lambda[2], tolerance) << "vertex " << v;
    ++checked;
  }
  EXPECT_GT(checked, 0);
}

TEST(TensorVoting, FindsExactlyTheFacesWithinTheRadius) {
  // Long skinny CAD triangles (the plate's OpenSCAD export) and a jittered sphere, each with a
  // radius of a few edges and one far beyond them.
  const TriangleSoup plate = read_soup(test::source_dir() / "fixtures/parts/plate.stl");
  expect_vote_matches_all_faces(plate, 1.5);
  expect_vote_matches_all_faces(plate, 12.0);
  TriangleSoup ball = test::icosphere(Eigen::Vector3d::Zero(), 5.0, 3);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> jitter(-0.05, 0.05);
  for (auto& q : ball.vertices) q += Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng));
  expect_vote_matches_all_faces(ball, 0.8);
  expect_vote_matches_all_faces(ball, 2.5);
}

/// Vertices amid a plane skip the walk (plainly_flat): on a sheet folded by 40° all do but those
/// within the radius of the other plane, and every vertex's λ and class still match the sum over
/// every face, the ones the fold passes within the radius of included.
TEST(TensorVoting, WalkNumbersWrapWithoutLosingFaces) {
  // A thread numbers its walks in 16 bits and clears its marks when the numbers wrap: 163,842
  // curved (so voted) vertices on one thread wrap twice. Every 4,001st vertex against the sum
  // over every face.
  TriangleSoup ball = test::icosphere(Eigen::Vector3d::Zero(), 50.0, 7);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.02, 0.02);
  for (auto& q : ball.vertices) q += Eigen::Vector3d(jitter(rng), jitter(rng), jitter(rng));
  ASSERT_GT(ball.vertices.size(), 2u * 65536u);
  tbb::task_arena(1).execute([&] { expect_vote_matches_all_faces(ball, 0.5, 2e-7, 4001); });
  // Every vertex the same on one thread and on three, whose walks wrap at other vertices. (A mark
  // left over from the walk 65,536 before matters only where that walk passed nearby, which it
  // rarely does: these checks cannot prove the clearing needed, only that wrapping harms nothing.)
  Mesh mesh;
  soup_to_mesh(ball, mesh);
  std::vector<VertexTensor> one, three;
  tbb::task_arena(1).execute([&] { one = vote_tensors(mesh, 0.5, 20.0, 0.0); });
  tbb::task_arena(3).execute([&] { three = vote_tensors(mesh, 0.5, 20.0, 0.0); });
  ASSERT_EQ(one.size(), three.size());
  int differ = 0;
  for (std::size_t v = 0; v < one.size(); ++v)
    differ += one[v].lambda != three[v].lambda || one[v].e3 != three[v].e3 || one[v].cls != three[v].cls;
  EXPECT_EQ(differ, 0);
}

TEST(TensorVoting, PlainlyFlatVerticesGetTheVoteOfEveryFace) {
  constexpr int n = 30;
  const double fold = 40.0 * M_PI / 180.0;
  const TriangleSoup sheet = test::obliquely_rotated(test::grid(n, [](int, int) { return true; }, [&](double x, double y) {
    const double past = std::max(0.0, x - n / 2.0);
    return Eigen::Vector3d(std::min(x, n / 2.0) + past * std::cos(fold), y, past * std::sin(fold));
  }));
  Mesh m;
  soup_to_mesh(sheet, m);
  const MeshArrays a = build_arrays(m);
  const double radius = 1.5 * a.median_edge;
  const VotingThresholds t = voting_thresholds(20.0, 0.0, a.median_edge);
  const std::vector<char> flat = plainly_flat(a, a.fnormal, radius, t);
  const auto plain = std::count(flat.begin(), flat.end(), 1);
  // Exactly the vertices farther than the radius from the other plane's faces: all but the fold's
  // column and the one on each side of it (one edge away; two edges is beyond 1.5).
  EXPECT_EQ(plain, a.vertices() - 3 * (n + 1));
  // A plainly flat vertex gets λ2 = λ3 = 0; the closed-form eigenvalues of the summed, nearly
  // rank-one tensor come out a few 1e-9 of λ1 instead (far below any threshold: 0.015 here).
  expect_vote_matches_all_faces(sheet, radius, 2e-7);
  const std::vector<VertexTensor> got = vote(a, a.fnormal, radius, t);
  for (int v = 0; v < a.vertices(); ++v) {
    if (flat[v]) {
      EXPECT_EQ(got[v].cls, VertexClass::face) << v;
    }
  }
  EXPECT_GE(std::count_if(got.begin(), got.end(), [](const VertexTensor& x) { return x.cls == VertexClass::crease; }),
            n + 1);  // the fold
}

TEST(FeaturesInput, EmptyMeshIsRefused) {
  Mesh empty;
  EXPECT_THROW(analyze(empty, {}), InvalidInput);
}

TEST(FeaturesInput, SphereWithoutCreasesIsOnePatchAndNoLines) {
  TriangleSoup s = test::icosphere(Eigen::Vector3d::Zero(), 5.0, 3);
  Mesh m;
  soup_to_mesh(s, m);
  const Analysis a = analyze(m, {});
  ASSERT_EQ(a.features.patches.size(), 1u);
  EXPECT_EQ(a.features.patches[0].shape.type, ShapeType::sphere);
  EXPECT_NEAR(a.features.patches[0].shape.radius, 5.0, 0.05);
  EXPECT_TRUE(a.features.lines.empty());
}


// A Poisson surface has bumps a few edges wide at any resolution; the waviness must see them,
// whatever the edge length, and not the curvature of the part.
TEST(Waviness, SeesBumpsAFewEdgesWideNotCurvatureNorEdgeLength) {
  const double radius = 5.0, amplitude = 0.02, wavelength = 1.2;  // mm
  auto waviness = [&](int levels, bool bumps) {
    TriangleSoup s = test::icosphere(Eigen::Vector3d::Zero(), radius, levels);
    const double k = 2 * M_PI / wavelength;
    if (bumps)
      for (auto& q : s.vertices)
        q *= 1.0 + amplitude / radius * std::sin(k * q.x()) * std::sin(k * q.y()) * std::sin(k * q.z());
    Mesh m;
    soup_to_mesh(s, m);
    return measure_waviness(build_arrays(m));
  };
  // A plane fitted to the six rings would leave their sagitta, about 0.04 mm at level 5.
  EXPECT_LT(waviness(5, false), 0.1 * amplitude);
  const double coarse = waviness(4, true), fine = waviness(5, true);
  // Its per-thread scratch is left clean: the same mesh measured again gives the same.
  EXPECT_EQ(waviness(5, true), fine);
  EXPECT_GT(coarse, 0.2 * amplitude);
  EXPECT_LT(coarse, 1.2 * amplitude);
  EXPECT_GT(fine, 0.2 * amplitude);
  EXPECT_LT(fine, 1.2 * amplitude);
  EXPECT_LT(std::max(coarse, fine) / std::min(coarse, fine), 2.0) << coarse << " " << fine;
}

}  // namespace
}  // namespace s2c::features
