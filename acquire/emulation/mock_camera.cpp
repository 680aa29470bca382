#include "mock_camera.h"

#include <fcntl.h>
#include <linux/videodev2.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <deque>
#include <mutex>
#include <stdexcept>

#include <umockdev.h>

namespace s2c::emulation {

struct MockCamera::State {
  MockCameraOptions o;
  UMockdevTestbed* testbed = nullptr;
  UMockdevIoctlBase* handler = nullptr;
  std::string node_file;  // the regular file behind /dev/video0 (mmap'ed by the client)
  int node_fd = -1;

  std::mutex mutex;
  bool unplugged = false, streaming = false;
  std::uint32_t format = V4L2_PIX_FMT_Z16;
  std::uint32_t buffer_bytes = 0, count = 0;
  std::deque<std::uint32_t> queued;           // buffers the client gave us
  struct Filled { std::uint32_t index, sequence, bytes, flags; timeval stamp; };
  std::deque<Filled> filled;                  // buffers holding a frame, not yet dequeued
  std::chrono::steady_clock::time_point t0;
  std::uint64_t produced = 0, delivered = 0, dropped = 0;
  int short_left = 0, error_left = 0;

  std::uint32_t image_bytes() const { return static_cast<std::uint32_t>(o.width * o.height * 2); }

  /// Frames due since STREAMON go into queued buffers; with none queued they are lost.
  void produce() {
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const auto due = static_cast<std::uint64_t>(elapsed * o.fps) + 1;
    for (; produced < due; ++produced) {
      if (queued.empty()) {
        ++dropped;
        continue;
      }
      const std::uint32_t index = queued.front();
      queued.pop_front();
      const DepthImage& img = o.frames[produced % o.frames.size()];
      if (node_fd < 0) node_fd = ::open(node_file.c_str(), O_WRONLY | O_CLOEXEC);
      [[maybe_unused]] auto n = ::pwrite(node_fd, img.data.data(), img.data.size() * 2,
                                         static_cast<off_t>(index) * buffer_bytes);
      Filled f{index, static_cast<std::uint32_t>(produced), image_bytes(), V4L2_BUF_FLAG_MAPPED | V4L2_BUF_FLAG_DONE, {}};
      if (short_left > 0) {
        --short_left;
        f.bytes /= 2;
      }
      if (error_left > 0) {
        --error_left;
        f.flags |= V4L2_BUF_FLAG_ERROR;
      }
      const double t = static_cast<double>(produced) / o.fps;
      f.stamp.tv_sec = static_cast<time_t>(t);
      f.stamp.tv_usec = static_cast<suseconds_t>((t - f.stamp.tv_sec) * 1e6);
      filled.push_back(f);
    }
  }

  bool offers(std::uint32_t f) const { return std::find(o.formats.begin(), o.formats.end(), f) != o.formats.end(); }

