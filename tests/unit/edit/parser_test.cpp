// The edit language's parser: every statement form, and one test per error class (each names
// line, column, what was expected and what was found).
#include <gtest/gtest.h>

#include "s2c/edit/script.h"

namespace s2c::edit {
namespace {

void expect_error(const std::string& text, const std::string& where, const std::string& what) {
  try {
    parse_script(text, "t.s2e");
    FAIL() << "no error for: " << text;
  } catch (const ScriptError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("t.s2e:" + where + ":"), std::string::npos) << msg;
    EXPECT_NE(msg.find(what), std::string::npos) << msg;
  }
}

TEST(EditParser, DesignCoreParses) {
  const Script s = parse_script(
      "# comments; one statement per line\n"
      "let bolts = select cylinder where radius ~ 3 +- 0.5        # several features\n"
      "let top   = select plane where normal ~ +z highest\n"
      "set bolts.radius = 4\n"
      "move top by [0, 0, 3]\n"
      "rotate top about [0, 0, 1] by 15 deg\n"
      "constrain parallel(top, bottom)\n"
      "assert bolts.radius ~ 4 +- 0.05\n"
      "export \"out/edited.stl\"\n",
      "t.s2e");
  ASSERT_EQ(s.statements.size(), 8u);
  EXPECT_EQ(s.statements[0].kind, Statement::Kind::let_select);
  EXPECT_EQ(s.statements[0].selector.type, "cylinder");
  ASSERT_TRUE(s.statements[0].selector.where);
  EXPECT_EQ(s.statements[0].selector.where->kind, Condition::Kind::approx);
  EXPECT_EQ(s.statements[1].selector.picker, Picker::highest);
  EXPECT_EQ(s.statements[1].selector.where->kind, Condition::Kind::direction);
  EXPECT_EQ(s.statements[2].kind, Statement::Kind::set);
  EXPECT_EQ(s.statements[2].property, "radius");
  EXPECT_EQ(s.statements[3].kind, Statement::Kind::move);
  EXPECT_EQ(s.statements[4].kind, Statement::Kind::rotate);
  EXPECT_EQ(s.statements[5].kind, Statement::Kind::constrain);
  EXPECT_EQ(s.statements[5].members, (std::vector<std::string>{"top", "bottom"}));
  EXPECT_EQ(s.statements[6].kind, Statement::Kind::check);
  EXPECT_EQ(s.statements[7].path, "out/edited.stl");
  EXPECT_EQ(s.statements[3].at.line, 5);
  EXPECT_EQ(s.statements[3].text, "move top by [0, 0, 3]");
}

TEST(EditParser, ExtensionsParse) {
  const Script s = parse_script(
      "param r = 4\n"
      "param d = [0, 0, 2 * r / 4 - -1]\n"
      "let holes = select cylinders where (radius > 2 and radius <= 3.5) or not axis || x\n"
      "let ring = select plane where adjacent to holes and area >= 10 largest\n"
      "let near = select circle nearest [22, 12, 8]\n"
      "let low = select plane lowest along [0, 1, 0]\n"
      "let x = holes.radius + 1 mm\n"
      "lock ring\n"
      "scale holes by 1.5 at [0, 0, 0]\n"
      "rotate ring about -y by 0.1 rad at ring.center\n"
      "unconstrain equal_radius(holes, near)\n"
      "unconstrain holes\n"
      "constrain fixed_angle(ring, low) = 30\n"
      "assert parallel(ring, low)\n"
      "assert holes.count == 4\n"
      "assert ring.normal ~ [0, 0, 1] +- 1\n"
      "set holes.radius = r × 2 ÷ 2\n"
      "move vertex 12 by [0, 0, 0.1]\n",
      "t.s2e");
  ASSERT_EQ(s.statements.size(), 18u);
  EXPECT_EQ(s.statements[17].kind, Statement::Kind::move_vertex);
  EXPECT_EQ(s.statements[2].selector.where->kind, Condition::Kind::any_of);
  EXPECT_EQ(s.statements[3].selector.where->kind, Condition::Kind::all_of);
  EXPECT_EQ(s.statements[3].selector.picker, Picker::largest);
  EXPECT_EQ(s.statements[4].selector.picker, Picker::nearest);
  EXPECT_EQ(s.statements[6].kind, Statement::Kind::let_value);
  EXPECT_EQ(s.statements[10].kind, Statement::Kind::unconstrain);
  EXPECT_EQ(s.statements[10].constraint, "equal_radius");
  EXPECT_EQ(s.statements[11].name, "holes");
  ASSERT_TRUE(s.statements[12].value);
  EXPECT_EQ(s.statements[14].property, "count");
}

TEST(EditParser, SetWithUnicodeTimesIsAnExpression) {
  // "± 0" after an expression is not part of set: the line must end after the value.
  expect_error("set a.radius = 2 ± 0\n", "1:18", "expected end of line, found '+-'");
}

TEST(EditParser, UnexpectedCharacter) { expect_error("move top by [0, 0, $]\n", "1:20", "unexpected character '$'"); }
TEST(EditParser, UnexpectedByte) { expect_error("lock \x01\n", "1:6", "unexpected byte 0x01"); }
TEST(EditParser, UnterminatedString) { expect_error("export \"out.stl\n", "1:8", "unterminated string"); }
TEST(EditParser, UnknownStatement) { expect_error("\n\nwiden holes by 2\n", "3:1", "unknown statement 'widen'"); }
TEST(EditParser, MissingKeyword) { expect_error("move top [0, 0, 1]\n", "1:10", "expected 'by', found '['"); }
TEST(EditParser, UnknownConstraintKind) { expect_error("constrain tangent(a, b)\n", "1:11", "unknown constraint kind 'tangent'"); }
TEST(EditParser, UnknownProperty) { expect_error("let a = select plane where colour ~ 3\n", "1:28", "unknown property 'colour'"); }
TEST(EditParser, ParamAfterStatement) { expect_error("lock a\nparam r = 3\n", "2:1", "'param' must come before"); }
TEST(EditParser, VectorOfFour) { expect_error("move a by [1, 2, 3, 4]\n", "1:19", "a vector has 3 components"); }
TEST(EditParser, VectorUnclosed) { expect_error("move a by [1, 2, 3\n", "1:19", "expected ']', found end of line"); }
TEST(EditParser, TrailingTokens) { expect_error("lock a b\n", "1:8", "expected end of line, found 'b'"); }
TEST(EditParser, UnknownType) { expect_error("let a = select torus\n", "1:16", "expected a feature type"); }
TEST(EditParser, MissingValue) { expect_error("set a.radius =\n", "1:15", "expected a number, a name, '[' or '(', found end of line"); }
TEST(EditParser, SetUnsupportedProperty) { expect_error("set a.length = 3\n", "1:7", "expected 'radius' or 'half_angle', found 'length'"); }
TEST(EditParser, ExportNeedsString) { expect_error("export out.stl\n", "1:8", "expected a quoted file name"); }
TEST(EditParser, KeywordAsName) { expect_error("let select = select plane\n", "1:5", "expected a name for the selection"); }
TEST(EditParser, MissingComparison) { expect_error("let a = select cylinder where radius 3\n", "1:38", "expected a comparison"); }
TEST(EditParser, UnclosedParenthesis) { expect_error("let a = select plane where (area > 3\n", "1:37", "expected ')'"); }
TEST(EditParser, BadPicker) { expect_error("let a = select plane biggest\n", "1:22", "expected 'where', a picker"); }
TEST(EditParser, CenterNeedsTolerance) { expect_error("let a = select sphere where center ~ [0, 0, 0]\n", "1:47", "expected '+-'"); }
TEST(EditParser, NestingIsBounded) {
  expect_error("let a = " + std::string(100000, '(') + "1\n", "1", "nested more than 256 levels deep");
  std::string chain = "let a = 1";
  for (int k = 0; k < 5000; ++k) chain += "+1";
  expect_error(chain + "\n", "1", "more than 4096 terms");
}
TEST(EditParser, ColumnsCountCharacters) { expect_error("let a = 2 × 3 ±\n", "1:15", "expected end of line, found '+-'"); }
TEST(EditParser, EmptyScriptIsValid) { EXPECT_TRUE(parse_script("# nothing\n\n", "t.s2e").statements.empty()); }

}  // namespace
}  // namespace s2c::edit
