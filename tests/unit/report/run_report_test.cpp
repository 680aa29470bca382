#include <gtest/gtest.h>

#include <fstream>

#include <nlohmann/json.hpp>

#include "s2c/core/files.h"
#include "s2c/report/run_report.h"
#include "test_util.h"

namespace s2c::report {
namespace {
namespace fs = std::filesystem;
using nlohmann::json;

/// A 10 mm cube as OFF text.
std::string cube_off() {
  const TriangleSoup c = test::cube(10);
  std::string s = "OFF\n8 12 0\n";
  for (const auto& p : c.vertices) s += std::to_string(p.x()) + " " + std::to_string(p.y()) + " " + std::to_string(p.z()) + "\n";
  for (const auto& t : c.faces) s += "3 " + std::to_string(t[0]) + " " + std::to_string(t[1]) + " " + std::to_string(t[2]) + "\n";
  return s;
}

/// A run folder whose repair ran and whose check failed, with a stale check.json and
/// reports/check.json from an earlier run lying around.
fs::path make_run(const fs::path& dir) {
  fs::create_directories(dir / "reports");
  test::write_text(dir / "input.off", cube_off());
  test::write_text(dir / "repaired.off", cube_off());
  json m = {{"format", "scan2cad.manifest/1"},
            {"input", {{"path", (dir / "input.off").string()}, {"kind", "mesh"}}},
            {"stages",
             {{{"name", "repair"}, {"status", "ok"}, {"seconds", 1.5},
               {"command", {(dir / "input.off").string(), "-o", (dir / "repaired.off").string()}}},
              {{"name", "check"}, {"status", "failed"}, {"exit_code", 3},
               {"command", {(dir / "repaired.off").string(), "-o", (dir / "check.json").string()}}}}}};
  test::write_text(dir / "manifest.json", m.dump());
  test::write_text(dir / "check.json", R"({"cad_ready": true, "closed": true, "problems": []})");
  test::write_text(dir / "reports" / "check.json", R"({"counts": {"stale_marker_count": 12345}})");
  return dir;
}

TEST(RunReport, ShowsWhatRanAndNothingStale) {
  const fs::path dir = make_run(test::scratch_dir() / "run");
  RunReportOptions o;
  o.run_dir = dir;
  o.output = dir / "report.html";
  o.render.width = 64;
  o.render.height = 48;
  o.reference = dir / "input.off";
  nlohmann::json counts;
  const RunReportResult r = write_run_report(o, &counts);
  const std::string page = read_file(o.output);
  EXPECT_EQ(r.pictures, 6);  // raw (the input), repaired, deviation × iso, iso-back
  EXPECT_TRUE(fs::exists(dir / "report_files" / "repaired_iso.png"));
  EXPECT_TRUE(fs::exists(dir / "report_files" / "deviation_iso-back.png"));
  EXPECT_NE(page.find("failed"), std::string::npos);
  // The failed check's old check.json and report are not shown as this run's.
  EXPECT_EQ(page.find("CAD-ready check of the final mesh"), std::string::npos);
  EXPECT_EQ(page.find("stale_marker_count"), std::string::npos);
  ASSERT_TRUE(r.deviation);
  EXPECT_NEAR(r.deviation->max_abs, 0.0, 1e-9);
  EXPECT_NEAR(counts["deviation"]["rms_mm"].get<double>(), 0.0, 1e-9);
  // Nothing temporary is left.
  for (const auto& e : fs::directory_iterator(dir)) EXPECT_EQ(e.path().filename().string().find(".tmp-"), std::string::npos);
  // Again: the report's own pictures folder is replaced.
  EXPECT_EQ(write_run_report(o).pictures, 6);
}

TEST(RunReport, RefusesWhatItMustNotTouch) {
  const fs::path dir = make_run(test::scratch_dir() / "run");
  RunReportOptions o;
  o.run_dir = dir;
  o.output = dir / "repaired.off";  // not HTML: would overwrite a run file
  test::expect_invalid_input([&] { write_run_report(o); }, {"repaired.off", ".html"});
  EXPECT_EQ(read_file(dir / "repaired.off"), cube_off());
  // A folder that happens to be called like the pictures folder is somebody's: never replaced.
  fs::create_directories(dir / "notes_files");
  test::write_text(dir / "notes_files" / "mine.txt", "keep me");
  o.output = dir / "notes.html";
  test::expect_invalid_input([&] { write_run_report(o); }, {"notes_files", "choose another"});
  EXPECT_TRUE(fs::exists(dir / "notes_files" / "mine.txt"));
  EXPECT_FALSE(fs::exists(dir / "notes.html"));
  // Not a run folder; a manifest with the wrong types: exit-2 errors naming the folder.
  o.run_dir = dir / "reports";
  o.output = dir / "r.html";
  test::expect_invalid_input([&] { write_run_report(o); }, {"manifest.json", "scan2cad run"});
  test::write_text(dir / "manifest.json", R"({"stages": [{"name": "repair", "status": 7}], "input": 3})");
  o.run_dir = dir;
  test::expect_invalid_input([&] { write_run_report(o); }, {dir.string()});
  EXPECT_FALSE(fs::exists(dir / "r.html"));
  EXPECT_FALSE(fs::exists(dir / "r_files"));
}

}  // namespace
}  // namespace s2c::report
