// s2c-bench-acquire: the acquire targets of issue 7 (bench/README.md "Acquire").
//   replay  — 640×480 depth replay rate (decode only, and decode + record), on a stream of real
//             TUM frames and on the bundled plate scan
//   live    — the V4L2 loop against the emulated Z16 camera at 30 fps: loop overhead per frame,
//             dropped frames; and the same camera unthrottled (throughput)
//   usb     — the USB laser loop against the emulated scanner: profiles/s, lost profiles
// Prints one JSON document (--json FILE also writes it).
#include <sys/resource.h>

#include <filesystem>

#include <CLI/CLI.hpp>
#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "mock_camera.h"
#include "mock_laser.h"
#include "s2c/acquire/acquire.h"
#include "s2c/acquire/sources.h"
#include "s2c/core/cli.h"
#include "s2c/core/clock.h"
#include "s2c/core/files.h"

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

double cpu_seconds() {
  rusage u{};
  getrusage(RUSAGE_SELF, &u);
  return u.ru_utime.tv_sec + u.ru_utime.tv_usec * 1e-6 + u.ru_stime.tv_sec + u.ru_stime.tv_usec * 1e-6;
}

s2c::StreamInfo tum_calibration() {
  s2c::StreamInfo c;
  c.width = 640;
  c.height = 480;
  c.depth_unit_mm = 0.2;
  c.camera_matrix << 525, 0, 319.5, 0, 525, 239.5, 0, 0, 1;
  c.device = "bench";
  return c;
}

/// A stream of `n` copies of the real TUM frame, each with a different noise-free shift so the
/// PNGs are not identical.
fs::path make_tum_stream(const fs::path& dir, const fs::path& tum_png, int n) {
  const s2c::DepthImage tum = s2c::read_depth_png(tum_png);
  s2c::StreamWriter w(dir, tum_calibration());
  for (int i = 0; i < n; ++i) {
    s2c::DepthImage f = tum;
    std::rotate(f.data.begin(), f.data.begin() + i % 640, f.data.end());
    w.add_frame(i / 30.0, f, std::nullopt);
  }
  w.finish();
  return dir;
}

/// acquire() into `out` (emptied first), with its CPU time in seconds; a failed capture is an error.
std::pair<s2c::AcquireResult, double> timed_acquire(s2c::FrameSource& src, const fs::path& out, std::uint64_t frames) {
  s2c::AcquireOptions ao;
  ao.frames = frames;
  fs::remove_all(out);
  const double cpu0 = cpu_seconds();
  s2c::AcquireResult res = s2c::acquire(src, out, ao);
  const double cpu = cpu_seconds() - cpu0;
  if (res.failure) throw s2c::ProcessingError(*res.failure);
  return {std::move(res), cpu};
}

json bench_replay(const fs::path& stream, const fs::path& work) {
  json r;
  {  // decode only: what replay feeds to a consumer
    auto src = s2c::make_replay_source({stream, false});
    src->open();
    src->start();
    const auto t0 = std::chrono::steady_clock::now();
    std::size_t n = 0;
    while (src->next(std::chrono::steady_clock::now() + std::chrono::seconds(5))) ++n;
    const double s = s2c::seconds_since(t0);
    r["frames"] = n;
    r["decode_fps"] = n / s;
  }
  {  // replay → recorder (PNG encode, fdatasync per frame)
    fs::remove_all(work / "copy");
    auto src = s2c::make_replay_source({stream, false});
    const auto res = s2c::acquire(*src, work / "copy", {});
    r["replay_record_fps"] = res.record.kept / res.seconds;
    r["kept"] = res.record.kept;
    r["dropped_disk_behind"] = res.record.dropped_queue;
  }
  return r;
}

