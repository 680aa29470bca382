#pragma once
/// \file An emulated Z16 depth camera behind V4L2 ioctls (umockdev), for the device tests and the
/// acquire benchmark. It streams given frames at a given rate, as a driver would: frames fill the
/// buffers the client queued, a frame with no queued buffer is dropped (its sequence number
/// skipped). The device node is a regular file, so the client's mmap works; frames are written
/// into it at the buffers' page-aligned offsets. poll() is not emulated (always ready), which
/// the source's loop must tolerate.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "s2c/core/stream.h"

namespace s2c::emulation {

struct MockCameraOptions {
  int width = 640, height = 480;
  std::vector<std::uint32_t> formats;   ///< fourccs offered; empty = {Z16}
  double fps = 30;
  std::vector<DepthImage> frames;       ///< streamed in turn (cycled); empty = a synthetic ramp
};

class MockCamera {
 public:
  explicit MockCamera(MockCameraOptions options);
  ~MockCamera();
  MockCamera(const MockCamera&) = delete;
  MockCamera& operator=(const MockCamera&) = delete;

  std::string device() const { return "/dev/video0"; }
  /// From now on every ioctl fails with ENODEV, as after the cable was pulled.
  void unplug();
  /// The next `n` frames arrive with half their bytes (bytesused short).
  void short_frames(int n);
  /// The next `n` frames carry V4L2_BUF_FLAG_ERROR.
  void error_frames(int n);
  std::uint64_t frames_delivered() const;   ///< handed to the client by DQBUF
  std::uint64_t frames_dropped() const;     ///< due while no buffer was queued

  struct State;

 private:
  std::unique_ptr<State> state_;
};

}  // namespace s2c::emulation
