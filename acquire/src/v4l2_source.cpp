// V4L2 depth camera: raw ioctls, mmap streaming with 4 buffers, poll with a stop fd.
#include <fcntl.h>
#include <linux/videodev2.h>
#include <poll.h>
#include <sys/eventfd.h>
#include <sys/ioctl.h>
#include <sys/mman.h>
#include <unistd.h>

#include <atomic>
#include <cerrno>
#include <cstring>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "s2c/acquire/decode.h"
#include "s2c/acquire/sources.h"

namespace s2c {
namespace {

using namespace std::chrono_literals;

int xioctl(int fd, unsigned long request, void* arg) {
  int r;
  do r = ::ioctl(fd, request, arg);
  while (r == -1 && errno == EINTR);
  return r;
}

std::string fourcc_text(std::uint32_t f) {
  std::string s;
  for (int i = 0; i < 4; ++i) s += static_cast<char>((f >> (8 * i)) & 0xff);
  while (!s.empty() && s.back() == ' ') s.pop_back();
  return s;
}

bool is_depth_format(std::uint32_t f) { return f == V4L2_PIX_FMT_Z16 || f == V4L2_PIX_FMT_Y16; }

/// The device's unplug errors: the node is gone (ENODEV) or the transfer failed for good (EIO).
bool unplugged(int err) { return err == ENODEV || err == EIO || err == ENXIO; }

class V4l2Source final : public FrameSource {
 public:
  explicit V4l2Source(V4l2Options o) : o_(std::move(o)) {
    info_ = o_.calibration;
    info_.sensor = Sensor::depth;
    info_.device = name();
  }
  ~V4l2Source() override { close_device(); }

  std::string name() const override { return "v4l2:" + o_.device; }
  const StreamInfo& info() const override { return info_; }
  SourceStats stats() const override { return stats_; }

  void open() override {
    fd_ = ::open(o_.device.c_str(), O_RDWR | O_NONBLOCK | O_CLOEXEC);
    if (fd_ < 0) {
      const int e = errno;
      if (e == ENOENT || e == ENODEV || e == ENXIO)
        throw DeviceFailure(DeviceFault::not_found, fmt::format("{}: no such device; is the camera plugged in? "
                                                                "`v4l2-ctl --list-devices` lists the cameras", o_.device));
      if (e == EBUSY)
        throw DeviceFailure(DeviceFault::busy, fmt::format("{}: device is busy; close the other program using the camera "
                                                           "(`fuser {}` names it)", o_.device, o_.device));
      if (e == EACCES || e == EPERM)
        throw DeviceFailure(DeviceFault::io, fmt::format("{}: permission denied; add your user to the 'video' group",
                                                         o_.device));
      throw DeviceFailure(DeviceFault::io, fmt::format("{}: cannot open: {}", o_.device, std::strerror(e)));
    }
    stop_fd_ = ::eventfd(0, EFD_NONBLOCK | EFD_CLOEXEC);
    query_capabilities();
    negotiate_format();
    map_buffers();
  }

  void start() override {
    for (std::uint32_t i = 0; i < buffers_.size(); ++i) queue(i);
    v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd_, VIDIOC_STREAMON, &type) < 0) fail_ioctl("VIDIOC_STREAMON");
    streaming_ = true;
  }

