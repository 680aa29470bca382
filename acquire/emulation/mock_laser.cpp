#include "mock_laser.h"

#include <linux/ioctl.h>
#include <linux/usbdevice_fs.h>

#include <chrono>
#include <cstring>
#include <deque>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <string>

#include <fmt/format.h>
#include <umockdev.h>

namespace s2c::emulation {

struct MockLaser::State {
  MockLaserOptions o;
  UMockdevTestbed* testbed = nullptr;
  UMockdevIoctlBase* handler = nullptr;

  std::mutex mutex;
  struct Urb {
    UMockdevIoctlData* urb;     // the client's struct usbdevfs_urb
    UMockdevIoctlData* buffer;  // its data buffer
  };
  std::deque<Urb> flying, discarded;
  bool unplugged = false;
  std::optional<std::uint64_t> stall, truncate;
  int lose = 0;
  std::uint64_t lose_at = 0;
  std::chrono::steady_clock::time_point t0 = std::chrono::steady_clock::now();
  std::uint64_t sequence = 0, sent = 0, halts = 0;

  static usbdevfs_urb* as_urb(UMockdevIoctlData* d) { return reinterpret_cast<usbdevfs_urb*>(d->data); }

  /// Hands `u` back to the client through the REAPURB argument.
  static void reap(UMockdevIoctlData* arg, const Urb& u) {
    UMockdevIoctlData* out = umockdev_ioctl_data_resolve(arg, 0, sizeof(void*), nullptr);
    umockdev_ioctl_data_set_ptr(out, 0, u.urb);
    umockdev_ioctl_data_unref(out);
  }
  static void release(const Urb& u) {
    umockdev_ioctl_data_unref(u.buffer);
    umockdev_ioctl_data_unref(u.urb);
  }

  /// Fills the oldest URB with the next profile if one is due.
  std::pair<int, int> reap_next(UMockdevIoctlData* arg) {
    if (!discarded.empty()) {  // cancelled transfers come back first, with -ENOENT
      Urb u = discarded.front();
      discarded.pop_front();
      as_urb(u.urb)->status = -ENOENT;
      as_urb(u.urb)->actual_length = 0;
      reap(arg, u);
      release(u);
      return {0, 0};
    }
    if (unplugged) return {-1, ENODEV};
    if (flying.empty()) return {-1, EAGAIN};
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    if (sequence >= static_cast<std::uint64_t>(elapsed * o.rate_hz) + 1) return {-1, EAGAIN};
    Urb u = flying.front();
    flying.pop_front();
    usbdevfs_urb* urb = as_urb(u.urb);
    if (stall && sequence >= *stall) {
      stall.reset();
      urb->status = -EPIPE;
      urb->actual_length = 0;
    } else {
      if (lose > 0 && sequence >= lose_at) {
        sequence += static_cast<std::uint64_t>(lose);
        lose = 0;
      }
      Profile p = o.profiles[sequence % o.profiles.size()];
      p.sequence = static_cast<std::uint32_t>(sequence);
      p.timestamp_us = static_cast<std::uint64_t>(sequence * 1e6 / o.rate_hz);
      p.end_of_sweep = o.sweep_length > 0 && (sequence + 1) % static_cast<std::uint64_t>(o.sweep_length) == 0;
      std::vector<std::uint8_t> packet = encode_profile(p, o.scale_mm, 0.f, 0.f);
      if (truncate && p.sequence >= *truncate) {
        truncate.reset();
        packet.resize(packet.size() / 2);
      }
      const std::size_t n = std::min<std::size_t>(packet.size(), static_cast<std::size_t>(urb->buffer_length));
      std::memcpy(u.buffer->data, packet.data(), n);
      urb->actual_length = static_cast<int>(n);
      urb->status = 0;
      ++sequence;
      ++sent;
    }
    reap(arg, u);
    release(u);
    return {0, 0};
  }

