// USB laser line scanner: libusb-1.0 asynchronous bulk transfers, 4–8 in flight, resubmitted
// from their callback; an event thread runs libusb's event loop; profiles become sweeps in the
// caller's thread.
#include <libusb.h>

#include <atomic>
#include <condition_variable>
#include <deque>
#include <mutex>
#include <thread>
#include <vector>

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include "s2c/acquire/decode.h"
#include "s2c/acquire/sources.h"

namespace s2c {
namespace {

using namespace std::chrono_literals;

std::string usb_id(std::uint16_t vid, std::uint16_t pid) { return fmt::format("{:04x}:{:04x}", vid, pid); }

class UsbLaserSource final : public FrameSource {
 public:
  explicit UsbLaserSource(UsbLaserOptions o) : o_(std::move(o)), assembler_(o_.calibration, o_.profiles_per_sweep) {
    info_ = o_.calibration;
    info_.sensor = Sensor::laser;
    info_.height = std::max(1, o_.profiles_per_sweep);
    info_.device = name();
  }
  ~UsbLaserSource() override { shutdown(); }

  std::string name() const override { return "usb:" + usb_id(o_.vendor, o_.product); }
  const StreamInfo& info() const override { return info_; }
  SourceStats stats() const override {
    std::lock_guard<std::mutex> lock(mutex_);
    SourceStats s = stats_;
    s.sequence_gaps = assembler_.sequence_gaps();
    return s;
  }

  void open() override {
    if (o_.transfers < 1 || o_.transfers > 32) throw InvalidInput("USB transfers in flight must be 1..32 (4-8 advised)");
    if (o_.profiles_per_sweep < 1) throw InvalidInput("profiles per sweep must be at least 1");
    if (int r = libusb_init(&ctx_); r < 0)
      throw DeviceFailure(DeviceFault::io, fmt::format("libusb: cannot initialise: {}", libusb_strerror(r)));
    libusb_device* dev = find_device();
    const int r = libusb_open(dev, &handle_);
    libusb_unref_device(dev);
    if (r < 0) fail(r, "open");
    libusb_set_auto_detach_kernel_driver(handle_, 1);
    if (int c = libusb_claim_interface(handle_, o_.interface); c < 0) {
      if (c == LIBUSB_ERROR_BUSY)
        throw DeviceFailure(DeviceFault::busy, fmt::format("{}: interface {} is claimed by another program; close it "
                                                           "and retry", name(), o_.interface));
      fail(c, "claim interface");
    }
    claimed_ = true;
    if (libusb_has_capability(LIBUSB_CAP_HAS_HOTPLUG)) {
      const int h = libusb_hotplug_register_callback(ctx_, LIBUSB_HOTPLUG_EVENT_DEVICE_LEFT, LIBUSB_HOTPLUG_NO_FLAGS,
                                                     o_.vendor, o_.product, LIBUSB_HOTPLUG_MATCH_ANY, &on_hotplug, this,
                                                     &hotplug_);
      hotplug_registered_ = h == LIBUSB_SUCCESS;
    }
  }

  void start() override {
    // One profile per bulk transfer: the device ends each profile with a short packet, so a
    // transfer sized for the largest profile completes with exactly one.
    const std::size_t bytes = (profile_packet_bytes(o_.max_points) + 511) / 512 * 512;
    events_ = std::thread([this] { event_loop(); });
    for (int i = 0; i < o_.transfers; ++i) {
      Transfer t;
      t.buffer.resize(bytes);
      t.xfer = libusb_alloc_transfer(0);
      transfers_.push_back(std::move(t));
    }
    for (auto& t : transfers_) {
      libusb_fill_bulk_transfer(t.xfer, handle_, o_.endpoint, t.buffer.data(), static_cast<int>(t.buffer.size()),
                                &on_transfer, this, 0);
      submit(t.xfer);
    }
  }

