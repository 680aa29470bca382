#pragma once
/// \file The frame sources behind FrameSource and how `--from` names them.
#include <filesystem>
#include <memory>
#include <string>

#include "s2c/acquire/frame_source.h"

namespace s2c {

struct V4l2Options {
  std::string device = "/dev/video0";
  StreamInfo calibration;          ///< camera matrix, distortion, depth unit (never from V4L2)
  int width = 0, height = 0;       ///< requested size; 0 = the calibration's, else the device's current
  double fps = 0;                  ///< requested rate; 0 = the device's current
  int buffers = 4;                 ///< mmap buffers (REQBUFS)
};

struct UsbLaserOptions {
  std::uint16_t vendor = 0, product = 0;
  StreamInfo calibration;          ///< fan (fx, cx), columns (width), depth unit, profile step
  int profiles_per_sweep = 0;      ///< rows per recorded sweep (or the device's end-of-sweep flag)
  int transfers = 8;               ///< bulk transfers in flight (4–8)
  std::size_t max_points = 4096;   ///< largest profile the device sends (sizes the transfers)
  std::uint8_t endpoint = 0x81;    ///< bulk IN endpoint of the profiles
  int interface = 0;
};

struct ReplayOptions {
  std::filesystem::path dir;
  bool realtime = false;           ///< wait the recorded time between frames
};

std::unique_ptr<FrameSource> make_v4l2_source(const V4l2Options& options);
std::unique_ptr<FrameSource> make_usb_laser_source(const UsbLaserOptions& options);
std::unique_ptr<FrameSource> make_replay_source(const ReplayOptions& options);

/// `--from` parsed: "v4l2:/dev/videoN", "usb:VID:PID" (hex), "replay:DIR".
struct SourceSpec {
  enum class Kind { v4l2, usb, replay } kind = Kind::replay;
  std::string path;                ///< device node or stream directory
  std::uint16_t vendor = 0, product = 0;
};
/// \throw InvalidInput naming the accepted forms.
SourceSpec parse_source_spec(const std::string& text);

}  // namespace s2c