  std::pair<int, int> handle(unsigned long request, UMockdevIoctlData* arg) {
    std::lock_guard<std::mutex> lock(mutex);
    switch (request) {
      case USBDEVFS_GET_CAPABILITIES: {
        UMockdevIoctlData* d = umockdev_ioctl_data_resolve(arg, 0, sizeof(std::uint32_t), nullptr);
        *reinterpret_cast<std::uint32_t*>(d->data) = USBDEVFS_CAP_BULK_CONTINUATION | USBDEVFS_CAP_NO_PACKET_SIZE_LIM |
                                                     USBDEVFS_CAP_REAP_AFTER_DISCONNECT | USBDEVFS_CAP_ZERO_PACKET;
        umockdev_ioctl_data_unref(d);
        return {0, 0};
      }
      case USBDEVFS_CLEAR_HALT:
        if (unplugged) return {-1, ENODEV};
        ++halts;
        return {0, 0};
      case USBDEVFS_CLAIMINTERFACE:
      case USBDEVFS_DISCONNECT_CLAIM:
        if (o.busy) return {-1, EBUSY};
        return unplugged ? std::pair{-1, ENODEV} : std::pair{0, 0};
      case USBDEVFS_RELEASEINTERFACE:
      case USBDEVFS_RESET:
      case USBDEVFS_RESETEP:
      case USBDEVFS_SETINTERFACE:
        return unplugged && request != USBDEVFS_RELEASEINTERFACE ? std::pair{-1, ENODEV} : std::pair{0, 0};
      case USBDEVFS_GETDRIVER: return {-1, ENODATA};  // no kernel driver bound
      case USBDEVFS_SUBMITURB: {
        if (unplugged) return {-1, ENODEV};
        UMockdevIoctlData* urb = umockdev_ioctl_data_resolve(arg, 0, sizeof(usbdevfs_urb), nullptr);
        usbdevfs_urb* u = as_urb(urb);
        if (u->type != USBDEVFS_URB_TYPE_BULK || !(u->endpoint & 0x80)) {
          umockdev_ioctl_data_unref(urb);
          return {-1, EINVAL};
        }
        UMockdevIoctlData* buf = umockdev_ioctl_data_resolve(urb, offsetof(usbdevfs_urb, buffer),
                                                             static_cast<std::size_t>(u->buffer_length), nullptr);
        flying.push_back({urb, buf});
        return {0, 0};
      }
      case USBDEVFS_REAPURB:
      case USBDEVFS_REAPURBNDELAY: return reap_next(arg);
      case USBDEVFS_DISCARDURB: {
        const auto addr = reinterpret_cast<gulong>(*reinterpret_cast<void**>(arg->data));
        for (auto it = flying.begin(); it != flying.end(); ++it)
          if (it->urb->client_addr == addr) {
            discarded.push_back(*it);
            flying.erase(it);
            return {0, 0};
          }
        return {-1, EINVAL};
      }
      default: return {-1, ENOTTY};
    }
  }
};

namespace {

gboolean on_ioctl(UMockdevIoctlBase*, UMockdevIoctlClient* client, gpointer self) {
  auto* s = static_cast<MockLaser::State*>(self);
  const auto [result, err] = s->handle(umockdev_ioctl_client_get_request(client), umockdev_ioctl_client_get_arg(client));
  umockdev_ioctl_client_complete(client, result, err);
  return TRUE;
}

Profile flat_profile() {
  Profile p;
  for (int i = 0; i < 256; ++i) {
    p.x_mm.push_back(-20.f + 40.f * i / 255.f);
    p.z_mm.push_back(100.f + 0.01f * i);
    p.intensity.push_back(200);
  }
  return p;
}

}  // namespace

MockLaser::MockLaser(MockLaserOptions options) : state_(std::make_unique<State>()) {
  State& s = *state_;
  s.o = std::move(options);
  if (s.o.profiles.empty()) s.o.profiles = {flat_profile()};
  s.testbed = umockdev_testbed_new();
  s.handler = umockdev_ioctl_base_new();
  g_signal_connect(s.handler, "handle-ioctl", G_CALLBACK(on_ioctl), &s);
  GError* error = nullptr;
  // Attach first, so the node answers as soon as the device appears.
  umockdev_testbed_attach_ioctl(s.testbed, "/dev/bus/usb/001/002", s.handler, &error);
  // Descriptors: device (vendor-specific, one configuration), configuration, one interface
  // (class 0xff) with one bulk IN endpoint 0x81 of 512-byte packets.
  const std::string descriptors =
      fmt::format("12010002000000 40{:02x}{:02x}{:02x}{:02x}000100000001"
                  "09021900010100803209040000 01ff0000000705810200 0200",
                  s.o.vendor & 0xff, s.o.vendor >> 8, s.o.product & 0xff, s.o.product >> 8);
  std::string hex;
  for (char c : descriptors)
    if (c != ' ') hex += c;
  const std::string dev = fmt::format(
      "P: /devices/pci0000:00/usb1/1-1\nN: bus/usb/001/002\nE: SUBSYSTEM=usb\nE: DEVTYPE=usb_device\n"
      "E: DRIVER=usb\nE: BUSNUM=001\nE: DEVNUM=002\nE: DEVNAME=/dev/bus/usb/001/002\n"
      "A: busnum=1\\n\nA: devnum=2\\n\nA: bConfigurationValue=1\\n\nA: speed=480\\n\nH: descriptors={}\n",
      hex);
  if (!error) umockdev_testbed_add_from_string(s.testbed, dev.c_str(), &error);
  if (error) {
    const std::string what = error->message;
    g_error_free(error);
    throw std::runtime_error("MockLaser: " + what);
  }
}

MockLaser::~MockLaser() {
  {
    std::lock_guard<std::mutex> lock(state_->mutex);
    for (auto& u : state_->flying) State::release(u);
    for (auto& u : state_->discarded) State::release(u);
    state_->flying.clear();
    state_->discarded.clear();
  }
  g_clear_object(&state_->handler);
  g_clear_object(&state_->testbed);
}

void MockLaser::unplug() {
  {
    std::lock_guard<std::mutex> lock(state_->mutex);
    state_->unplugged = true;
  }
  umockdev_testbed_uevent(state_->testbed, "/sys/devices/pci0000:00/usb1/1-1", "remove");
}
void MockLaser::stall_at(std::uint64_t sequence) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->stall = sequence;
}
void MockLaser::truncate_at(std::uint64_t sequence) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->truncate = sequence;
}
void MockLaser::lose(std::uint64_t at_sequence, int n) {
  std::lock_guard<std::mutex> lock(state_->mutex);
  state_->lose_at = at_sequence;
  state_->lose = n;
}
std::uint64_t MockLaser::profiles_sent() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->sent;
}
std::size_t MockLaser::urbs_pending() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->flying.size() + state_->discarded.size();
}
std::uint64_t MockLaser::halts_cleared() const {
  std::lock_guard<std::mutex> lock(state_->mutex);
  return state_->halts;
}

}  // namespace s2c::emulation
