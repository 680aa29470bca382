#pragma once
// Shared by the device tests: calibrations and stream comparison.
#include <fcntl.h>
#include <unistd.h>

#include <gtest/gtest.h>

#include "mock_camera.h"

#include "s2c/core/stream.h"
#include "test_util.h"

namespace s2c::test {

inline StreamInfo depth_calibration(int w = 640, int h = 480) {
  StreamInfo c;
  c.sensor = Sensor::depth;
  c.width = w;
  c.height = h;
  c.depth_unit_mm = 0.2;  // TUM: 5000 counts per metre
  c.camera_matrix << 525, 0, 319.5, 0, 525, 239.5, 0, 0, 1;
  return c;
}

inline StreamInfo laser_calibration(int columns = 512) {
  StreamInfo c;
  c.sensor = Sensor::laser;
  c.width = columns;
  c.depth_unit_mm = 0.01;
  c.camera_matrix << 1000, 0, 255.5, 0, 1000, 0, 0, 0, 1;
  c.profile_step_mm = 0.1;
  return c;
}

/// A real 640×480 depth frame (TUM RGB-D, 16-bit PNG) from ../shared/data/real.
inline DepthImage real_tum_frame() { return read_depth_png(shared_dir() / "data/real/rgbd/tum_single/TUM_depth.png"); }

/// Whether umockdev's preload library intercepts this process's device calls (it must be linked
/// first; see acquire/CMakeLists.txt). Without it, the device tests skip rather than fail.
inline bool emulation_works() {
  static const bool works = [] {
    emulation::MockCamera cam({});
    const int fd = ::open(cam.device().c_str(), O_RDWR | O_NONBLOCK);
    if (fd < 0) return false;
    ::close(fd);
    return true;
  }();
  return works;
}

/// Base of the emulated-device tests: skips (GTEST_SKIP, ctest reports it) without umockdev.
class EmulatedDevice : public ::testing::Test {
 protected:
  void SetUp() override {
    if (!emulation_works()) GTEST_SKIP() << "umockdev's preload is not active in this process: no device emulation";
  }
};

}  // namespace s2c::test
