#include "s2c/core/progress.h"

#include <unistd.h>

#include <cstdio>

#include "s2c/core/clock.h"

namespace s2c {
namespace {
std::atomic<bool> g_enabled{true};
}

void Progress::set_enabled(bool enabled) { g_enabled = enabled; }

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)), total_(total), start_(std::chrono::steady_clock::now()), last_draw_(start_) {
  active_ = g_enabled && ::isatty(STDERR_FILENO) && total_ > 0;
}

Progress::~Progress() { finish(); }

void Progress::advance(std::size_t n) {
  done_ += n;
  if (!active_) return;
  const auto now = std::chrono::steady_clock::now();
  std::lock_guard<std::mutex> lock(mutex_);
  if (now - last_draw_ < std::chrono::milliseconds(100)) return;
  last_draw_ = now;
  draw(false);
}

void Progress::finish() {
  if (!active_ || finished_) return;
  std::lock_guard<std::mutex> lock(mutex_);
  finished_ = true;
  draw(true);
}

void Progress::draw(bool final) {
  const std::size_t d = std::min(done_.load(), total_);
  const double frac = static_cast<double>(d) / static_cast<double>(total_);
  const int width = 30, filled = static_cast<int>(frac * width);
  const double secs = seconds_since(start_);
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.resize(width, '.');
  std::fprintf(stderr, "\r  %-12s [%s] %zu/%zu %5.1fs%s", label_.c_str(), bar.c_str(), d, total_, secs, final ? "\n" : "");
  std::fflush(stderr);
}

}  // namespace s2c
