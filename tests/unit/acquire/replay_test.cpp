// Replay and record without hardware: a simulated scan replayed through acquire() must come out
// byte-identical; a corrupt replay leaves nothing behind.
#include <fmt/format.h>
#include <gtest/gtest.h>

#include "s2c/acquire/acquire.h"
#include "s2c/acquire/simulate.h"
#include "s2c/acquire/sources.h"
#include "s2c/core/files.h"
#include "../test_util.h"

namespace s2c {
namespace {

namespace fs = std::filesystem;

fs::path simulated_stream(const fs::path& dir, Sensor sensor = Sensor::depth) {
  SimulateOptions o;
  o.sensor = sensor;
  o.views = 4;
  o.width = 160;
  o.height = 120;
  o.focal_px = 140;
  simulate_scan(test::cube(20), dir / "scan", o);
  return dir / "scan";
}

TEST(Replay, RecordingAReplayReproducesTheStreamByteForByte) {
  for (Sensor sensor : {Sensor::depth, Sensor::laser}) {
    const fs::path dir = test::scratch_dir() / to_string(sensor);
    const fs::path original = simulated_stream(dir, sensor);
    auto src = make_replay_source({original, false});
    const AcquireResult r = acquire(*src, dir / "copy", {});
    ASSERT_FALSE(r.failure) << *r.failure;
    EXPECT_EQ(r.record.kept, 4u);
    for (const char* file : {"depth.txt", "poses.txt", "depth/000000.png", "depth/000003.png"})
      EXPECT_EQ(sha256_file(original / file), sha256_file(dir / "copy" / file)) << to_string(sensor) << " " << file;
    const Stream a = read_stream(original), b = read_stream(dir / "copy");
    EXPECT_EQ(b.info.width, a.info.width);
    EXPECT_EQ(b.info.sensor, a.info.sensor);
    EXPECT_DOUBLE_EQ(b.info.profile_step_mm, a.info.profile_step_mm);
    EXPECT_EQ(b.info.device, a.info.device) << "a replay records where the data came from";
  }
}

TEST(Replay, StopsAfterTheRequestedFrames) {
  const fs::path dir = test::scratch_dir();
  auto src = make_replay_source({simulated_stream(dir), false});
  AcquireOptions o;
  o.frames = 2;
  const AcquireResult r = acquire(*src, dir / "copy", o);
  EXPECT_EQ(r.record.kept, 2u);
  EXPECT_EQ(read_stream(dir / "copy").frames.size(), 2u);
}

TEST(Replay, RealtimeFollowsTheRecordedTiming) {
  const fs::path dir = test::scratch_dir();
  const fs::path s = simulated_stream(dir);
  // Space the 4 frames 0.1 s apart.
  std::string index = "# t file\n";
  for (int i = 0; i < 4; ++i) index += fmt::format("{:.1f} depth/{:06d}.png\n", 0.1 * i, i);
  test::write_text(s / "depth.txt", index);
  fs::remove(s / "poses.txt");
  auto src = make_replay_source({s, true});
  const AcquireResult r = acquire(*src, dir / "copy", {});
  EXPECT_EQ(r.record.kept, 4u);
  EXPECT_GE(r.seconds, 0.29);
  EXPECT_LT(r.seconds, 2.0);
}

TEST(Replay, CorruptFrameNamesTheFileAndLeavesNoOutput) {
  const fs::path dir = test::scratch_dir();
  const fs::path s = simulated_stream(dir);
  std::string png = read_file(s / "depth/000002.png");
  png.resize(png.size() / 2);
  test::write_text(s / "depth/000002.png", png);
  const std::string before = sha256_file(s / "depth/000002.png");
  auto src = make_replay_source({s, false});
  test::expect_invalid_input([&] { acquire(*src, dir / "copy", {}); }, {"000002.png"});
  EXPECT_FALSE(fs::exists(dir / "copy"));
  EXPECT_EQ(sha256_file(s / "depth/000002.png"), before) << "inputs are never modified";
}

TEST(Replay, ReplayIsStrictAboutTheStreamItReads) {
  const fs::path dir = test::scratch_dir();
  const fs::path s = simulated_stream(dir);
  test::write_text(s / "stream.yaml", "%YAML:1.0\n---\nformat: \"scan2cad.stream/1\"\nsensor: depth\n");
  auto src = make_replay_source({s, false});
  test::expect_invalid_input([&] { acquire(*src, dir / "copy", {}); }, {"stream.yaml", "width"});
  EXPECT_FALSE(fs::exists(dir / "copy"));
}

TEST(SourceSpec, ParsesTheThreeFormsAndExplainsMistakes) {
  EXPECT_EQ(parse_source_spec("v4l2:/dev/video2").path, "/dev/video2");
  const SourceSpec u = parse_source_spec("usb:1209:00aF");
  EXPECT_EQ(u.kind, SourceSpec::Kind::usb);
  EXPECT_EQ(u.vendor, 0x1209);
  EXPECT_EQ(u.product, 0x00af);
  EXPECT_EQ(parse_source_spec("replay:scans/a").kind, SourceSpec::Kind::replay);
  test::expect_invalid_input([] { parse_source_spec("camera0"); }, {"v4l2:/dev/videoN", "usb:VID:PID"});
  test::expect_invalid_input([] { parse_source_spec("usb:12345:1"); }, {"12345"});
  test::expect_invalid_input([] { parse_source_spec("usb:1209"); }, {"usb:VID:PID"});
  test::expect_invalid_input([] { parse_source_spec("v4l2:"); }, {"v4l2:/dev/videoN"});
}

TEST(Calibration, NamesTheMissingKey) {
  const fs::path dir = test::scratch_dir();
  const std::string base =
      "%YAML:1.0\n---\ncamera_matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n"
      "   data: [ 525., 0., 319.5, 0., 525., 239.5, 0., 0., 1. ]\n"
      "dist_coeffs: !!opencv-matrix\n   rows: 1\n   cols: 5\n   dt: d\n   data: [ 0., 0., 0., 0., 0. ]\n";
  test::write_text(dir / "cam.yaml", base + "depth_unit_mm: 1.\nimage_width: 640\nimage_height: 480\n");
  const StreamInfo c = read_calibration(dir / "cam.yaml", Sensor::depth);
  EXPECT_EQ(c.width, 640);
  EXPECT_DOUBLE_EQ(c.camera_matrix(0, 2), 319.5);
  test::write_text(dir / "nounit.yaml", base);
  test::expect_invalid_input([&] { read_calibration(dir / "nounit.yaml", Sensor::depth); },
                             {"nounit.yaml", "depth_unit_mm"});
  test::write_text(dir / "laser.yaml", base + "depth_unit_mm: 0.01\nwidth: 512\n");
  test::expect_invalid_input([&] { read_calibration(dir / "laser.yaml", Sensor::laser); }, {"profile_step_mm"});
  test::expect_invalid_input([&] { read_calibration(dir / "none.yaml", Sensor::depth); }, {"none.yaml"});
}

TEST(DropMonitor, WarnsOnceAboveFivePercentInAWindow) {
  DropMonitor m(30, 0.05);
  const auto t0 = std::chrono::steady_clock::now();
  int warnings = 0;
  for (int i = 0; i < 100; ++i) warnings += m.count(i % 25 == 24, t0).has_value();  // 4%, evenly
  EXPECT_EQ(warnings, 0);
  for (int i = 0; i < 100; ++i) warnings += m.count(i % 5 == 0, t0).has_value();  // now 12% of 200
  EXPECT_EQ(warnings, 1);
  // A new window starts afresh.
  EXPECT_FALSE(m.count(false, t0 + std::chrono::seconds(31)));
}

}  // namespace
}  // namespace s2c