  std::optional<Frame> next(SteadyTime deadline) override {
    const double patience = std::chrono::duration<double>(deadline - std::chrono::steady_clock::now()).count();
    std::unique_lock<std::mutex> lock(mutex_);
    for (;;) {
      if (!sweeps_.empty()) {
        Frame f = std::move(sweeps_.front());
        sweeps_.pop_front();
        ++stats_.frames;
        return f;
      }
      if (!profiles_.empty()) {
        const auto busy_start = std::chrono::steady_clock::now();
        Profile p = std::move(profiles_.front());
        profiles_.pop_front();
        for (auto& s : assembler_.add(p)) sweeps_.push_back(std::move(s));
        stats_.busy_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - busy_start).count();
        continue;
      }
      if (!stalled_.empty()) {  // clear the halt here, not in the callback: it is a synchronous request
        libusb_transfer* t = stalled_.front();
        stalled_.pop_front();
        lock.unlock();
        const int r = libusb_clear_halt(handle_, o_.endpoint);
        lock.lock();
        if (r == LIBUSB_ERROR_NO_DEVICE) gone_ = true;
        else if (r < 0) spdlog::warn("{}: clearing the endpoint halt failed: {}", name(), libusb_strerror(r));
        --in_flight_;  // submit() counts it again
        if (!gone_ && !stopping_) {
          lock.unlock();
          submit(t);
          lock.lock();
        }
        continue;
      }
      if (stopping_ || gone_) {
        if (auto partial = assembler_.flush()) {
          ++stats_.frames;
          return partial;
        }
        if (gone_ && !stopping_)
          throw DeviceFailure(DeviceFault::vanished,
                              fmt::format("{}: device vanished (unplugged?) after {} sweeps", name(), stats_.frames));
        return std::nullopt;
      }
      if (cv_.wait_until(lock, deadline) == std::cv_status::timeout && profiles_.empty() && sweeps_.empty() &&
          stalled_.empty() && !gone_ && !stopping_)
        throw DeviceFailure(DeviceFault::timeout,
                            fmt::format("{}: no profiles for {:.0f} s after {} sweeps; is the laser on and the "
                                        "scanner triggered?", name(), patience, stats_.frames));
    }
  }

  void stop() override {
    stopping_ = true;
    cv_.notify_all();
  }

 private:
  struct Transfer {
    libusb_transfer* xfer = nullptr;
    std::vector<unsigned char> buffer;
  };

  [[noreturn]] void fail(int r, const char* what) const {
    if (r == LIBUSB_ERROR_ACCESS)
      throw DeviceFailure(DeviceFault::io, fmt::format("{}: permission denied; install a udev rule giving your user "
                                                       "access (docs/acquire.md)", name()));
    if (r == LIBUSB_ERROR_BUSY) throw DeviceFailure(DeviceFault::busy, fmt::format("{}: device is busy", name()));
    if (r == LIBUSB_ERROR_NO_DEVICE)
      throw DeviceFailure(DeviceFault::vanished, fmt::format("{}: device vanished (unplugged?)", name()));
    throw DeviceFailure(DeviceFault::io, fmt::format("{}: {} failed: {}", name(), what, libusb_strerror(r)));
  }

  libusb_device* find_device() {
    libusb_device** list = nullptr;
    const ssize_t n = libusb_get_device_list(ctx_, &list);
    if (n < 0) fail(static_cast<int>(n), "listing devices");
    libusb_device* found = nullptr;
    for (ssize_t i = 0; i < n && !found; ++i) {
      libusb_device_descriptor d{};
      if (libusb_get_device_descriptor(list[i], &d) == 0 && d.idVendor == o_.vendor && d.idProduct == o_.product)
        found = libusb_ref_device(list[i]);
    }
    libusb_free_device_list(list, 1);
    if (!found)
      throw DeviceFailure(DeviceFault::not_found,
                          fmt::format("no USB device {} found ({} devices present); is the scanner plugged in and "
                                      "powered? `lsusb` lists the devices", usb_id(o_.vendor, o_.product), n));
    return found;
  }

  void submit(libusb_transfer* t) {
    const int r = libusb_submit_transfer(t);
    std::lock_guard<std::mutex> lock(mutex_);
    if (r == 0) {
      ++in_flight_;
      return;
    }
    if (r == LIBUSB_ERROR_NO_DEVICE) gone_ = true;
    else spdlog::warn("{}: cannot submit a transfer: {}", name(), libusb_strerror(r));
    cv_.notify_all();
  }

  static void LIBUSB_CALL on_transfer(libusb_transfer* t) { static_cast<UsbLaserSource*>(t->user_data)->completed(t); }

