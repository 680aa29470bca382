// s2c-make-defects on a fixture part: every variant exists, holds the defects defects.json says
// (re-checked from the written file), and the same seed gives the same bytes.
#include <cstdlib>
#include <set>

#include <nlohmann/json.hpp>

#include "../test_util.h"
#include "s2c/core/check.h"
#include "s2c/core/files.h"
#include "s2c/core/io.h"
#include "s2c/repair/gaps.h"
#include "s2c/repair/holes.h"

namespace fs = std::filesystem;
using namespace s2c;
using nlohmann::json;

namespace {

int run(const std::string& args) {
  const std::string cmd = (test::bin_dir() / "s2c-make-defects").string() + " " + args + " --quiet";
  const int rc = std::system(cmd.c_str());
  return WIFEXITED(rc) ? WEXITSTATUS(rc) : -1;
}

// --edge 3 keeps the plate at ~36k faces so the test stays quick (the default refines further).
std::string plate_args(const fs::path& out, int seed) {
  return (test::source_dir() / "fixtures/parts/plate.stl").string() + " --out " + out.string() + " --seed " +
         std::to_string(seed) + " --edge 3";
}

}  // namespace

TEST(MakeDefects, PlateVariantsHoldTheirDefects) {
  const fs::path dir = test::scratch_dir();
  ASSERT_EQ(run(plate_args(dir / "a", 1)), 0);
  const json doc = json::parse(read_file(dir / "a" / "defects.json"));
  EXPECT_EQ(doc["format"], "scan2cad.defects/1");
  EXPECT_EQ(doc["seed"], 1);

  const auto clean = read_soup(dir / "a" / "clean.ply");
  const auto c0 = check_mesh(clean);
  EXPECT_TRUE(c0.cad_ready) << ::testing::PrintToString(c0.problems);
  EXPECT_EQ(clean.faces.size(), doc["clean"]["faces"].get<std::size_t>());

  std::set<std::string> names;
  for (const auto& v : doc["variants"]) {
    const std::string name = v["name"];
    names.insert(name);
    SCOPED_TRACE(name);
    const auto soup = read_soup(dir / "a" / v["file"].get<std::string>());
    const auto r = check_mesh(soup);
    // The file holds what defects.json says it holds.
    const auto& c = v["check"];
    EXPECT_EQ(r.boundary_loops, c["boundary_loops"].get<std::size_t>());
    EXPECT_EQ(r.nonmanifold_vertices, c["nonmanifold_vertices"].get<std::size_t>());
    EXPECT_EQ(r.nonmanifold_edges, c["nonmanifold_edges"].get<std::size_t>());
    EXPECT_EQ(r.orientation_conflicts, c["orientation_conflicts"].get<std::size_t>());
    EXPECT_EQ(r.components, c["components"].get<std::size_t>());
    EXPECT_EQ(r.self_intersections, c["self_intersections"].get<std::size_t>());
    EXPECT_EQ(r.duplicate_faces, c["duplicate_faces"].get<std::size_t>());
    EXPECT_EQ(r.degenerate_faces, 0u);
    EXPECT_FALSE(r.cad_ready);
    const auto& d = v["defects"];
    if (name == "holes") {
      EXPECT_EQ(d["holes"], 2);
      EXPECT_EQ(r.boundary_loops, 2u);
      EXPECT_EQ(r.nonmanifold_vertices, 0u);
      EXPECT_EQ(r.components, 1u);
      repair::HoleStats st;
      EXPECT_EQ(repair::find_holes(soup, &st).size(), 2u);
      EXPECT_EQ(st.single_holes, 2u);
    } else if (name == "nested") {
      EXPECT_EQ(r.boundary_loops, 2u);
      EXPECT_EQ(r.nonmanifold_vertices, 2u);
      EXPECT_EQ(r.nonmanifold_edges, 0u);
      repair::HoleStats st;
      const auto holes = repair::find_holes(soup, &st);
      EXPECT_EQ(st.nested_holes, 2u);
      EXPECT_EQ(st.common_points, 2u);
      // Two touching holes stay two; the island's rim is merged into its outer hole.
      EXPECT_EQ(holes.size(), 3u);
      std::size_t with_repeat = 0;
      for (const auto& h : holes)
        with_repeat += std::set<int>(h.loop.begin(), h.loop.end()).size() < h.loop.size();
      EXPECT_EQ(with_repeat, 1u);
    } else if (name == "flipped") {
      EXPECT_GT(d["flipped_faces"].get<int>(), 0);
      EXPECT_GT(r.orientation_conflicts, 0u);
      EXPECT_EQ(r.boundary_loops, 0u);
      EXPECT_FALSE(r.oriented);
    } else if (name == "duplicates") {
      EXPECT_EQ(r.duplicate_faces, 5u);
      EXPECT_EQ(d["duplicate_faces"], 5);
    } else if (name == "gap") {
      EXPECT_EQ(r.components, 2u);
      EXPECT_GE(r.boundary_loops, 2u);
      EXPECT_EQ(r.self_intersections, 0u);
      // The gap is what close_gaps is for: afterwards the part is closed again.
      auto closed = soup;
      repair::close_gaps(closed);
      const auto after = check_mesh(closed);
      EXPECT_EQ(after.boundary_edges, 0u);
      EXPECT_EQ(after.nonmanifold_edges, 0u);
      EXPECT_EQ(after.components, 1u);
      EXPECT_TRUE(after.oriented);
      EXPECT_TRUE(after.closed);
      EXPECT_EQ(after.self_intersections, 0u);
      EXPECT_EQ(after.degenerate_faces, 0u);
    } else if (name == "self_intersections") {
      EXPECT_GT(r.self_intersections, 0u);
      EXPECT_TRUE(r.closed);
    } else if (name == "loose") {
      EXPECT_EQ(r.components, 4u);
      EXPECT_EQ(d["loose_components"], 3);
    } else if (name == "everything") {
      EXPECT_EQ(r.duplicate_faces, 5u);
      EXPECT_GT(r.orientation_conflicts, 0u);
      EXPECT_GT(r.self_intersections, 0u);
      EXPECT_GE(r.nonmanifold_vertices, 2u);
      EXPECT_EQ(r.components, 2u + 3u);  // the two sides of the gap and the loose triangles
      EXPECT_GE(r.boundary_loops, 2u + 2u + 2u + 3u);
    }
  }
  EXPECT_EQ(names, (std::set<std::string>{"holes", "nested", "flipped", "duplicates", "gap", "self_intersections",
                                          "loose", "everything"}));

  // Deterministic: the same seed gives the same files, another seed other defects.
  ASSERT_EQ(run(plate_args(dir / "b", 1)), 0);
  for (const auto& v : doc["variants"])
    EXPECT_EQ(sha256_file(dir / "a" / v["file"].get<std::string>()), sha256_file(dir / "b" / v["file"].get<std::string>()))
        << v["file"];
  ASSERT_EQ(run(plate_args(dir / "c", 2)), 0);
  EXPECT_NE(sha256_file(dir / "a" / "holes.ply"), sha256_file(dir / "c" / "holes.ply"));
}

TEST(MakeDefects, RefusesOpenInputAndBadUsage) {
  const fs::path dir = test::scratch_dir();
  auto open = test::cube(10);
  open.faces.pop_back();
  test::write_text(dir / "open.off", [&] {
    std::string s = "OFF\n8 11 0\n";
    for (const auto& p : open.vertices) s += std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
    for (const auto& f : open.faces) s += "3 " + std::to_string(f[0]) + " " + std::to_string(f[1]) + " " + std::to_string(f[2]) + "\n";
    return s;
  }());
  EXPECT_EQ(run((dir / "open.off").string() + " --out " + (dir / "out").string() + " 2>/dev/null"), 2);
  EXPECT_FALSE(fs::exists(dir / "out" / "defects.json"));
  EXPECT_EQ(run("2>/dev/null"), 2);  // no input
}
