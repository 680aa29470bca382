#pragma once
/// \file Writes a stream directory (DESIGN.md) as frames arrive, so that whatever happens —
/// unplug, disk full, Ctrl-C, a crash — every frame listed in depth.txt is complete on disk.
#include <condition_variable>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <mutex>
#include <optional>
#include <string>
#include <thread>

#include "s2c/acquire/frame_source.h"

namespace s2c {

struct RecorderOptions {
  std::size_t queue_frames = 64;   ///< frames waiting for the disk before new ones are dropped
  bool wait_when_full = false;     ///< block add() instead of dropping (sources that can wait: replay)
  bool sync_each_frame = true;     ///< fdatasync each PNG before its index line is written
  /// Opens a frame file for writing (O_WRONLY|O_CREAT|O_TRUNC); tests inject /dev/full here.
  std::function<int(const std::filesystem::path&)> open_frame_file;
};

struct RecordSummary {
  std::uint64_t kept = 0;          ///< frames listed in depth.txt, complete on disk
  std::uint64_t dropped_queue = 0; ///< frames dropped because the disk fell behind
  std::optional<std::string> write_error;  ///< why recording stopped early (e.g. "No space left on device")
};

/// Records into `dir`, which must not exist or be empty (a recording never overwrites).
/// stream.yaml is written first, then each frame as depth/NNNNNN.png; its "timestamp file"
/// line is appended to depth.txt only after the PNG is written (and synced). A writer thread
/// does the disk work so that capture never waits for it.
class Recorder {
 public:
  Recorder(std::filesystem::path dir, const StreamInfo& info, RecorderOptions options = {});
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// Queues a frame; false when it was dropped (queue full) or recording has stopped on an error.
  bool add(Frame frame);
  /// Writes what is queued, syncs depth.txt and the directory, and says what was kept.
  RecordSummary finish();
  /// Frames on disk so far.
  std::uint64_t kept() const;
  /// Set once a write failed; add() then refuses frames.
  bool failed() const;

 private:
  void writer_loop();
  void write_frame(const Frame& f);

  std::filesystem::path dir_;
  StreamInfo info_;
  RecorderOptions options_;
  int index_fd_ = -1, poses_fd_ = -1;
  std::uint64_t index_bytes_ = 0, poses_bytes_ = 0;
  mutable std::mutex mutex_;
  std::condition_variable cv_;
  std::deque<Frame> queue_;
  bool closing_ = false, finished_ = false;
  RecordSummary summary_;
  std::thread writer_;
};

}  // namespace s2c
