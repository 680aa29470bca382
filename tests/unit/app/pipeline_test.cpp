// The scan2cad run driver: manifest, skipping up-to-date stages, re-running after changes,
// stopping cleanly on failure; and the environment the `scan2cad` dispatcher gives the stages.
#include <cstdlib>
#include <fstream>

#include <nlohmann/json.hpp>

#include "../test_util.h"
#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "src/pipeline.h"

namespace fs = std::filesystem;
using namespace s2c;
using nlohmann::json;

namespace {

int run(const std::string& args) {
  const std::string cmd = (test::bin_dir() / "scan2cad").string() + " run " + args + " --quiet";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

json manifest(const fs::path& out) {
  std::ifstream f(out / "manifest.json");
  return json::parse(f);
}

json stage(const json& m, const std::string& name) {
  for (const auto& s : m["stages"])
    if (s["name"] == name) return s;
  return {};
}

}  // namespace

TEST(Pipeline, ClassifiesInputs) {
  const auto dir = test::scratch_dir();
  EXPECT_EQ(app::classify_input(test::source_dir() / "fixtures/parts/plate.stl"), app::InputKind::mesh);
  test::write_text(dir / "cloud.ply",
                   "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nproperty float z\n"
                   "end_header\n0 0 0\n");
  EXPECT_EQ(app::classify_input(dir / "cloud.ply"), app::InputKind::cloud);
  fs::create_directories(dir / "stream");
  test::write_text(dir / "stream/stream.yaml", "");
  EXPECT_EQ(app::classify_input(dir / "stream"), app::InputKind::stream);
  fs::create_directories(dir / "plain");
  EXPECT_THROW(app::classify_input(dir / "plain"), InvalidInput);
  EXPECT_THROW(app::classify_input(dir / "missing.stl"), InvalidInput);
}

TEST(Pipeline, ReRunSkipsAndInputChangeReRuns) {
  const auto dir = test::scratch_dir();
  fs::copy_file(test::source_dir() / "fixtures/parts/plate.stl", dir / "part.stl");
  const std::string args = (dir / "part.stl").string() + " --out " + (dir / "out").string();
  ASSERT_EQ(run(args), 0);
  json m1 = manifest(dir / "out");
  ASSERT_EQ(stage(m1, "check")["status"], "ok");
  EXPECT_FALSE(stage(m1, "check").value("skipped", false));
  EXPECT_TRUE(fs::exists(dir / "out/check.json"));

  ASSERT_EQ(run(args), 0);
  json m2 = manifest(dir / "out");
  EXPECT_TRUE(stage(m2, "check").value("skipped", false)) << m2.dump(2);

  // Change the input: every stage that depends on it runs again.
  fs::copy_file(test::source_dir() / "fixtures/parts/pocket.stl", dir / "part.stl", fs::copy_options::overwrite_existing);
  ASSERT_EQ(run(args), 0);
  json m3 = manifest(dir / "out");
  EXPECT_FALSE(stage(m3, "check").value("skipped", false));
  EXPECT_NE(m3["input"]["sha256"], m1["input"]["sha256"]);

  // An output changed behind the driver's back is not trusted either.
  test::write_text(dir / "out/check.json", "{}");
  ASSERT_EQ(run(args), 0);
  EXPECT_FALSE(stage(manifest(dir / "out"), "check").value("skipped", false));

  // --force runs everything.
  ASSERT_EQ(run(args + " --force"), 0);
  EXPECT_FALSE(stage(manifest(dir / "out"), "check").value("skipped", false));
}

TEST(Pipeline, FailedStageStopsWithItsExitCodeAndKeepsEarlierOutputs) {
  const auto dir = test::scratch_dir();
  test::write_text(dir / "broken.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n");
  const int rc = run((dir / "broken.off").string() + " --out " + (dir / "out").string());
  EXPECT_NE(rc, 0);
  const json m = manifest(dir / "out");
  bool any_failed = false;
  for (const auto& s : m["stages"]) any_failed |= s["status"] == "failed";
  EXPECT_TRUE(any_failed) << m.dump(2);
}

TEST(Pipeline, BadInputExitsTwo) {
  const auto dir = test::scratch_dir();
  EXPECT_EQ(run((dir / "nothing.stl").string() + " --out " + (dir / "out").string()), kExitBadInput);
  EXPECT_EQ(run("--out " + (dir / "out").string()), kExitBadInput);
}

TEST(Pipeline, HashOfADirectoryChangesWithAnyFile) {
  const auto dir = test::scratch_dir();
  fs::create_directories(dir / "d/sub");
  test::write_text(dir / "d/a", "1");
  test::write_text(dir / "d/sub/b", "2");
  const std::string h1 = app::hash_path(dir / "d");
  EXPECT_EQ(h1, app::hash_path(dir / "d"));
  test::write_text(dir / "d/sub/b", "3");
  EXPECT_NE(h1, app::hash_path(dir / "d"));
}

// The dispatcher starts the stage with the caller's environment as it is (stop 34 removed the
// huge-pages tunable it used to add: bench/README.md, "Huge pages"): a copy of `scan2cad` next to
// a shell "stage" that prints what it was given.
TEST(Dispatcher, StagesInheritTheEnvironmentUnchanged) {
  const auto dir = test::scratch_dir();
  fs::copy_file(test::bin_dir() / "scan2cad", dir / "scan2cad");
  const fs::path stage = dir / "scan2cad-env";
  test::write_text(stage, "#!/bin/sh\nprintf '%s' \"${GLIBC_TUNABLES-unset}\" > \"$1\"\n");
  fs::permissions(stage, fs::perms::owner_all, fs::perm_options::add);
  const auto seen = [&](const std::string& env) {
    const fs::path out = dir / "seen.txt";
    fs::remove(out);
    const std::string cmd = env + " " + (dir / "scan2cad").string() + " env " + out.string();
    EXPECT_EQ(std::system(cmd.c_str()), 0) << cmd;
    std::ifstream f(out);
    return std::string(std::istreambuf_iterator<char>(f), {});
  };
  EXPECT_EQ(seen("env -u GLIBC_TUNABLES"), "unset");
  EXPECT_EQ(seen("GLIBC_TUNABLES=glibc.malloc.arena_max=2"), "glibc.malloc.arena_max=2");
  EXPECT_EQ(seen("GLIBC_TUNABLES=glibc.malloc.hugetlb=1"), "glibc.malloc.hugetlb=1");
}
