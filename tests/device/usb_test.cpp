// The USB laser source against an emulated scanner (umockdev usbdevfs handler, libusb async).
#include <cmath>
#include <thread>

#include <gtest/gtest.h>

#include "device_test_util.h"
#include "mock_laser.h"
#include "s2c/acquire/acquire.h"
#include "s2c/acquire/sources.h"

namespace s2c {
namespace {

class UsbDevice : public test::EmulatedDevice {};

using emulation::MockLaser;
using emulation::MockLaserOptions;

std::unique_ptr<FrameSource> laser_source(std::uint16_t pid = 0x0001, int rows = 20) {
  UsbLaserOptions o;
  o.vendor = 0x1209;
  o.product = pid;
  o.calibration = test::laser_calibration();
  o.profiles_per_sweep = rows;
  o.transfers = 6;
  o.max_points = 1024;
  return make_usb_laser_source(o);
}

/// A profile of a tilted plane: x from −20 to 20 mm, z = 100 + 0.1·x mm.
Profile plane_profile() {
  Profile p;
  for (int i = 0; i < 400; ++i) {
    const float x = -20.f + 40.f * i / 399.f;
    p.x_mm.push_back(x);
    p.z_mm.push_back(100.f + 0.1f * x);
    p.intensity.push_back(128);
  }
  return p;
}

TEST_F(UsbDevice, StreamsProfilesIntoSweepsThatDeprojectOntoTheSurface) {
  MockLaserOptions mo;
  mo.profiles = {plane_profile()};
  mo.rate_hz = 4000;
  MockLaser laser(mo);
  auto src = laser_source();
  const auto out = test::scratch_dir() / "rec";
  AcquireOptions ao;
  ao.frames = 3;
  const AcquireResult r = acquire(*src, out, ao);
  ASSERT_FALSE(r.failure) << *r.failure;
  EXPECT_EQ(r.record.kept, 3u);
  EXPECT_EQ(r.source.sequence_gaps + r.source.dropped_short + r.source.dropped_error, 0u);
  const Stream s = read_stream(out);
  EXPECT_EQ(s.info.sensor, Sensor::laser);
  EXPECT_EQ(s.info.height, 20);
  EXPECT_EQ(s.info.device, "usb:1209:0001");
  const DepthImage sweep = read_frame(s, 1);
  const std::vector<Eigen::Vector3d> pts = Deprojector(s.info).sensor_points(sweep);
  ASSERT_GT(pts.size(), 20u * 300u);  // every row measured, most columns hit
  double worst = 0;
  for (const auto& p : pts) worst = std::max(worst, std::abs(p.z() - (100 + 0.1 * p.x())));
  // Packet quantisation (0.01 mm) + depth unit (0.01 mm) + column rounding (0.5 px · 0.1 mm/px · 0.1 slope).
  EXPECT_LT(worst, 0.03);
  EXPECT_NEAR(pts.back().y() - pts.front().y(), 19 * 0.1, 1e-9);  // rows advance by the profile step
}

TEST_F(UsbDevice, ShortPacketIsDroppedAndItsSequenceCountedAsAGap) {
  MockLaserOptions mo;
  mo.rate_hz = 4000;
  MockLaser laser(mo);
  laser.truncate_at(7);
  auto src = laser_source();
  AcquireOptions ao;
  ao.frames = 2;
  const AcquireResult r = acquire(*src, test::scratch_dir() / "rec", ao);
  ASSERT_FALSE(r.failure) << *r.failure;
  EXPECT_EQ(r.source.dropped_short, 1u);
  EXPECT_EQ(r.source.sequence_gaps, 1u);
}

TEST_F(UsbDevice, StallIsClearedAndStreamingGoesOn) {
  MockLaserOptions mo;
  mo.rate_hz = 4000;
  MockLaser laser(mo);
  laser.stall_at(10);
  auto src = laser_source();
  AcquireOptions ao;
  ao.frames = 3;
  const AcquireResult r = acquire(*src, test::scratch_dir() / "rec", ao);
  ASSERT_FALSE(r.failure) << *r.failure;
  EXPECT_EQ(r.source.stalls, 1u);
  EXPECT_EQ(laser.halts_cleared(), 1u);
  EXPECT_EQ(r.record.kept, 3u);
  EXPECT_EQ(r.source.sequence_gaps, 0u);
}

TEST_F(UsbDevice, LostProfilesLeaveEmptyRowsSoTheTravelStaysRight) {
  MockLaserOptions mo;
  mo.rate_hz = 4000;
  MockLaser laser(mo);
  laser.lose(25, 3);  // profiles 25..27 never arrive: rows 5..7 of the second sweep
  auto src = laser_source();
  const auto out = test::scratch_dir() / "rec";
  AcquireOptions ao;
  ao.frames = 3;
  const AcquireResult r = acquire(*src, out, ao);
  ASSERT_FALSE(r.failure) << *r.failure;
  EXPECT_EQ(r.source.sequence_gaps, 3u);
  const Stream s = read_stream(out);
  const DepthImage sweep = read_frame(s, 1);
  for (int v = 0; v < sweep.height; ++v) {
    int hits = 0;
    for (int u = 0; u < sweep.width; ++u) hits += sweep.at(u, v) != 0;
    if (v >= 5 && v <= 7) EXPECT_EQ(hits, 0) << "row " << v;
    else EXPECT_GT(hits, 100) << "row " << v;
  }
}

TEST_F(UsbDevice, UnplugKeepsTheSweepsSoFar) {
  MockLaserOptions mo;
  mo.rate_hz = 4000;
  MockLaser laser(mo);
  auto src = laser_source();
  const auto out = test::scratch_dir() / "rec";
  AcquireOptions ao;
  ao.on_frame = [&](std::uint64_t n) {
    if (n == 2) laser.unplug();
  };
  const AcquireResult r = acquire(*src, out, ao);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.exit_code, kExitDevice);
  EXPECT_NE(r.failure->find("vanished"), std::string::npos) << *r.failure;
  const Stream s = read_stream(out);
  EXPECT_GE(s.frames.size(), 2u);  // the 2 sweeps, and the partial one the unplug cut
  EXPECT_EQ(s.frames.size(), r.record.kept);
}

TEST_F(UsbDevice, StopCancelsAndDrainsEveryTransfer) {
  MockLaserOptions mo;
  mo.rate_hz = 1;  // the transfers wait in the device
  MockLaser laser(mo);
  {
    auto src = laser_source();
    src->open();
    src->start();
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    EXPECT_EQ(laser.urbs_pending(), 6u);  // all in flight at once (one came back with the first profile and went out again)
    src->stop();
    // The one profile sent so far is kept: stop hands out the partial sweep, then ends.
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(1);
    EXPECT_TRUE(src->next(deadline).has_value());
    EXPECT_FALSE(src->next(deadline).has_value());
  }  // destroyed: cancel, wait for every callback, release
  EXPECT_EQ(laser.urbs_pending(), 0u);
}

TEST_F(UsbDevice, BusyDeviceSaysSo) {
  MockLaserOptions mo;
  mo.busy = true;
  MockLaser laser(mo);
  auto src = laser_source();
  try {
    src->open();
    FAIL();
  } catch (const DeviceFailure& e) {
    EXPECT_EQ(e.fault, DeviceFault::busy);
    EXPECT_NE(std::string(e.what()).find("claimed by another program"), std::string::npos) << e.what();
  }
}

TEST_F(UsbDevice, UnknownDeviceIsNamedInTheMessage) {
  MockLaser laser({});
  auto src = laser_source(0x0bad);
  try {
    src->open();
    FAIL();
  } catch (const DeviceFailure& e) {
    EXPECT_EQ(e.fault, DeviceFault::not_found);
    EXPECT_NE(std::string(e.what()).find("1209:0bad"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace s2c