json bench_live(double fps, int frames, const fs::path& tum_png, const fs::path& work) {
  s2c::emulation::MockCameraOptions mo;
  mo.fps = fps;
  mo.frames = {s2c::read_depth_png(tum_png)};
  s2c::emulation::MockCamera cam(mo);
  s2c::V4l2Options vo;
  vo.device = cam.device();
  vo.calibration = tum_calibration();
  auto src = s2c::make_v4l2_source(vo);
  const auto [res, cpu] = timed_acquire(*src, work / "live", static_cast<std::uint64_t>(frames));
  const auto& st = res.source;
  return {{"fps_requested", fps},
          {"frames", res.record.kept},
          {"seconds", res.seconds},
          {"fps_achieved", res.record.kept / res.seconds},
          {"loop_ms_per_frame", 1e3 * st.busy_seconds / std::max<std::uint64_t>(1, st.frames)},
          {"device_call_ms_per_frame", 1e3 * st.device_call_seconds / std::max<std::uint64_t>(1, st.frames)},
          {"own_ms_per_frame", 1e3 * (st.busy_seconds - st.device_call_seconds) / std::max<std::uint64_t>(1, st.frames)},
          {"cpu_ms_per_frame", 1e3 * cpu / std::max<std::uint64_t>(1, res.record.kept)},
          {"dropped_by_device", cam.frames_dropped()},
          {"sequence_gaps", st.sequence_gaps},
          {"dropped_short_or_bad", st.dropped_short + st.dropped_error},
          {"dropped_disk_behind", res.record.dropped_queue}};
}

json bench_usb(double rate_hz, int sweeps, int rows, const fs::path& work) {
  s2c::emulation::MockLaserOptions mo;
  mo.rate_hz = rate_hz;
  s2c::emulation::MockLaser laser(mo);
  s2c::UsbLaserOptions o;
  o.vendor = mo.vendor;
  o.product = mo.product;
  o.calibration.sensor = s2c::Sensor::laser;
  o.calibration.width = 512;
  o.calibration.depth_unit_mm = 0.01;
  o.calibration.camera_matrix << 1000, 0, 255.5, 0, 1000, 0, 0, 0, 1;
  o.calibration.profile_step_mm = 0.1;
  o.profiles_per_sweep = rows;
  auto src = s2c::make_usb_laser_source(o);
  const auto [res, cpu] = timed_acquire(*src, work / "usb", static_cast<std::uint64_t>(sweeps));
  const double profiles = static_cast<double>(sweeps) * rows;
  return {{"rate_requested_hz", rate_hz},
          {"sweeps", res.record.kept},
          {"profiles_per_second", profiles / res.seconds},
          {"lost_profiles", res.source.sequence_gaps},
          {"dropped_short_or_bad", res.source.dropped_short + res.source.dropped_error},
          {"cpu_us_per_profile", 1e6 * cpu / profiles}};
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"Acquire benchmarks (issue 7): replay rate, live loop overhead and drops under emulation.",
               "s2c-bench-acquire"};
  std::string what = "all", json_out, work = "/tmp/s2c-bench-acquire";
  std::string tum = std::string(S2C_SOURCE_DIR) + "/../shared/data/real/rgbd/tum_single/TUM_depth.png";
  std::string plate = std::string(S2C_SOURCE_DIR) + "/fixtures/scans/plate";
  int frames = 300;
  app.add_option("WHAT", what, "replay | live | usb | all")->check(CLI::IsMember({"replay", "live", "usb", "all"}));
  app.add_option("--frames", frames, "Frames per measurement")->capture_default_str();
  app.add_option("--work", work, "Scratch folder")->capture_default_str();
  app.add_option("--json", json_out, "Also write the results here");
  CLI11_PARSE(app, argc, argv);
  return s2c::run_guarded([&] {
    fs::create_directories(work);
    json out = {{"frames", frames}};
    if (what == "replay" || what == "all") {
      const fs::path tum_stream = make_tum_stream(fs::path(work) / "tum_stream", tum, frames);
      out["replay_tum_640x480"] = bench_replay(tum_stream, work);
      out["replay_plate_fixture"] = bench_replay(plate, work);
    }
    if (what == "live" || what == "all") {
      out["live_v4l2_30fps"] = bench_live(30, frames, tum, work);
      out["live_v4l2_unthrottled"] = bench_live(1000, frames, tum, work);
    }
    if (what == "usb" || what == "all") out["usb_laser_2kHz"] = bench_usb(2000, 10, 200, work);
    const std::string text = out.dump(2);
    fmt::print("{}\n", text);
    if (!json_out.empty()) s2c::write_file_atomic(json_out, text + "\n");
  });
}
