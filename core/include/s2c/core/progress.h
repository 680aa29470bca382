#pragma once
/// \file A progress bar on stderr for long work; silent when stderr is not a terminal.
#include <atomic>
#include <chrono>
#include <cstddef>
#include <mutex>
#include <string>

namespace s2c {

class Progress {
 public:
  /// `total` units of work; `label` says what they are ("views", "faces").
  Progress(std::string label, std::size_t total);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;

  /// Thread-safe; redraws at most ten times a second.
  void advance(std::size_t n = 1);
  void finish();

  /// Disables every bar of the process (--quiet, tests).
  static void set_enabled(bool enabled);

 private:
  void draw(bool final);
  std::string label_;
  std::size_t total_;
  std::atomic<std::size_t> done_{0};
  std::mutex mutex_;
  std::chrono::steady_clock::time_point start_, last_draw_;
  bool active_ = false, finished_ = false;
};

}  // namespace s2c