  /// Runs in the event thread: decode, queue, resubmit at once (so the device never waits).
  void completed(libusb_transfer* t) {
    bool resubmit = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      --in_flight_;
      switch (t->status) {
        case LIBUSB_TRANSFER_COMPLETED: {
          DecodeError e{};
          auto p = decode_profile(t->buffer, static_cast<std::size_t>(t->actual_length), &e);
          if (p) profiles_.push_back(std::move(*p));
          else if (e == DecodeError::short_buffer) ++stats_.dropped_short;
          else ++stats_.dropped_error;
          if (auto w = drops_.count(!p, std::chrono::steady_clock::now())) spdlog::warn("{}: {}", name(), *w);
          resubmit = true;
          break;
        }
        case LIBUSB_TRANSFER_STALL:
          ++stats_.stalls;
          ++in_flight_;  // still ours until next() clears the halt and resubmits it
          stalled_.push_back(t);
          break;
        case LIBUSB_TRANSFER_NO_DEVICE:
          gone_ = true;
          break;
        case LIBUSB_TRANSFER_CANCELLED:
          break;
        default:  // ERROR, OVERFLOW, TIMED_OUT: this transfer is lost, the stream goes on
          ++stats_.dropped_error;
          resubmit = true;
          break;
      }
      if (stopping_ || gone_) resubmit = false;
    }
    cv_.notify_all();
    if (resubmit) submit(t);
  }

  static int LIBUSB_CALL on_hotplug(libusb_context*, libusb_device*, libusb_hotplug_event, void* self) {
    auto* s = static_cast<UsbLaserSource*>(self);
    {
      std::lock_guard<std::mutex> lock(s->mutex_);
      s->gone_ = true;
    }
    s->cv_.notify_all();
    return 0;
  }

  void event_loop() {
    while (!events_stop_) {
      timeval tv{0, 100000};
      int completed = 0;
      libusb_handle_events_timeout_completed(ctx_, &tv, &completed);
    }
  }

  /// Cancels every transfer in flight and waits for their callbacks (at most 2 s), so no
  /// callback can run after the buffers are freed.
  void shutdown() {
    stopping_ = true;
    if (events_.joinable()) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (libusb_transfer* t : stalled_) {
          (void)t;
          --in_flight_;
        }
        stalled_.clear();
      }
      for (auto& t : transfers_) libusb_cancel_transfer(t.xfer);  // errors: already completed
      std::unique_lock<std::mutex> lock(mutex_);
      if (!cv_.wait_for(lock, 2s, [&] { return in_flight_ <= 0; }))
        spdlog::warn("{}: {} transfers did not complete after cancel", name(), in_flight_);
      lock.unlock();
      events_stop_ = true;
      if (hotplug_registered_) libusb_hotplug_deregister_callback(ctx_, hotplug_);  // wakes the event loop
      hotplug_registered_ = false;
      events_.join();
    }
    if (hotplug_registered_) libusb_hotplug_deregister_callback(ctx_, hotplug_);
    if (in_flight_ <= 0)
      for (auto& t : transfers_) libusb_free_transfer(t.xfer);
    transfers_.clear();
    if (handle_) {
      if (claimed_) libusb_release_interface(handle_, o_.interface);
      libusb_close(handle_);
      handle_ = nullptr;
    }
    if (ctx_) libusb_exit(ctx_);
    ctx_ = nullptr;
  }

  UsbLaserOptions o_;
  StreamInfo info_;
  libusb_context* ctx_ = nullptr;
  libusb_device_handle* handle_ = nullptr;
  libusb_hotplug_callback_handle hotplug_{};
  bool claimed_ = false, hotplug_registered_ = false;
  std::vector<Transfer> transfers_;
  std::thread events_;
  std::atomic<bool> events_stop_{false}, stopping_{false};

  mutable std::mutex mutex_;  // guards everything below (shared with the event thread)
  std::condition_variable cv_;
  int in_flight_ = 0;
  bool gone_ = false;
  std::deque<Profile> profiles_;
  std::deque<libusb_transfer*> stalled_;
  std::deque<Frame> sweeps_;
  SweepAssembler assembler_;
  SourceStats stats_;
  DropMonitor drops_;
};

}  // namespace

std::unique_ptr<FrameSource> make_usb_laser_source(const UsbLaserOptions& options) {
  return std::make_unique<UsbLaserSource>(options);
}

}  // namespace s2c
