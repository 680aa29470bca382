// features.json ("scan2cad.features/1"): what is written reads back identically, and every
// malformed file is refused with a message naming the file and the offending element.
#include "s2c/features/feature_set.h"

#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "s2c/core/errors.h"

namespace s2c::features {
namespace {

using nlohmann::json;

FeatureSet sample() {
  FeatureSet f;
  f.mesh_vertices = 8;
  f.mesh_faces = 12;
  f.mesh_sha256 = "abc123";
  Patch p;
  p.id = "P0";
  p.faces = {0, 1};
  p.area = 4.5;
  p.rms = 0.01;
  p.shape.type = ShapeType::plane;
  p.shape.dir = {0, 0, 1};
  p.shape.point = {1, 2, 3};
  p.attributes["note"] = "\"top face\"";
  f.patches.push_back(p);
  Patch c;
  c.id = "P1";
  c.faces = {2, 3, 4};
  c.shape.type = ShapeType::cylinder;
  c.shape.point = {0, 0, 0};
  c.shape.dir = {0, 1, 0};
  c.shape.radius = 3.0;
  c.attributes["tags"] = "[1,2,{\"a\":true}]";
  f.patches.push_back(c);
  Line l;
  l.id = "L0";
  l.vertices = {0, 1, 2};
  l.closed = true;
  l.shape.type = ShapeType::circle;
  l.shape.point = {0, 0, 1};
  l.shape.dir = {0, 0, 1};
  l.shape.radius = 2.0;
  f.lines.push_back(l);
  Group g;
  g.id = "G0";
  g.kind = "constraint";
  g.constraint = ConstraintKind::fixed_angle;
  g.members = {"P0", "P1"};
  g.value = 45.0;
  f.groups.push_back(g);
  Group comp;
  comp.id = "G1";
  comp.kind = "component";
  comp.members = {"P0", "P1", "L0", "G0"};  // groups may contain groups
  f.groups.push_back(comp);
  f.adjacency = {{"P0", "P1"}, {"P0", "L0"}};
  return f;
}

TEST(FeatureSetJson, RoundTripKeepsEverything) {
  const FeatureSet f = sample();
  const std::string text = to_json_text(f);
  const FeatureSet g = from_json_text(text, "f.json");
  EXPECT_EQ(to_json_text(g), text);
  ASSERT_EQ(g.patches.size(), 2u);
  EXPECT_EQ(g.patches[1].shape.type, ShapeType::cylinder);
  EXPECT_DOUBLE_EQ(g.patches[1].shape.radius, 3.0);
  EXPECT_EQ(json::parse(g.patches[1].attributes.at("tags")), json::parse("[1,2,{\"a\":true}]"));
  EXPECT_TRUE(g.lines[0].closed);
  ASSERT_TRUE(g.groups[0].constraint.has_value());
  EXPECT_EQ(*g.groups[0].constraint, ConstraintKind::fixed_angle);
  EXPECT_DOUBLE_EQ(*g.groups[0].value, 45.0);
  EXPECT_EQ(g.groups[1].members.back(), "G0");
  EXPECT_EQ(g.adjacency.size(), 2u);
}

// The text is dump(1)'s but for arrays of numbers or strings, one line each: a million-face
// part's face lists are most of the file. Everything else is as the JSON library writes it.
TEST(FeatureSetJson, ListsOfNumbersAndNamesTakeOneLine) {
  FeatureSet f = sample();
  f.patches[1].faces = {2, 3, 4, 4294967, -1};
  f.patches[1].area = 0.1;
  const std::string text = to_json_text(f);
  EXPECT_NE(text.find("\"faces\": [2, 3, 4, 4294967, -1]"), std::string::npos) << text;
  EXPECT_NE(text.find("\"members\": [\"P0\", \"P1\"]"), std::string::npos) << text;
  EXPECT_NE(text.find("\"area\": 0.1,"), std::string::npos) << text;
  EXPECT_NE(text.find("\n \"patches\": [\n  {\n   \"area\""), std::string::npos) << text;
  EXPECT_EQ(text.back(), '\n');
  const std::string none = to_json_text(FeatureSet{});  // the patches' list is printed on its own
  EXPECT_NE(none.find("\n \"patches\": []\n}\n"), std::string::npos) << none;
  EXPECT_TRUE(json::parse(none)["patches"].empty());
}

TEST(FeatureSetJson, EveryConstraintNameRoundTrips) {
  for (int k = 0; k <= static_cast<int>(ConstraintKind::equal_radius); ++k) {
    const auto kind = static_cast<ConstraintKind>(k);
    EXPECT_EQ(constraint_kind(constraint_name(kind)), kind);
  }
  EXPECT_THROW(constraint_kind("tangential"), InvalidInput);
}

/// Edits the sample's JSON with `change`, expects InvalidInput mentioning the file and `where`.
void expect_refused(const std::function<void(json&)>& change, const std::string& where) {
  json doc = json::parse(to_json_text(sample()));
  change(doc);
  try {
    from_json_text(doc.dump(), "bad.json");
    ADD_FAILURE() << "accepted a file with a bad " << where;
  } catch (const InvalidInput& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("bad.json"), std::string::npos) << msg;
    EXPECT_NE(msg.find(where), std::string::npos) << "message does not name " << where << ": " << msg;
  }
}

TEST(FeatureSetJson, MalformedFilesAreRefusedNamingTheElement) {
  expect_refused([](json& d) { d["format"] = "scan2cad.features/9"; }, "format");
  expect_refused([](json& d) { d.erase("mesh"); }, "mesh");
  expect_refused([](json& d) { d["mesh"]["faces"] = -3; }, "mesh");
  expect_refused([](json& d) { d["patches"][0]["faces"] = json::array({0, 99}); }, "patches[0]");
  expect_refused([](json& d) { d["patches"][1]["id"] = "P0"; }, "patches[1]");
  expect_refused([](json& d) { d["patches"][0]["shape"]["type"] = "torus"; }, "patches[0]");
  expect_refused([](json& d) { d["patches"][0]["shape"] = {{"type", "circle"}, {"center", {0, 0, 0}},
                                                            {"normal", {0, 0, 1}}, {"radius", 1}}; },
                 "patches[0].shape.type");
  expect_refused([](json& d) { d["patches"][0]["area"] = "big"; }, "patches[0]");
  expect_refused([](json& d) { d["lines"][0]["vertices"] = json::array({0, -1}); }, "lines[0]");
  expect_refused([](json& d) { d["lines"][0]["closed"] = 1; }, "lines[0].closed");
  expect_refused([](json& d) { d["lines"][0]["shape"] = {{"type", "plane"}, {"normal", {0, 0, 1}},
                                                         {"point", {0, 0, 0}}}; },
                 "lines[0].shape.type");
  expect_refused([](json& d) { d["groups"][0]["constraint"] = "tangential"; }, "groups[0].constraint");
  expect_refused([](json& d) { d["groups"][0].erase("constraint"); }, "groups[0]");
  expect_refused([](json& d) { d["groups"][1]["members"] = json::array({"P7"}); }, "groups[1].members");
  expect_refused([](json& d) { d["groups"][1]["members"] = json::array({1}); }, "groups[1].members");
  expect_refused([](json& d) { d["adjacency"][0] = json::array({"P0"}); }, "adjacency[0]");
  expect_refused([](json& d) { d["adjacency"][1] = json::array({"P0", "L9"}); }, "adjacency[1]");
  expect_refused([](json& d) { d["adjacency"] = json::object(); }, "adjacency");
}

TEST(FeatureSetJson, NotJsonOrNotAnObjectIsRefused) {
  EXPECT_THROW(from_json_text("{\"format\": ", "trunc.json"), InvalidInput);
  EXPECT_THROW(from_json_text("[1, 2]", "array.json"), InvalidInput);
  EXPECT_THROW(from_json_text("", "empty.json"), InvalidInput);
  EXPECT_THROW(from_json_text("{\"format\": 7}", "num.json"), InvalidInput);
}

}  // namespace
}  // namespace s2c::features
