#include "s2c/acquire/acquire.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "s2c/core/clock.h"

namespace fs = std::filesystem;

namespace s2c {

AcquireResult acquire(FrameSource& source, const fs::path& out, const AcquireOptions& options) {
  source.open();
  AcquireResult result;
  std::optional<Recorder> recorder;
  RecorderOptions ro = options.recorder;
  ro.wait_when_full = ro.wait_when_full || !source.live();
  recorder.emplace(out, source.info(), ro);
  const auto start = std::chrono::steady_clock::now();
  auto timeout = std::chrono::duration_cast<std::chrono::steady_clock::duration>(
      std::chrono::duration<double>(options.timeout_s));
  try {
    source.start();
    std::uint64_t n = 0, behind = 0;
    while (options.frames == 0 || n < options.frames) {
      if (options.duration_s > 0 && seconds_since(start) >= options.duration_s) break;
      std::optional<Frame> f = source.next(std::chrono::steady_clock::now() + timeout);
      if (!f) break;
      if (!recorder->add(std::move(*f))) {
        if (recorder->failed()) break;
        if (++behind == 1 || behind % 100 == 0)
          spdlog::warn("{}: the disk falls behind; {} frame(s) dropped so far (a faster disk, or fewer fps)",
                       out.string(), behind);
      }
      ++n;
      if (options.on_frame) options.on_frame(n);
    }
  } catch (const DeviceFailure& e) {
    result.failure = e.what();
    result.exit_code = kExitDevice;
  } catch (const InvalidInput&) {
    // A corrupt replay: bad input leaves no partial output.
    source.stop();
    recorder.reset();
    std::error_code ec;
    fs::remove_all(out, ec);
    throw;
  }
  source.stop();
  result.seconds = seconds_since(start);
  result.record = recorder->finish();
  result.source = source.stats();
  if (result.record.write_error) {
    result.failure = fmt::format("{}: writing stopped: {}", out.string(), *result.record.write_error);
    result.exit_code = kExitDevice;
  }
  if (result.failure)
    *result.failure += fmt::format("; {} complete frame{} kept in {} (a valid stream)", result.record.kept,
                                   result.record.kept == 1 ? "" : "s", out.string());
  return result;
}

}  // namespace s2c
