#pragma once
/// \file Wall-clock timing of steps, for reports and benchmarks.
#include <chrono>

namespace s2c {

/// Seconds elapsed since `start` on the steady clock.
inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace s2c