  /// Answers one ioctl: returns (result, errno).
  std::pair<int, int> handle(unsigned long request, UMockdevIoctlData* arg) {
    std::lock_guard<std::mutex> lock(mutex);
    if (unplugged) return {-1, ENODEV};
    auto resolve = [&](std::size_t size) { return umockdev_ioctl_data_resolve(arg, 0, size, nullptr); };
    switch (request) {
      case VIDIOC_QUERYCAP: {
        UMockdevIoctlData* d = resolve(sizeof(v4l2_capability));
        auto* c = reinterpret_cast<v4l2_capability*>(d->data);
        std::memset(c, 0, sizeof *c);
        std::strcpy(reinterpret_cast<char*>(c->driver), "s2c-mock");
        std::strcpy(reinterpret_cast<char*>(c->card), "scan2cad emulated Z16 camera");
        c->device_caps = V4L2_CAP_VIDEO_CAPTURE | V4L2_CAP_STREAMING;
        c->capabilities = c->device_caps | V4L2_CAP_DEVICE_CAPS;
        umockdev_ioctl_data_unref(d);
        return {0, 0};
      }
      case VIDIOC_ENUM_FMT: {
        UMockdevIoctlData* d = resolve(sizeof(v4l2_fmtdesc));
        auto* f = reinterpret_cast<v4l2_fmtdesc*>(d->data);
        const bool ok = f->index < o.formats.size();
        if (ok) {
          f->pixelformat = o.formats[f->index];
          std::snprintf(reinterpret_cast<char*>(f->description), sizeof f->description, "%s",
                        f->pixelformat == V4L2_PIX_FMT_Z16 ? "16-bit Depth" : "other");
        }
        umockdev_ioctl_data_unref(d);
        return ok ? std::pair{0, 0} : std::pair{-1, EINVAL};
      }
      case VIDIOC_ENUM_FRAMESIZES: {
        UMockdevIoctlData* d = resolve(sizeof(v4l2_frmsizeenum));
        auto* s = reinterpret_cast<v4l2_frmsizeenum*>(d->data);
        const bool ok = s->index == 0 && offers(s->pixel_format);
        if (ok) {
          s->type = V4L2_FRMSIZE_TYPE_DISCRETE;
          s->discrete = {static_cast<std::uint32_t>(o.width), static_cast<std::uint32_t>(o.height)};
        }
        umockdev_ioctl_data_unref(d);
        return ok ? std::pair{0, 0} : std::pair{-1, EINVAL};
      }
      case VIDIOC_ENUM_FRAMEINTERVALS: {
        UMockdevIoctlData* d = resolve(sizeof(v4l2_frmivalenum));
        auto* iv = reinterpret_cast<v4l2_frmivalenum*>(d->data);
        const bool ok = iv->index == 0;
        if (ok) {
          iv->type = V4L2_FRMIVAL_TYPE_DISCRETE;
          iv->discrete = {1000, static_cast<std::uint32_t>(o.fps * 1000)};
        }
        umockdev_ioctl_data_unref(d);
        return ok ? std::pair{0, 0} : std::pair{-1, EINVAL};
      }
      case VIDIOC_G_FMT:
      case VIDIOC_S_FMT: {
        UMockdevIoctlData* d = resolve(sizeof(v4l2_format));
        auto* f = reinterpret_cast<v4l2_format*>(d->data);
        // Like a driver: an unsupported request is corrected, not refused.
        if (request == VIDIOC_S_FMT) format = offers(f->fmt.pix.pixelformat) ? f->fmt.pix.pixelformat : o.formats[0];
        f->fmt.pix.pixelformat = format;
        f->fmt.pix.width = static_cast<std::uint32_t>(o.width);
        f->fmt.pix.height = static_cast<std::uint32_t>(o.height);
        f->fmt.pix.bytesperline = static_cast<std::uint32_t>(o.width * 2);
        f->fmt.pix.sizeimage = image_bytes();
        f->fmt.pix.field = V4L2_FIELD_NONE;
        umockdev_ioctl_data_unref(d);
        return {0, 0};
      }
      case VIDIOC_S_PARM: return {0, 0};
      case VIDIOC_REQBUFS: {
        UMockdevIoctlData* d = resolve(sizeof(v4l2_requestbuffers));
        auto* r = reinterpret_cast<v4l2_requestbuffers*>(d->data);
        const long page = ::sysconf(_SC_PAGESIZE);
        buffer_bytes = static_cast<std::uint32_t>((image_bytes() + page - 1) / page * page);
        count = std::min<std::uint32_t>(r->count, 8);
        r->count = count;
        umockdev_ioctl_data_unref(d);
        if (::truncate(node_file.c_str(), static_cast<off_t>(count) * buffer_bytes) < 0) return {-1, ENOMEM};
        return {0, 0};
      }
      case VIDIOC_QUERYBUF:
      case VIDIOC_QBUF: {
        UMockdevIoctlData* d = resolve(sizeof(v4l2_buffer));
        auto* b = reinterpret_cast<v4l2_buffer*>(d->data);
        const bool ok = b->index < count;
        if (ok && request == VIDIOC_QUERYBUF) {
          b->length = buffer_bytes;
          b->m.offset = b->index * buffer_bytes;
        }
        if (ok && request == VIDIOC_QBUF) queued.push_back(b->index);
        umockdev_ioctl_data_unref(d);
        return ok ? std::pair{0, 0} : std::pair{-1, EINVAL};
      }
      case VIDIOC_STREAMON:
        streaming = true;
        t0 = std::chrono::steady_clock::now();
        return {0, 0};
      case VIDIOC_STREAMOFF:
        streaming = false;
        queued.clear();
        filled.clear();
        return {0, 0};
      case VIDIOC_DQBUF: {
        if (!streaming) return {-1, EINVAL};
        produce();
        if (filled.empty()) return {-1, EAGAIN};
        const Filled f = filled.front();
        filled.pop_front();
        UMockdevIoctlData* d = resolve(sizeof(v4l2_buffer));
        auto* b = reinterpret_cast<v4l2_buffer*>(d->data);
        b->index = f.index;
        b->bytesused = f.bytes;
        b->flags = f.flags;
        b->sequence = f.sequence;
        b->timestamp = f.stamp;
        b->length = buffer_bytes;
        b->m.offset = f.index * buffer_bytes;
        umockdev_ioctl_data_unref(d);
        ++delivered;
        return {0, 0};
      }
      default: return {-1, ENOTTY};
    }
  }
};

namespace {

gboolean on_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self) {
  auto* s = static_cast<MockCamera::State*>(self);
  const auto [result, err] = s->handle(umockdev_ioctl_client_get_request(client), umockdev_ioctl_client_get_arg(client));
  umockdev_ioctl_client_complete(client, result, err);
  return TRUE;
}

DepthImage ramp(int w, int h) {
  DepthImage d;
  d.width = w;
  d.height = h;
  d.data.resize(static_cast<std::size_t>(w) * h);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) d.data[static_cast<std::size_t>(v) * w + u] = static_cast<std::uint16_t>(1000 + u + v);
  return d;
}

}  // namespace

