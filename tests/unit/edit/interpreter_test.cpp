// The interpreter: selections, expressions, parameters, asserts and the runtime error classes
// (each names file, line and column, or the statement for exit-3 failures).
#include <gtest/gtest.h>

#include <set>

#include "edit_fixture.h"

namespace s2c::test {
namespace {

const EditPart& plate() {
  static const EditPart p = load_edit_part("plate");
  return p;
}

edit::ScriptResult run(const std::string& text, edit::ScriptOptions o = {}) {
  edit::Editor ed(plate().mesh, plate().features);
  return edit::run_script(edit::parse_script(text, "t.s2e"), ed, o);
}

void expect_script_error(const std::string& text, const std::string& where, const std::string& what,
                         edit::ScriptOptions o = {}) {
  try {
    run(text, o);
    FAIL() << "no error";
  } catch (const edit::ScriptError& e) {
    EXPECT_NE(std::string(e.what()).find("t.s2e:" + where), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

void expect_failure(const std::string& text, const std::string& what, edit::ScriptOptions o = {}) {
  try {
    run(text, o);
    FAIL() << "no failure";
  } catch (const edit::ScriptError& e) {
    FAIL() << "a script error instead of a failure: " << e.what();
  } catch (const ProcessingError& e) {
    EXPECT_NE(std::string(e.what()).find(what), std::string::npos) << e.what();
  }
}

TEST(EditInterpreter, SelectionsAndPickers) {
  const auto r = run(
      "let holes = select cylinder where radius ~ 3 +- 0.5\n"
      "let big = select cylinder where radius > 5\n"
      "let vertical = select cylinder where axis || z and not radius > 5\n"
      "let top = select plane where normal ~ +z highest\n"
      "let sides = select plane where normal ~ +x or normal ~ -x or normal ~ [0, 1, 0] or normal ~ -y\n"
      "let rims = select circle where adjacent to big\n"
      "let near = select cylinder nearest [-22, -12, 4]\n"
      "let largest = select plane largest\n"
      "assert holes.count == 4\n"
      "assert big.count == 1\n"
      "assert vertical.count == 4\n"
      "assert sides.count == 4\n"
      "assert rims.count == 2\n"
      "assert near.center ~ [-22, -12, 4] +- 0.01\n"
      "assert largest.area > 1000\n"
      "assert top.normal ~ +z +- 0.001\n");
  EXPECT_EQ(r.asserts, 8);
  EXPECT_EQ(r.statements[0].selected.size(), 4u);
}

TEST(EditInterpreter, ParametersExpressionsAndOverrides) {
  edit::ScriptOptions o;
  o.overrides["r"] = "2 * 2.25";
  const auto r = run(
      "param r = 4\n"
      "param lift = [0, 0, 1]\n"
      "let hole = select cylinder nearest [22, 12, 4]\n"
      "let target = (r + hole.radius) / 2 - 0.25 mm\n"
      "set hole.radius = target\n"
      "assert hole.radius ~ 3.5 +- 1e-4\n",
      o);
  EXPECT_EQ(r.asserts, 1);
}

TEST(EditInterpreter, ExportsAreCollectedNotWritten) {
  const auto r = run("let hole = select cylinder nearest [22, 12, 4]\nexport \"a.ply\"\nset hole.radius = 4\nexport \"b.stl\"\n");
  ASSERT_EQ(r.exports.size(), 2u);
  EXPECT_EQ(r.exports[0].first, "a.ply");
  EXPECT_FALSE(std::filesystem::exists("a.ply"));
}

TEST(EditInterpreter, DryRunLinesSayWhatIsSelectedAndChanged) {
  std::vector<std::string> lines;
  edit::ScriptOptions o;
  o.say = [&](const std::string& s) { lines.push_back(s); };
  run("let hole = select cylinder nearest [22, 12, 4]\nset hole.radius = 4\n", o);
  std::string all;
  for (const auto& l : lines) all += l + "\n";
  EXPECT_NE(all.find("line 1: let hole"), std::string::npos) << all;
  EXPECT_NE(all.find("selects P"), std::string::npos) << all;
  EXPECT_NE(all.find("propagates: G"), std::string::npos) << all;
  EXPECT_NE(all.find("equal_radius"), std::string::npos) << all;
}

TEST(EditInterpreter, UnknownName) { expect_script_error("set holes.radius = 4\n", "1:5", "unknown name 'holes'"); }
TEST(EditInterpreter, UnknownNameInExpression) {
  expect_script_error("let h = select cylinder\nset h.radius = r + 1\n", "2:16", "unknown name 'r'");
}
TEST(EditInterpreter, ValueUsedAsSelection) { expect_script_error("param r = 3\nlock r\n", "2:6", "is a value, not a selection"); }
TEST(EditInterpreter, SelectionUsedAsValue) {
  expect_script_error("let h = select cylinder\nlet x = h + 1\n", "2:9", "is a selection, not a value");
}
TEST(EditInterpreter, VectorWhereNumber) {
  expect_script_error("let h = select cylinder\nset h.radius = [1, 2, 3]\n", "2:16", "must be a number, not a vector");
}
TEST(EditInterpreter, NumberWhereVector) { expect_script_error("let h = select cylinder\nmove h by 3\n", "2:11", "must be a vector"); }
TEST(EditInterpreter, DivisionByZero) { expect_script_error("param a = 1 / (2 - 2)\n", "1:13", "division by zero"); }
TEST(EditInterpreter, EmptySelectionEdit) {
  expect_script_error("let s = select sphere\nset s.radius = 2\n", "2:5", "selects no feature");
}
TEST(EditInterpreter, RadiusOfAPlane) {
  expect_script_error("let t = select plane\nset t.radius = 2\n", "2:5", "only cylinders, spheres, circles and arcs have a radius");
}
TEST(EditInterpreter, DifferingPropertyInExpression) {
  expect_script_error("let c = select cylinder\nlet x = c.radius\n", "2:9", "differ");
}
TEST(EditInterpreter, UnknownSetParameter) {
  edit::ScriptOptions o;
  o.overrides["nope"] = "1";
  try {
    run("param r = 1\n", o);
    FAIL();
  } catch (const InvalidInput& e) {
    EXPECT_NE(std::string(e.what()).find("--set nope=1"), std::string::npos) << e.what();
  }
}
TEST(EditInterpreter, FailedAssertNamesTheLine) {
  expect_failure("let h = select cylinder nearest [22, 12, 4]\n\nassert h.radius ~ 4 +- 0.05\n", "t.s2e:3: `assert h.radius");
}
TEST(EditInterpreter, FailedConstraintAssert) {
  expect_failure("let t = select plane where normal ~ +z\nlet s = select plane where normal ~ +x\nassert parallel(t, s)\n",
                 "assert failed: parallel");
}
TEST(EditInterpreter, ConflictWithLockedFeature) {
  expect_failure("let t = select plane where normal ~ +z\nlet b = select plane where normal ~ -z\nlock b\n"
                 "rotate t about [1, 0, 0] by 2 deg\n",
                 "locked");
}

TEST(EditInterpreter, SetValueMustBeAnExpression) {
  edit::ScriptOptions o;
  o.overrides["d"] = "select plane";
  try {
    run("param d = 1\n", o);
    FAIL() << "no error";
  } catch (const edit::ScriptError& e) {
    EXPECT_NE(std::string(e.what()).find("--set d=select plane:1:1"), std::string::npos) << e.what();
  }
  o.overrides["d"] = "4 5";
  try {
    run("param d = 1\n", o);
    FAIL() << "no error";
  } catch (const edit::ScriptError& e) {
    EXPECT_NE(std::string(e.what()).find("--set d=4 5:1:3: expected end of the value"), std::string::npos) << e.what();
  }
}
TEST(EditInterpreter, ZeroDirectionOfAPicker) {
  expect_script_error("let t = select plane highest along [0, 0, 0]\n", "1:36", "zero vector");
}
TEST(EditInterpreter, HugeMoveIsRefusedNotWritten) {
  expect_script_error("let t = select plane where normal ~ +z\nmove t by [1e308, 1e308, 0] * 10\n", "2:29", "not finite");
  expect_failure("let t = select plane where normal ~ +z\nmove t by [1e308, 0, 0]\n", "folds or collapses");
}
TEST(EditInterpreter, FixedAngleAssertTakesItsValue) {
  const auto r = run("let t = select plane where normal ~ +z\nlet s = select plane where normal ~ +x\n"
                     "assert fixed_angle(t, s) = 90\n");
  EXPECT_EQ(r.asserts, 1);
}
TEST(EditInterpreter, ASharedVertexMovesOnceWhenTwoSelectedFeaturesShareIt) {
  // A hole and its rim circles moved together: the rims move by the vector, not twice it.
  edit::Editor ed(plate().mesh, plate().features);
  edit::run_script(edit::parse_script("let h = select feature where center ~ [22, 12, 4] +- 4.5 and radius ~ 3 +- 0.1\n"
                                      "assert h.count >= 3\nmove h by [0, 0, 0.5]\n",
                                      "t.s2e"),
                   ed);
  for (double d : ed.displacement()) EXPECT_TRUE(d == 0.0 || std::abs(d - 0.5) < 1e-12) << d;
}
TEST(EditInterpreter, VertexEditBubblesIntoThePatchesHoldingIt) {
  // The plate's corner (30, 20, 8): top, side_xp and side_yp hold it and follow; nothing else moves.
  const Mesh& m = plate().mesh;
  int corner = -1;
  for (auto v : m.vertices())
    if ((to_eigen(m.point(v)) - Eigen::Vector3d(30, 20, 8)).norm() < 1e-9) corner = v.idx();
  ASSERT_GE(corner, 0);
  edit::Editor ed(plate().mesh, plate().features);
  const auto r = edit::run_script(
      edit::parse_script("move vertex " + std::to_string(corner) + " by [0, 0, 0.2]\n", "t.s2e"), ed);
  ASSERT_EQ(r.statements.size(), 1u);
  const auto d = ed.displacement();
  EXPECT_NEAR(d[corner], 0.2, 1e-12);
  std::set<int> held;
  for (const auto& f : r.statements[0].edit.free)
    for (int v : ed.vertices(f)) held.insert(v);
  for (int v = 0; v < static_cast<int>(d.size()); ++v)
    if (!held.count(v)) {
      EXPECT_EQ(d[v], 0.0) << v;
    }
  EXPECT_GE(r.statements[0].edit.free.size(), 3u);
  expect_script_error("move vertex 1e9 by [0, 0, 1]\n", "1:13", "does not exist");
  expect_script_error("move vertex 1.5 by [0, 0, 1]\n", "1:13", "does not exist");
}
TEST(EditInterpreter, LockedLineMakesAConflict) {
  expect_failure("let h = select cylinder nearest [22, 12, 4]\nlet rim = select circle nearest [22, 12, 8]\nlock rim\n"
                 "set h.radius = 3.5\n",
                 "locked");
}

}  // namespace
}  // namespace s2c::test
