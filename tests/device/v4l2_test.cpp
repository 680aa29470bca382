// The V4L2 source against an emulated Z16 camera (umockdev ioctl handler, mmap'ed node file).
#include <linux/videodev2.h>

#include <thread>

#include <gtest/gtest.h>

#include "device_test_util.h"
#include "mock_camera.h"
#include "s2c/acquire/acquire.h"
#include "s2c/acquire/sources.h"

namespace s2c {
namespace {

class V4l2Device : public test::EmulatedDevice {};

using emulation::MockCamera;
using emulation::MockCameraOptions;
using namespace std::chrono_literals;

std::unique_ptr<FrameSource> camera_source(const MockCamera& cam, StreamInfo calibration = test::depth_calibration()) {
  V4l2Options o;
  o.device = cam.device();
  o.calibration = calibration;
  return make_v4l2_source(o);
}

DepthImage ramp(int w, int h, int offset) {
  DepthImage d{w, h, std::vector<std::uint16_t>(static_cast<std::size_t>(w) * h)};
  for (std::size_t i = 0; i < d.data.size(); ++i) d.data[i] = static_cast<std::uint16_t>(offset + i % 5000);
  return d;
}

TEST_F(V4l2Device, NegotiatesZ16AmongOfferedFormats) {
  MockCameraOptions mo;
  mo.formats = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_Z16};
  MockCamera cam(mo);
  auto src = camera_source(cam);
  src->open();
  EXPECT_EQ(src->info().width, 640);
  EXPECT_EQ(src->info().height, 480);
  EXPECT_EQ(src->info().sensor, Sensor::depth);
  EXPECT_DOUBLE_EQ(src->info().depth_unit_mm, 0.2);  // from the calibration, never from V4L2
  EXPECT_EQ(src->info().device, "v4l2:/dev/video0");
}

TEST_F(V4l2Device, RefusesACameraWithoutDepthFormatListingWhatItOffers) {
  MockCameraOptions mo;
  mo.formats = {V4L2_PIX_FMT_YUYV, V4L2_PIX_FMT_MJPEG};
  MockCamera cam(mo);
  auto src = camera_source(cam);
  try {
    src->open();
    FAIL() << "a YUYV/MJPG camera was accepted";
  } catch (const DeviceFailure& e) {
    EXPECT_EQ(e.fault, DeviceFault::wrong_format);
    const std::string what = e.what();
    EXPECT_NE(what.find("YUYV"), std::string::npos) << what;
    EXPECT_NE(what.find("MJPG"), std::string::npos) << what;
    EXPECT_NE(what.find("640x480"), std::string::npos) << what;
  }
}

TEST_F(V4l2Device, RefusesIntrinsicsForAnotherResolution) {
  MockCamera cam({});
  auto src = camera_source(cam, test::depth_calibration(320, 240));
  try {
    src->open();
    FAIL();
  } catch (const DeviceFailure& e) {
    EXPECT_EQ(e.fault, DeviceFault::wrong_format);
    EXPECT_NE(std::string(e.what()).find("calibration is for 320x240"), std::string::npos) << e.what();
  }
}

TEST_F(V4l2Device, RecordsARealDepthFrameByteForByte) {
  MockCameraOptions mo;
  mo.frames = {test::real_tum_frame(), ramp(640, 480, 7000)};
  mo.fps = 60;
  MockCamera cam(mo);
  auto src = camera_source(cam);
  const auto out = test::scratch_dir() / "rec";
  AcquireOptions ao;
  ao.frames = 6;
  const AcquireResult r = acquire(*src, out, ao);
  ASSERT_FALSE(r.failure) << *r.failure;
  EXPECT_EQ(r.record.kept, 6u);
  const Stream s = read_stream(out);
  ASSERT_EQ(s.frames.size(), 6u);
  EXPECT_EQ(s.info.device, "v4l2:/dev/video0");
  for (std::size_t i = 0; i < 6; ++i) EXPECT_EQ(read_frame(s, i).data, mo.frames[i % 2].data) << "frame " << i;
  EXPECT_EQ(r.source.dropped_short + r.source.dropped_error + r.source.sequence_gaps, 0u);
  EXPECT_GT(s.frames[1].timestamp, s.frames[0].timestamp);
}

TEST_F(V4l2Device, DropsAndCountsShortAndErrorFrames) {
  MockCameraOptions mo;
  mo.fps = 200;
  MockCamera cam(mo);
  cam.short_frames(2);
  cam.error_frames(1);
  auto src = camera_source(cam);
  const auto out = test::scratch_dir() / "rec";
  AcquireOptions ao;
  ao.frames = 5;
  const AcquireResult r = acquire(*src, out, ao);
  ASSERT_FALSE(r.failure) << *r.failure;
  EXPECT_EQ(r.record.kept, 5u);
  // Frame 0 is flagged bad (and short), frame 1 is short: one of each counted, none recorded.
  EXPECT_EQ(r.source.dropped_error, 1u);
  EXPECT_EQ(r.source.dropped_short, 1u);
  const Stream s = read_stream(out);
  for (std::size_t i = 0; i < s.frames.size(); ++i) EXPECT_EQ(read_frame(s, i).data.size(), 640u * 480u);
}

TEST_F(V4l2Device, UnplugKeepsTheFramesSoFarAsAValidStream) {
  MockCameraOptions mo;
  mo.fps = 100;
  MockCamera cam(mo);
  auto src = camera_source(cam);
  const auto out = test::scratch_dir() / "rec";
  AcquireOptions ao;
  ao.on_frame = [&](std::uint64_t n) {
    if (n == 4) cam.unplug();
  };
  const AcquireResult r = acquire(*src, out, ao);
  ASSERT_TRUE(r.failure);
  EXPECT_EQ(r.exit_code, kExitDevice);
  EXPECT_NE(r.failure->find("vanished"), std::string::npos) << *r.failure;
  EXPECT_NE(r.failure->find("4 complete frames kept"), std::string::npos) << *r.failure;
  EXPECT_EQ(read_stream(out).frames.size(), 4u);
}

TEST_F(V4l2Device, TimesOutWhenNoFrameComes) {
  MockCameraOptions mo;
  mo.fps = 0.01;  // first frame at once, the next after 100 s
  MockCamera cam(mo);
  auto src = camera_source(cam);
  AcquireOptions ao;
  ao.timeout_s = 0.3;
  const AcquireResult r = acquire(*src, test::scratch_dir() / "rec", ao);
  ASSERT_TRUE(r.failure);
  EXPECT_NE(r.failure->find("no frames for"), std::string::npos) << *r.failure;
  EXPECT_EQ(r.record.kept, 1u);
}

TEST_F(V4l2Device, StopFromAnotherThreadEndsCleanly) {
  MockCameraOptions mo;
  mo.fps = 100;
  MockCamera cam(mo);
  auto src = camera_source(cam);
  std::thread stopper([&] {
    std::this_thread::sleep_for(150ms);
    src->stop();
  });
  const AcquireResult r = acquire(*src, test::scratch_dir() / "rec", {});
  stopper.join();
  EXPECT_FALSE(r.failure);
  EXPECT_GE(r.record.kept, 3u);
}

TEST_F(V4l2Device, NoFrameDroppedAt30Fps) {
  MockCameraOptions mo;
  mo.fps = 30;
  mo.frames = {test::real_tum_frame()};
  MockCamera cam(mo);
  auto src = camera_source(cam);
  AcquireOptions ao;
  ao.frames = 45;
  const AcquireResult r = acquire(*src, test::scratch_dir() / "rec", ao);
  ASSERT_FALSE(r.failure) << *r.failure;
  EXPECT_EQ(r.record.kept, 45u);
  EXPECT_EQ(cam.frames_dropped(), 0u);
  EXPECT_EQ(r.source.sequence_gaps, 0u);
  EXPECT_EQ(r.record.dropped_queue, 0u);
}

}  // namespace
}  // namespace s2c
