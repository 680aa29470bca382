#pragma once
/// \file An emulated USB laser line scanner (umockdev): a usbdevfs device that answers bulk IN
/// URBs with profile packets (docs/formats.md), at a given rate. Faults on request: endpoint
/// STALL, a short (truncated) packet, lost profiles (sequence gap), unplug.
#include <cstdint>
#include <memory>
#include <vector>

#include "s2c/acquire/decode.h"

namespace s2c::emulation {

struct MockLaserOptions {
  std::uint16_t vendor = 0x1209, product = 0x0001;  // pid.codes' test id
  std::vector<Profile> profiles;   ///< sent in turn (cycled, sequence numbers keep counting)
  double rate_hz = 1000;           ///< profiles per second
  int sweep_length = 0;            ///< set the end-of-sweep flag every N profiles (0: never)
  float scale_mm = 0.01f;          ///< packet quantisation
  bool busy = false;               ///< another program holds the interface (claim fails EBUSY)
};

class MockLaser {
 public:
  explicit MockLaser(MockLaserOptions options);
  ~MockLaser();
  MockLaser(const MockLaser&) = delete;
  MockLaser& operator=(const MockLaser&) = delete;

  void unplug();                   ///< URBs fail with ENODEV and a "remove" uevent is sent
  void stall_at(std::uint64_t sequence);     ///< that URB ends with -EPIPE (endpoint halted)
  void truncate_at(std::uint64_t sequence);  ///< that profile arrives cut in half
  void lose(std::uint64_t at_sequence, int n);  ///< profiles at_sequence.. are numbered but never sent
  std::uint64_t profiles_sent() const;
  std::uint64_t halts_cleared() const;
  std::size_t urbs_pending() const;  ///< submitted and neither reaped nor discarded-and-reaped

  struct State;

 private:
  std::unique_ptr<State> state_;
};

}  // namespace s2c::emulation
