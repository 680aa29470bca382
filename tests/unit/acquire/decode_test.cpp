#include <random>

#include <gtest/gtest.h>

#include "s2c/acquire/decode.h"

namespace s2c {
namespace {

std::vector<std::uint8_t> z16_bytes(int w, int h, int stride) {
  std::vector<std::uint8_t> b(static_cast<std::size_t>(stride) * h, 0xee);
  for (int v = 0; v < h; ++v)
    for (int u = 0; u < w; ++u) {
      const std::uint16_t value = static_cast<std::uint16_t>(1000 * v + u);
      b[static_cast<std::size_t>(v) * stride + 2 * u] = static_cast<std::uint8_t>(value);
      b[static_cast<std::size_t>(v) * stride + 2 * u + 1] = static_cast<std::uint8_t>(value >> 8);
    }
  return b;
}

TEST(DecodeZ16, ReadsLittleEndianRowsHonouringTheStride) {
  const auto b = z16_bytes(5, 3, 16);  // 6 bytes of padding per row
  const auto img = decode_z16(b.data(), b.size(), 5, 3, 16);
  ASSERT_TRUE(img);
  EXPECT_EQ(img->at(4, 2), 2004);
  EXPECT_EQ(img->at(0, 1), 1000);
}

TEST(DecodeZ16, RefusesAShortBuffer) {
  const auto b = z16_bytes(5, 3, 10);
  DecodeError e{};
  EXPECT_FALSE(decode_z16(b.data(), b.size() - 1, 5, 3, 10, &e));
  EXPECT_EQ(e, DecodeError::short_buffer);
  // The last row needs no padding after it.
  EXPECT_TRUE(decode_z16(z16_bytes(5, 3, 16).data(), 16 * 2 + 10, 5, 3, 16));
  EXPECT_FALSE(decode_z16(b.data(), b.size(), 5, 3, 8, &e));  // stride below the row
  EXPECT_EQ(e, DecodeError::bad_header);
}

Profile sample_profile() {
  Profile p;
  p.sequence = 0xfffffffe;
  p.timestamp_us = 0x123456789aULL;
  p.end_of_sweep = true;
  for (int i = 0; i < 100; ++i) {
    p.x_mm.push_back(-10.f + 0.2f * i);
    p.z_mm.push_back(i % 7 ? 150.f + 0.05f * i : 0.f);
    p.intensity.push_back(static_cast<std::uint8_t>(i));
  }
  return p;
}

TEST(ProfilePacket, RoundTripsWithinTheQuantisation) {
  const Profile p = sample_profile();
  const auto bytes = encode_profile(p, 0.01f, 0.f, 100.f);
  EXPECT_EQ(bytes.size(), profile_packet_bytes(100));
  DecodeError e{};
  const auto q = decode_profile(bytes.data(), bytes.size(), &e);
  ASSERT_TRUE(q) << to_string(e);
  EXPECT_EQ(q->sequence, p.sequence);
  EXPECT_EQ(q->timestamp_us, p.timestamp_us);
  EXPECT_TRUE(q->end_of_sweep);
  ASSERT_EQ(q->x_mm.size(), 100u);
  for (std::size_t i = 0; i < 100; ++i) {
    EXPECT_NEAR(q->x_mm[i], p.x_mm[i], 0.0051);
    EXPECT_NEAR(q->z_mm[i], p.z_mm[i], 0.0051);
    EXPECT_EQ(q->z_mm[i] == 0, p.z_mm[i] == 0) << "no-return points stay no-return";
    EXPECT_EQ(q->intensity[i], p.intensity[i]);
  }
}

TEST(ProfilePacket, RejectsMalformedPacketsWithTheReason) {
  auto bytes = encode_profile(sample_profile(), 0.01f, 0.f, 0.f);
  DecodeError e{};
  EXPECT_FALSE(decode_profile(bytes.data(), bytes.size() - 1, &e));
  EXPECT_EQ(e, DecodeError::short_buffer);
  EXPECT_FALSE(decode_profile(bytes.data(), 20, &e));
  EXPECT_EQ(e, DecodeError::short_buffer);
  auto bad = bytes;
  bad[0] ^= 0xff;
  EXPECT_FALSE(decode_profile(bad.data(), bad.size(), &e));
  EXPECT_EQ(e, DecodeError::bad_magic);
  bad = bytes;
  bad[4] = 2;
  EXPECT_FALSE(decode_profile(bad.data(), bad.size(), &e));
  EXPECT_EQ(e, DecodeError::bad_version);
  bad = bytes;
  bad[20] = 0xff;
  bad[21] = 0xff;  // 65535 points
  EXPECT_FALSE(decode_profile(bad.data(), bad.size(), &e));
  EXPECT_EQ(e, DecodeError::too_many_points);
  bad = bytes;
  bad[24] = bad[25] = bad[26] = 0;
  bad[27] = 0x80;  // scale −0
  EXPECT_FALSE(decode_profile(bad.data(), bad.size(), &e));
  EXPECT_EQ(e, DecodeError::bad_header);
}

TEST(ProfilePacket, RandomBytesNeverCrashOrOverread) {
  std::mt19937 rng(7);
  const auto good = encode_profile(sample_profile(), 0.01f, 0.f, 0.f);
  for (int trial = 0; trial < 20000; ++trial) {
    std::vector<std::uint8_t> b = good;
    b.resize(rng() % (good.size() + 8));
    for (int k = 0; k < 4 && !b.empty(); ++k) b[rng() % b.size()] = static_cast<std::uint8_t>(rng());
    // Exact-size heap copy: AddressSanitizer builds catch any read past the end.
    std::unique_ptr<std::uint8_t[]> exact(new std::uint8_t[b.size() + 1]);
    std::copy(b.begin(), b.end(), exact.get());
    const auto p = decode_profile(exact.get(), b.size());
    if (p) {
      EXPECT_LE(profile_packet_bytes(p->x_mm.size()), b.size());
    }
  }
}

StreamInfo fan(int columns) {
  StreamInfo info;
  info.sensor = Sensor::laser;
  info.width = columns;
  info.depth_unit_mm = 0.01;
  info.camera_matrix << 100, 0, (columns - 1) / 2.0, 0, 100, 0, 0, 0, 1;
  info.profile_step_mm = 0.5;
  return info;
}

Profile ray_profile(std::uint32_t seq, std::vector<std::pair<float, float>> xz, bool end = false) {
  Profile p;
  p.sequence = seq;
  p.timestamp_us = seq * 1000ULL;
  p.end_of_sweep = end;
  for (auto [x, z] : xz) {
    p.x_mm.push_back(x);
    p.z_mm.push_back(z);
    p.intensity.push_back(1);
  }
  return p;
}

TEST(SweepAssembler, PutsEachPointOnItsRaysColumnAndTheNearestWins) {
  SweepAssembler a(fan(21), 2);
  // Column u = 100·x/z + 10: x = 1, z = 50 → u = 12; x = 2.2, z = 110 → u = 12 too, farther.
  EXPECT_TRUE(a.add(ray_profile(0, {{1.f, 50.f}, {2.2f, 110.f}, {0.f, 80.f}})).empty());
  const auto done = a.add(ray_profile(1, {{-5.f, 50.f}, {100.f, 10.f}}));  // the second is outside the fan
  ASSERT_EQ(done.size(), 1u);
  const DepthImage& img = done[0].image;
  EXPECT_EQ(img.width, 21);
  EXPECT_EQ(img.height, 2);
  EXPECT_EQ(img.at(12, 0), 5000);  // 50 mm in 0.01 mm counts: the nearer return
  EXPECT_EQ(img.at(10, 0), 8000);
  EXPECT_EQ(img.at(0, 1), 5000);   // u = 100·(−5)/50 + 10 = 0
  EXPECT_EQ(a.points_outside(), 1u);
  EXPECT_DOUBLE_EQ(done[0].timestamp, 0.0);
}

TEST(SweepAssembler, LostProfilesBecomeEmptyRowsAndAreCounted) {
  SweepAssembler a(fan(21), 4);
  EXPECT_TRUE(a.add(ray_profile(10, {{0.f, 50.f}})).empty());
  const auto done = a.add(ray_profile(13, {{0.f, 60.f}}));  // 11 and 12 lost
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(a.sequence_gaps(), 2u);
  EXPECT_EQ(done[0].image.at(10, 0), 5000);
  EXPECT_EQ(done[0].image.at(10, 1), 0);
  EXPECT_EQ(done[0].image.at(10, 2), 0);
  EXPECT_EQ(done[0].image.at(10, 3), 6000);
}

TEST(SweepAssembler, EndOfSweepFlagClosesASweepEarlyAtFullHeight) {
  SweepAssembler a(fan(21), 10);
  EXPECT_TRUE(a.add(ray_profile(0, {{0.f, 50.f}})).empty());
  const auto done = a.add(ray_profile(1, {{0.f, 50.f}}, true));
  ASSERT_EQ(done.size(), 1u);
  EXPECT_EQ(done[0].image.height, 10);  // one frame size per stream
  EXPECT_EQ(done[0].image.at(10, 1), 5000);
  EXPECT_EQ(done[0].image.at(10, 2), 0);
  EXPECT_FALSE(a.flush());  // nothing pending
  a.add(ray_profile(2, {{0.f, 50.f}}));
  const auto partial = a.flush();
  ASSERT_TRUE(partial);
  EXPECT_EQ(partial->image.at(10, 0), 5000);
  EXPECT_EQ(partial->sequence, 1u);
}

}  // namespace
}  // namespace s2c
