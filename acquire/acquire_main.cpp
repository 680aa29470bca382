// scan2cad-acquire: record a stream from a V4L2 depth camera, a USB laser line scanner or a replay.
#include <pthread.h>
#include <signal.h>

#include <atomic>
#include <thread>

#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "s2c/acquire/acquire.h"
#include "s2c/acquire/sources.h"
#include "s2c/core/cli.h"
#include "s2c/core/progress.h"
#include "s2c/core/report.h"

namespace {

/// Turns SIGINT/SIGTERM into source.stop() from an ordinary thread (sigwait), so Ctrl-C ends a
/// recording cleanly: the frames so far are kept and the stream is finalized.
class StopOnSignal {
 public:
  explicit StopOnSignal(s2c::FrameSource& source) : source_(source) {
    sigemptyset(&set_);
    sigaddset(&set_, SIGINT);
    sigaddset(&set_, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set_, nullptr);  // before any other thread starts: they inherit it
    thread_ = std::thread([this] {
      const timespec tick{0, 200'000'000};
      while (!done_) {
        if (sigtimedwait(&set_, nullptr, &tick) > 0) {
          spdlog::info("interrupted: finishing the recording");
          source_.stop();
        }
      }
    });
  }
  ~StopOnSignal() {
    done_ = true;
    thread_.join();
  }

 private:
  s2c::FrameSource& source_;
  sigset_t set_;
  std::atomic<bool> done_{false};
  std::thread thread_;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "Record a stream directory (docs/formats.md) from a live sensor or a recorded stream.\n"
      "  --from v4l2:/dev/videoN   a depth camera streaming Z16/Y16 (needs --calibration)\n"
      "  --from usb:VID:PID        a laser line scanner speaking the S2CL profile protocol (needs --calibration)\n"
      "  --from replay:STREAM      a recorded stream, through the same decoding (--realtime for recorded timing)\n"
      "Frames are on disk as they arrive; an unplugged device, a full disk or Ctrl-C keep every complete\n"
      "frame as a valid stream. Exit codes: 0 ok, 2 bad input or usage, 4 device or disk failure.\n"
      "Example: scan2cad acquire --from v4l2:/dev/video2 --calibration cam.yaml --out scans/part --frames 300",
      "scan2cad-acquire"};
  s2c::CommonOptions common;
  std::string from, out, calibration;
  s2c::AcquireOptions o;
  bool realtime = false;
  s2c::V4l2Options v4l2;
  s2c::UsbLaserOptions usb;
  usb.profiles_per_sweep = 500;
  app.add_option("--from", from, "Source: v4l2:/dev/videoN | usb:VID:PID | replay:STREAM_DIR")->required();
  app.add_option("--out", out, "Stream directory to record into (must not exist or be empty)")->required();
  app.add_option("--frames", o.frames, "Stop after N frames (laser: sweeps); 0 = until the source ends or Ctrl-C")
      ->capture_default_str();
  app.add_option("--duration", o.duration_s, "Stop after this many seconds (0 = no limit)")->capture_default_str();
  app.add_option("--calibration", calibration,
                 "OpenCV YAML with camera_matrix, dist_coeffs, depth_unit_mm (laser: also width, profile_step_mm); "
                 "required for live devices: V4L2 reports neither depth scale nor intrinsics");
  app.add_option("--timeout", o.timeout_s, "Give up when no frame arrives for this many seconds")->capture_default_str();
  app.add_flag("--realtime", realtime, "Replay at the recorded timing instead of as fast as possible");
  app.add_option("--width", v4l2.width, "V4L2: frame width to request (default: the calibration's or the device's)");
  app.add_option("--height", v4l2.height, "V4L2: frame height to request");
  app.add_option("--fps", v4l2.fps, "V4L2: frame rate to request (default: the device's)");
  app.add_option("--profiles-per-sweep", usb.profiles_per_sweep,
                 "Laser: profiles (rows) per recorded sweep; the device's end-of-sweep flag also ends one")
      ->capture_default_str();
  app.add_option("--transfers", usb.transfers, "Laser: USB bulk transfers in flight (4-8)")->capture_default_str();
  s2c::add_common_options(app, common);
  if (int rc = s2c::parse_command_line(app, argc, argv); rc >= 0) return rc;
  s2c::init_logging("scan2cad-acquire", common);

  return s2c::run_guarded([&]() {
    s2c::Report report("scan2cad-acquire");
    const s2c::SourceSpec spec = s2c::parse_source_spec(from);
    std::unique_ptr<s2c::FrameSource> source;
    if (spec.kind == s2c::SourceSpec::Kind::replay) {
      source = s2c::make_replay_source({spec.path, realtime});
    } else {
      if (calibration.empty())
        throw s2c::InvalidInput(fmt::format("--from {}: live capture needs --calibration FILE (depth scale and "
                                            "intrinsics never come from the device; see docs/acquire.md)", from));
      if (spec.kind == s2c::SourceSpec::Kind::v4l2) {
        v4l2.device = spec.path;
        v4l2.calibration = s2c::read_calibration(calibration, s2c::Sensor::depth);
        source = s2c::make_v4l2_source(v4l2);
      } else {
        usb.vendor = spec.vendor;
        usb.product = spec.product;
        usb.calibration = s2c::read_calibration(calibration, s2c::Sensor::laser);
        source = s2c::make_usb_laser_source(usb);
      }
    }
    StopOnSignal stop_on_signal(*source);
    s2c::Progress progress("frames", o.frames);
    o.on_frame = [&](std::uint64_t) { progress.advance(); };
    const s2c::AcquireResult r = s2c::acquire(*source, out, o);
    progress.finish();
    const auto& st = r.source;
    report.parameters() = {{"from", from}, {"out", out}, {"frames", o.frames}, {"timeout_s", o.timeout_s},
                           {"realtime", realtime}};
    report.counts() = {{"frames_kept", r.record.kept}, {"frames_received", st.frames},
                       {"dropped_short", st.dropped_short}, {"dropped_error", st.dropped_error},
                       {"dropped_disk_behind", r.record.dropped_queue}, {"sequence_gaps", st.sequence_gaps},
                       {"stalls_cleared", st.stalls}};
    report.add_time("capture", r.seconds);
    report.json()["frames_per_second"] = r.seconds > 0 ? st.frames / r.seconds : 0.0;
    report.json()["loop_ms_per_frame"] = st.frames ? 1e3 * st.busy_seconds / st.frames : 0.0;
    report.json()["device_call_ms_per_frame"] = st.frames ? 1e3 * st.device_call_seconds / st.frames : 0.0;
    if (r.failure) report.json()["failure"] = *r.failure;
    report.write(common.report);
    if (r.failure) throw s2c::DeviceError(*r.failure);
    spdlog::info("{} frames from {} → {} ({:.1f} frames/s; dropped: {} short, {} flagged bad, {} sequence gaps)",
                 r.record.kept, source->name(), out, r.seconds > 0 ? st.frames / r.seconds : 0.0, st.dropped_short,
                 st.dropped_error, st.sequence_gaps);
  });
}