  std::optional<Frame> next(SteadyTime deadline) override {
    const double patience = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    while (!stopping_) {
      const auto now = std::chrono::steady_clock::now();
      if (now >= deadline)
        throw DeviceFailure(DeviceFault::timeout,
                            fmt::format("{}: no frames for {:.0f} s after {} frames; check the cable and that no other "
                                        "program holds the camera", o_.device, patience, stats_.frames));
      pollfd fds[2] = {{fd_, POLLIN, 0}, {stop_fd_, POLLIN, 0}};
      const auto wait = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - now).count();
      const int r = ::poll(fds, 2, static_cast<int>(std::min<long long>(wait + 1, 100)));
      if (r < 0 && errno != EINTR) fail_ioctl("poll");
      if (r <= 0) continue;
      if (fds[1].revents) break;
      if (fds[0].revents & (POLLERR | POLLHUP))
        throw vanished();  // a real driver reports POLLERR once the device is gone
      const auto busy_start = std::chrono::steady_clock::now();
      std::optional<Frame> f = dequeue();
      if (f) {
        stats_.busy_seconds += seconds_since(busy_start);
        return f;
      }
      // POLLIN without a buffer: spurious (or an emulated device whose poll always succeeds);
      // back off a little instead of spinning.
      std::this_thread::sleep_for(500us);
    }
    return std::nullopt;
  }

  void stop() override {
    stopping_ = true;
    if (stop_fd_ >= 0) {
      const std::uint64_t one = 1;
      [[maybe_unused]] const auto n = ::write(stop_fd_, &one, sizeof one);  // async-signal-safe
    }
  }

 private:
  struct Buffer {
    void* start = MAP_FAILED;
    std::size_t length = 0;
  };

  DeviceFailure vanished() const {
    return DeviceFailure(DeviceFault::vanished,
                         fmt::format("{}: device vanished (unplugged?) after {} frames", o_.device, stats_.frames));
  }

  [[noreturn]] void fail_ioctl(const char* what) const {
    const int e = errno;
    if (unplugged(e)) throw vanished();
    throw DeviceFailure(DeviceFault::io, fmt::format("{}: {} failed: {}", o_.device, what, std::strerror(e)));
  }

  void query_capabilities() {
    v4l2_capability cap{};
    if (xioctl(fd_, VIDIOC_QUERYCAP, &cap) < 0) {
      if (errno == ENOTTY || errno == EINVAL)
        throw DeviceFailure(DeviceFault::wrong_format, fmt::format("{}: not a V4L2 device", o_.device));
      fail_ioctl("VIDIOC_QUERYCAP");
    }
    const std::uint32_t caps = (cap.capabilities & V4L2_CAP_DEVICE_CAPS) ? cap.device_caps : cap.capabilities;
    if (!(caps & V4L2_CAP_VIDEO_CAPTURE))
      throw DeviceFailure(DeviceFault::wrong_format, fmt::format("{} ({}): not a video capture device", o_.device,
                                                                 reinterpret_cast<const char*>(cap.card)));
    if (!(caps & V4L2_CAP_STREAMING))
      throw DeviceFailure(DeviceFault::wrong_format, fmt::format("{} ({}): does not support streaming I/O", o_.device,
                                                                 reinterpret_cast<const char*>(cap.card)));
    card_ = reinterpret_cast<const char*>(cap.card);
  }

  /// Every format the device offers with its frame sizes and rates, for the wrong-format message.
  std::string describe_formats(std::vector<std::uint32_t>* fourccs) {
    std::string text;
    for (std::uint32_t i = 0;; ++i) {
      v4l2_fmtdesc d{};
      d.index = i;
      d.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      if (xioctl(fd_, VIDIOC_ENUM_FMT, &d) < 0) break;
      if (fourccs) fourccs->push_back(d.pixelformat);
      text += fmt::format("\n  {} ({})", fourcc_text(d.pixelformat), reinterpret_cast<const char*>(d.description));
      for (std::uint32_t j = 0; j < 16; ++j) {
        v4l2_frmsizeenum s{};
        s.index = j;
        s.pixel_format = d.pixelformat;
        if (xioctl(fd_, VIDIOC_ENUM_FRAMESIZES, &s) < 0) break;
        if (s.type == V4L2_FRMSIZE_TYPE_DISCRETE) {
          text += fmt::format(" {}x{}", s.discrete.width, s.discrete.height);
          text += describe_intervals(d.pixelformat, s.discrete.width, s.discrete.height);
        } else {
          text += fmt::format(" {}x{}..{}x{}", s.stepwise.min_width, s.stepwise.min_height, s.stepwise.max_width,
                              s.stepwise.max_height);
          break;
        }
      }
    }
    return text.empty() ? "\n  (none listed)" : text;
  }

  std::string describe_intervals(std::uint32_t fourcc, std::uint32_t w, std::uint32_t h) {
    std::string rates;
    for (std::uint32_t k = 0; k < 8; ++k) {
      v4l2_frmivalenum iv{};
      iv.index = k;
      iv.pixel_format = fourcc;
      iv.width = w;
      iv.height = h;
      if (xioctl(fd_, VIDIOC_ENUM_FRAMEINTERVALS, &iv) < 0 || iv.type != V4L2_FRMIVAL_TYPE_DISCRETE) break;
      if (iv.discrete.numerator)
        rates += fmt::format("{}{:g}", rates.empty() ? "" : "/", double(iv.discrete.denominator) / iv.discrete.numerator);
    }
    return rates.empty() ? "" : fmt::format("@{}fps", rates);
  }

  void negotiate_format() {
    std::vector<std::uint32_t> offered;
    const std::string offered_text = describe_formats(&offered);
    std::uint32_t want = 0;
    for (std::uint32_t f : {V4L2_PIX_FMT_Z16, V4L2_PIX_FMT_Y16})
      if (!want && std::find(offered.begin(), offered.end(), f) != offered.end()) want = f;
    if (!want)
      throw DeviceFailure(DeviceFault::wrong_format,
                          fmt::format("{} ({}): offers no 16-bit depth format (Z16 or Y16); it offers:{}\n"
                                      "Is this the depth node of the camera? Its colour/IR nodes are separate /dev/video* "
                                      "devices.", o_.device, card_, offered_text));
    v4l2_format fmt{};
    fmt.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    if (xioctl(fd_, VIDIOC_G_FMT, &fmt) < 0) fail_ioctl("VIDIOC_G_FMT");
    const int want_w = o_.width ? o_.width : info_.width, want_h = o_.height ? o_.height : info_.height;
    if (want_w > 0 && want_h > 0) {
      fmt.fmt.pix.width = static_cast<std::uint32_t>(want_w);
      fmt.fmt.pix.height = static_cast<std::uint32_t>(want_h);
    }
    fmt.fmt.pix.pixelformat = want;
    fmt.fmt.pix.field = V4L2_FIELD_NONE;
    if (xioctl(fd_, VIDIOC_S_FMT, &fmt) < 0) fail_ioctl("VIDIOC_S_FMT");
    // The driver may have chosen something else: believe only what it reads back.
    if (!is_depth_format(fmt.fmt.pix.pixelformat))
      throw DeviceFailure(DeviceFault::wrong_format,
                          fmt::format("{} ({}): asked for {}, the device set {}; it offers:{}", o_.device, card_,
                                      fourcc_text(want), fourcc_text(fmt.fmt.pix.pixelformat), offered_text));
    const int w = static_cast<int>(fmt.fmt.pix.width), h = static_cast<int>(fmt.fmt.pix.height);
    if (want_w > 0 && want_h > 0 && (w != want_w || h != want_h))
      throw DeviceFailure(DeviceFault::wrong_format,
                          fmt::format("{}: the calibration is for {}x{} but the device streams {}x{}; calibrate at "
                                      "that size or pass --width/--height it offers:{}",
                                      o_.device, want_w, want_h, w, h, offered_text));
    if (w < 1 || h < 1 || w > 16384 || h > 16384)
      throw DeviceFailure(DeviceFault::wrong_format, fmt::format("{}: absurd frame size {}x{}", o_.device, w, h));
    info_.width = w;
    info_.height = h;
    bytes_per_line_ = std::max<int>(static_cast<int>(fmt.fmt.pix.bytesperline), 2 * w);
    if (o_.fps > 0) {
      v4l2_streamparm parm{};
      parm.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      parm.parm.capture.timeperframe = {1000, static_cast<std::uint32_t>(o_.fps * 1000)};
      if (xioctl(fd_, VIDIOC_S_PARM, &parm) < 0) spdlog::warn("{}: cannot set {} fps; using the device's rate", o_.device, o_.fps);
    }
    spdlog::debug("{}: {} {}x{}, {} bytes per line", o_.device, fourcc_text(fmt.fmt.pix.pixelformat), w, h, bytes_per_line_);
  }

  void map_buffers() {
    v4l2_requestbuffers req{};
    req.count = static_cast<std::uint32_t>(o_.buffers);
    req.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    req.memory = V4L2_MEMORY_MMAP;
    if (xioctl(fd_, VIDIOC_REQBUFS, &req) < 0) fail_ioctl("VIDIOC_REQBUFS");
    if (req.count < 2)
      throw DeviceFailure(DeviceFault::io, fmt::format("{}: only {} capture buffer(s) available", o_.device, req.count));
    buffers_.resize(req.count);
    for (std::uint32_t i = 0; i < req.count; ++i) {
      v4l2_buffer b{};
      b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      b.memory = V4L2_MEMORY_MMAP;
      b.index = i;
      if (xioctl(fd_, VIDIOC_QUERYBUF, &b) < 0) fail_ioctl("VIDIOC_QUERYBUF");
      buffers_[i].length = b.length;
      buffers_[i].start = ::mmap(nullptr, b.length, PROT_READ | PROT_WRITE, MAP_SHARED, fd_, b.m.offset);
      if (buffers_[i].start == MAP_FAILED) fail_ioctl("mmap");
    }
  }

  void queue(std::uint32_t index) {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    b.index = index;
    if (xioctl(fd_, VIDIOC_QBUF, &b) < 0) fail_ioctl("VIDIOC_QBUF");
  }

  /// One DQBUF: a decoded frame, or nothing (not ready, or a dropped frame requeued).
  std::optional<Frame> dequeue() {
    v4l2_buffer b{};
    b.type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
    b.memory = V4L2_MEMORY_MMAP;
    const auto call_start = std::chrono::steady_clock::now();
    if (xioctl(fd_, VIDIOC_DQBUF, &b) < 0) {
      if (errno == EAGAIN) return std::nullopt;
      fail_ioctl("VIDIOC_DQBUF");
    }
    stats_.device_call_seconds += seconds_since(call_start);
    if (b.index >= buffers_.size())
      throw DeviceFailure(DeviceFault::io, fmt::format("{}: driver returned buffer {} of {}", o_.device, b.index, buffers_.size()));
    const auto now = std::chrono::steady_clock::now();
    if (last_sequence_ && b.sequence > *last_sequence_ + 1) stats_.sequence_gaps += b.sequence - *last_sequence_ - 1;
    last_sequence_ = b.sequence;
    std::optional<DepthImage> img;
    bool dropped = false;
    if (b.flags & V4L2_BUF_FLAG_ERROR) {
      ++stats_.dropped_error;
      dropped = true;
    } else {
      const std::size_t used = std::min<std::size_t>(b.bytesused, buffers_[b.index].length);
      img = decode_z16(static_cast<const std::uint8_t*>(buffers_[b.index].start), used, info_.width, info_.height,
                       bytes_per_line_);
      if (!img) {
        ++stats_.dropped_short;
        dropped = true;
      }
    }
    const auto requeue_start = std::chrono::steady_clock::now();
    queue(b.index);  // back to the driver at once: the copy above is ours
    stats_.device_call_seconds += seconds_since(requeue_start);
    if (auto warning = drops_.count(dropped, now)) spdlog::warn("{}: {}", o_.device, *warning);
    if (!img) return std::nullopt;
    ++stats_.frames;
    Frame f;
    f.sequence = b.sequence;
    f.timestamp = b.timestamp.tv_sec + b.timestamp.tv_usec * 1e-6;
    f.image = std::move(*img);
    return f;
  }

  void close_device() {
    if (fd_ < 0) return;
    if (streaming_) {
      v4l2_buf_type type = V4L2_BUF_TYPE_VIDEO_CAPTURE;
      xioctl(fd_, VIDIOC_STREAMOFF, &type);  // errors ignored: the device may be gone
    }
    for (auto& b : buffers_)
      if (b.start != MAP_FAILED) ::munmap(b.start, b.length);
    buffers_.clear();
    ::close(fd_);
    fd_ = -1;
    if (stop_fd_ >= 0) ::close(stop_fd_);
    stop_fd_ = -1;
  }

  static double seconds_since(SteadyTime t) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
  }

  V4l2Options o_;
  StreamInfo info_;
  std::string card_;
  int fd_ = -1, stop_fd_ = -1;
  std::atomic<bool> stopping_{false};
  bool streaming_ = false;
  std::vector<Buffer> buffers_;
  int bytes_per_line_ = 0;
  std::optional<std::uint32_t> last_sequence_;
  SourceStats stats_;
  DropMonitor drops_;
};

}  // namespace

std::unique_ptr<FrameSource> make_v4l2_source(const V4l2Options& options) {
  return std::make_unique<V4l2Source>(options);
}

}  // namespace s2c
