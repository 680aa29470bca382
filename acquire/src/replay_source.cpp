// Replay: a recorded stream fed through the same decoding as a live one (PNG → raw counts),
// as fast as possible or at the recorded timing.
#include <atomic>
#include <deque>
#include <future>
#include <thread>

#include <fmt/format.h>

#include "s2c/acquire/sources.h"

namespace s2c {
namespace {

class ReplaySource final : public FrameSource {
 public:
  explicit ReplaySource(ReplayOptions o) : o_(std::move(o)) {}

  std::string name() const override { return "replay:" + o_.dir.string(); }
  const StreamInfo& info() const override { return stream_.info; }
  SourceStats stats() const override { return stats_; }

  void open() override { stream_ = read_stream(o_.dir); }
  void start() override { started_ = std::chrono::steady_clock::now(); }

  std::optional<Frame> next(SteadyTime deadline) override {
    if (stopping_ || next_ >= stream_.frames.size()) return std::nullopt;
    const double t = stream_.frames[next_].timestamp;
    if (o_.realtime) {
      const double since_first = t - stream_.frames.front().timestamp;
      const auto due = started_ + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                                      std::chrono::duration<double>(std::max(0.0, since_first)));
      if (due > deadline)
        throw DeviceFailure(DeviceFault::timeout, fmt::format("{}: frame {} is due after the deadline", name(), next_));
      std::this_thread::sleep_until(due);
    }
    const auto busy_start = std::chrono::steady_clock::now();
    Frame f;
    f.sequence = next_;
    f.timestamp = t;
    // Frames are read ahead, two at a time, so both cores decode PNGs while the caller works.
    while (ahead_.size() < kReadAhead && next_ + ahead_.size() < stream_.frames.size())
      ahead_.push_back(std::async(std::launch::async, [this, i = next_ + ahead_.size()] { return read_frame(stream_, i); }));
    f.image = ahead_.front().get();  // InvalidInput naming the file if it is corrupt
    ahead_.pop_front();
    f.pose = stream_.pose_of(next_);
    ++next_;
    ++stats_.frames;
    stats_.busy_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - busy_start).count();
    return f;
  }

  void stop() override { stopping_ = true; }
  bool live() const override { return false; }

 private:
  ReplayOptions o_;
  Stream stream_;
  std::size_t next_ = 0;
  static constexpr std::size_t kReadAhead = 2;
  std::deque<std::future<DepthImage>> ahead_;
  SteadyTime started_{};
  std::atomic<bool> stopping_{false};
  SourceStats stats_;
};

}  // namespace

std::unique_ptr<FrameSource> make_replay_source(const ReplayOptions& options) {
  return std::make_unique<ReplaySource>(options);
}

}  // namespace s2c