MockCamera::MockCamera(MockCameraOptions options) : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.o = std::move(options);
  if (s.o.formats.empty()) s.o.formats = {V4L2_PIX_FMT_Z16};
  if (s.o.frames.empty()) s.o.frames = {ramp(s.o.width, s.o.height)};
  for (const auto& f : s.o.frames)
    if (f.width != s.o.width || f.height != s.o.height) throw std::invalid_argument("MockCamera: frame size mismatch");
  s.format = s.o.formats[0];
  s.testbed = umockdev_testbed_new();
  gchar* root = umockdev_testbed_get_root_dir(s.testbed);
  s.node_file = std::string(root) + "/dev/video0";
  g_free(root);
  s.handler = umockdev_ioctl_base_new();
  g_signal_connect(s.handler, "handle-ioctl", G_CALLBACK(on_ioctl), &s);
  GError* error = nullptr;
  // "N: video0=00": the node is a regular file (one byte, grown by REQBUFS) that mmap can map.
  umockdev_testbed_add_from_string(s.testbed,
                                   "P: /devices/virtual/video4linux/video0\nN: video0=00\n"
                                   "E: SUBSYSTEM=video4linux\nE: DEVNAME=/dev/video0\n",
                                   &error);
  if (!error) umockdev_testbed_attach_ioctl(s.testbed, "/dev/video0", s.handler, &error);
  if (error) {
    const std::string what = error->message;
    g_error_free(error);
    throw std::runtime_error("MockCamera: " + what);
  }
}

MockCamera::~MockCamera() {
  if (state_->node_fd >= 0) ::close(state_->node_fd);
  g_clear_object(&state_->handler);
  g_clear_object(&state_->testbed);
}

void MockCamera::unplug() {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->unplugged = true;
}
void MockCamera::short_frames(int n) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->short_left += n;
}
void MockCamera::error_frames(int n) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->error_left += n;
}
std::uint64_t MockCamera::frames_delivered() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->delivered;
}
std::uint64_t MockCamera::frames_dropped() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->dropped;
}

}  // namespace s2c::emulation
