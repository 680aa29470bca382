#pragma once
/// \file The capture loop of `scan2cad acquire`: frames from a source into a recorder, with the
/// failure handling a technician needs (what happened, how many frames were kept).
#include <cstdint>
#include <filesystem>
#include <functional>
#include <optional>
#include <string>

#include "s2c/acquire/frame_source.h"
#include "s2c/acquire/recorder.h"

namespace s2c {

struct AcquireOptions {
  std::uint64_t frames = 0;        ///< stop after this many (0: until the source ends or stop())
  double timeout_s = 5;            ///< no frame for this long = DeviceFailure{timeout}
  double duration_s = 0;           ///< stop after this long (0: no limit)
  RecorderOptions recorder;
  std::function<void(std::uint64_t)> on_frame;  ///< progress
};

struct AcquireResult {
  RecordSummary record;
  SourceStats source;
  double seconds = 0;
  /// Why capture ended early (vanished, timeout, disk full), with the frames kept; empty if it
  /// ended as asked.
  std::optional<std::string> failure;
  int exit_code = 0;               ///< 0, or kExitDevice for a failure above
};

/// Opens and starts `source`, records into `out` until done, stops and finalizes. A device that
/// vanishes or times out and a disk that fills up keep every complete frame (a valid stream) and
/// are reported in `failure`. A corrupt replay frame removes the partial recording and throws
/// InvalidInput naming the file. `stop`, set from another thread, ends capture cleanly.
AcquireResult acquire(FrameSource& source, const std::filesystem::path& out, const AcquireOptions& options);

}  // namespace s2c
