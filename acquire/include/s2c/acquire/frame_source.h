#pragma once
/// \file One interface for every source of frames: a V4L2 depth camera, a USB laser line
/// scanner, a recorded stream. The recorder and `scan2cad acquire` see only this.
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include "s2c/core/errors.h"
#include "s2c/core/stream.h"

namespace s2c {

using SteadyTime = std::chrono::steady_clock::time_point;

/// One frame as the stream stores it: a depth image, or a laser sweep (one profile per row).
struct Frame {
  std::uint64_t sequence = 0;  ///< the device's counter (gaps mean lost frames)
  double timestamp = 0;        ///< seconds, device clock where it has one
  DepthImage image;            ///< raw counts, never rescaled
  std::optional<Eigen::Isometry3d> pose;  ///< camera-to-world (mm), when known (replay, turntable)
};

/// What went wrong with a device, so that the message can say what to do.
enum class DeviceFault { vanished, wrong_format, timeout, busy, not_found, io };

/// A capture device failed. Exit code 4 (DeviceError).
struct DeviceFailure : DeviceError {
  DeviceFailure(DeviceFault f, const std::string& what) : DeviceError(what), fault(f) {}
  DeviceFault fault;
};

/// Counters every source keeps; `scan2cad acquire --report` prints them.
struct SourceStats {
  std::uint64_t frames = 0;          ///< delivered by next()
  std::uint64_t dropped_short = 0;   ///< fewer bytes than the format needs
  std::uint64_t dropped_error = 0;   ///< flagged bad by the device (V4L2_BUF_FLAG_ERROR, bad packet)
  std::uint64_t sequence_gaps = 0;   ///< frames (profiles) the device numbered but never delivered
  std::uint64_t stalls = 0;          ///< USB endpoint halts cleared
  double busy_seconds = 0;           ///< time spent inside next() handling frames (not waiting for them)
  double device_call_seconds = 0;    ///< of which inside the device's calls (V4L2 DQBUF/QBUF ioctls)
};

/// The life of a source: open() (find the device, negotiate), start() (stream), next() until it
/// returns nothing, stop() (idempotent; also from another thread, to interrupt a next()).
class FrameSource {
 public:
  virtual ~FrameSource() = default;
  virtual void open() = 0;
  virtual void start() = 0;
  /// The next frame, waiting at most until `deadline`. std::nullopt when the source is exhausted
  /// (replay at its end) or stopped. \throw DeviceFailure{timeout} when the deadline passes,
  /// DeviceFailure{vanished} when the device is unplugged, InvalidInput for a corrupt replay.
  virtual std::optional<Frame> next(SteadyTime deadline) = 0;
  /// Stops streaming; safe to call from another thread or more than once.
  virtual void stop() = 0;
  /// What the stream.yaml of a recording says (valid after open()).
  virtual const StreamInfo& info() const = 0;
  virtual SourceStats stats() const = 0;
  /// "v4l2:/dev/video0", "usb:1209:0001", "replay:DIR".
  virtual std::string name() const = 0;
  /// A live device cannot wait for the disk (its frames would be lost in the driver instead);
  /// a replay can, so the recorder applies back-pressure to it rather than drop frames.
  virtual bool live() const { return true; }
};

/// Warns when more than 5% of the frames of the last 30 s were dropped (once per window).
class DropMonitor {
 public:
  explicit DropMonitor(double window_s = 30, double threshold = 0.05) : window_s_(window_s), threshold_(threshold) {}
  /// Counts one frame, dropped or not; returns the warning text when the threshold is crossed.
  std::optional<std::string> count(bool dropped, SteadyTime now);

 private:
  double window_s_, threshold_;
  SteadyTime window_start_{};
  std::uint64_t seen_ = 0, dropped_ = 0;
  bool started_ = false, warned_ = false;
};

}  // namespace s2c
