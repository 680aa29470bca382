// Recording onto a full disk: /dev/full answers every write with ENOSPC.
#include <fcntl.h>

#include <gtest/gtest.h>

#include "device_test_util.h"
#include "s2c/acquire/recorder.h"

namespace s2c {
namespace {

TEST(DiskFull, KeepsEveryCompleteFrameAndFinalizesAValidStream) {
  const auto out = test::scratch_dir() / "rec";
  RecorderOptions ro;
  int opened = 0;
  // Frames 0-2 go to the disk, then it is full: the 4th frame's file is /dev/full.
  ro.open_frame_file = [&](const std::filesystem::path& p) {
    const bool full = ++opened > 3;
    return ::open(full ? "/dev/full" : p.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  };
  const DepthImage img = test::real_tum_frame();
  Recorder rec(out, test::depth_calibration(), ro);
  int accepted = 0;
  for (int i = 0; i < 10; ++i) {
    Frame f;
    f.sequence = static_cast<std::uint64_t>(i);
    f.timestamp = i / 30.0;
    f.image = img;
    accepted += rec.add(std::move(f));
  }
  const RecordSummary sum = rec.finish();
  ASSERT_TRUE(sum.write_error);
  EXPECT_NE(sum.write_error->find("No space left on device"), std::string::npos) << *sum.write_error;
  EXPECT_EQ(sum.kept, 3u);
  const Stream s = read_stream(out);
  ASSERT_EQ(s.frames.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(read_frame(s, i).data, img.data);
  EXPECT_FALSE(std::filesystem::exists(out / "depth/000003.png"));
  EXPECT_GE(accepted, 4);
}

TEST(DiskFull, RefusesToRecordOverAnExistingFolder) {
  const auto out = test::scratch_dir() / "rec";
  std::filesystem::create_directories(out);
  test::write_text(out / "precious.txt", "keep me");
  EXPECT_THROW(Recorder(out, test::depth_calibration()), InvalidInput);
  EXPECT_TRUE(std::filesystem::exists(out / "precious.txt"));
}

}  // namespace
}  // namespace s2c
