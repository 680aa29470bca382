#include "s2c/acquire/decode.h"

#include <algorithm>
#include <cmath>
#include <cstring>

namespace s2c {
namespace {

constexpr bool kLittleEndianHost = __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__;

// Little-endian field readers: the packet layout is little-endian whatever the host.
std::uint16_t u16(const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] | p[1] << 8); }
std::uint32_t u32(const std::uint8_t* p) { return u16(p) | static_cast<std::uint32_t>(u16(p + 2)) << 16; }
std::uint64_t u64(const std::uint8_t* p) { return u32(p) | static_cast<std::uint64_t>(u32(p + 4)) << 32; }
float f32(const std::uint8_t* p) {
  const std::uint32_t bits = u32(p);
  float f;
  std::memcpy(&f, &bits, 4);
  return f;
}
void put16(std::vector<std::uint8_t>& b, std::uint16_t v) {
  b.push_back(static_cast<std::uint8_t>(v));
  b.push_back(static_cast<std::uint8_t>(v >> 8));
}
void put32(std::vector<std::uint8_t>& b, std::uint32_t v) {
  put16(b, static_cast<std::uint16_t>(v));
  put16(b, static_cast<std::uint16_t>(v >> 16));
}
void putf(std::vector<std::uint8_t>& b, float f) {
  std::uint32_t bits;
  std::memcpy(&bits, &f, 4);
  put32(b, bits);
}

template <class T>
std::optional<T> fail(DecodeError* out, DecodeError e) {
  if (out) *out = e;
  return std::nullopt;
}

}  // namespace

const char* to_string(DecodeError e) {
  switch (e) {
    case DecodeError::none: return "ok";
    case DecodeError::short_buffer: return "short buffer";
    case DecodeError::bad_magic: return "bad magic (not an S2CL profile packet)";
    case DecodeError::bad_version: return "unsupported packet version";
    case DecodeError::bad_header: return "inconsistent header";
    case DecodeError::too_many_points: return "point count above the limit";
  }
  return "?";
}

std::optional<DepthImage> decode_z16(const std::uint8_t* data, std::size_t size, int width, int height,
                                     int bytes_per_line, DecodeError* error) {
  if (error) *error = DecodeError::none;
  if (width <= 0 || height <= 0 || bytes_per_line < 2 * width) return fail<DepthImage>(error, DecodeError::bad_header);
  const std::size_t need = static_cast<std::size_t>(bytes_per_line) * (height - 1) + 2 * static_cast<std::size_t>(width);
  if (!data || size < need) return fail<DepthImage>(error, DecodeError::short_buffer);
  DepthImage d;
  d.width = width;
  d.height = height;
  d.data.resize(static_cast<std::size_t>(width) * height);
  for (int v = 0; v < height; ++v) {
    const std::uint8_t* row = data + static_cast<std::size_t>(v) * bytes_per_line;
    std::uint16_t* out = &d.data[static_cast<std::size_t>(v) * width];
    if constexpr (kLittleEndianHost) {
      std::memcpy(out, row, 2 * static_cast<std::size_t>(width));  // Z16 is little-endian: a plain copy
    } else {
      for (int u = 0; u < width; ++u) out[u] = u16(row + 2 * u);
    }
  }
  return d;
}

std::optional<Profile> decode_profile(const std::uint8_t* data, std::size_t size, DecodeError* error) {
  if (error) *error = DecodeError::none;
  if (!data || size < kProfileHeaderBytes) return fail<Profile>(error, DecodeError::short_buffer);
  if (u32(data) != kProfileMagic) return fail<Profile>(error, DecodeError::bad_magic);
  if (u16(data + 4) != 1) return fail<Profile>(error, DecodeError::bad_version);
  const std::size_t header = u16(data + 6);
  if (header < kProfileHeaderBytes) return fail<Profile>(error, DecodeError::bad_header);
  Profile p;
  p.sequence = u32(data + 8);
  p.timestamp_us = u64(data + 12);
  const std::size_t n = u16(data + 20);
  p.end_of_sweep = (u16(data + 22) & kProfileFlagEndOfSweep) != 0;
  const float scale = f32(data + 24), x0 = f32(data + 28), z0 = f32(data + 32);
  if (n > kProfileMaxPoints) return fail<Profile>(error, DecodeError::too_many_points);
  if (!std::isfinite(scale) || !(scale > 0) || !std::isfinite(x0) || !std::isfinite(z0))
    return fail<Profile>(error, DecodeError::bad_header);
  if (size < header + n * kProfilePointBytes) return fail<Profile>(error, DecodeError::short_buffer);
  p.x_mm.resize(n);
  p.z_mm.resize(n);
  p.intensity.resize(n);
  const std::uint8_t* q = data + header;
  for (std::size_t i = 0; i < n; ++i, q += kProfilePointBytes) {
    const auto xc = static_cast<std::int16_t>(u16(q));
    const std::uint16_t zc = u16(q + 2);
    p.x_mm[i] = xc * scale + x0;
    p.z_mm[i] = zc ? zc * scale + z0 : 0.f;  // count 0 is "no return", whatever the offset
    p.intensity[i] = q[4];
  }
  return p;
}

std::vector<std::uint8_t> encode_profile(const Profile& p, float scale_mm, float x_offset_mm, float z_offset_mm) {
  const std::size_t n = std::min<std::size_t>(p.x_mm.size(), kProfileMaxPoints);
  std::vector<std::uint8_t> b;
  b.reserve(profile_packet_bytes(n));
  put32(b, kProfileMagic);
  put16(b, 1);
  put16(b, kProfileHeaderBytes);
  put32(b, p.sequence);
  put32(b, static_cast<std::uint32_t>(p.timestamp_us));
  put32(b, static_cast<std::uint32_t>(p.timestamp_us >> 32));
  put16(b, static_cast<std::uint16_t>(n));
  put16(b, p.end_of_sweep ? kProfileFlagEndOfSweep : 0);
  putf(b, scale_mm);
  putf(b, x_offset_mm);
  putf(b, z_offset_mm);
  for (std::size_t i = 0; i < n; ++i) {
    const double xc = std::round((p.x_mm[i] - x_offset_mm) / scale_mm);
    const double zc = p.z_mm[i] > 0 ? std::round((p.z_mm[i] - z_offset_mm) / scale_mm) : 0;
    put16(b, static_cast<std::uint16_t>(static_cast<std::int16_t>(std::clamp(xc, -32768.0, 32767.0))));
    put16(b, static_cast<std::uint16_t>(std::clamp(zc, 0.0, 65535.0)));
    b.push_back(i < p.intensity.size() ? p.intensity[i] : 0);
    b.push_back(0);
  }
  return b;
}

// ---------------------------------------------------------------------------------------------

SweepAssembler::SweepAssembler(const StreamInfo& info, int profiles_per_sweep)
    : info_(info), rows_per_sweep_(std::max(1, profiles_per_sweep)) {
  image_.width = info.width;
  image_.height = rows_per_sweep_;
  image_.data.assign(static_cast<std::size_t>(image_.width) * image_.height, 0);
}

Frame SweepAssembler::take() {
  Frame f;
  f.sequence = sweeps_++;
  f.timestamp = sweep_timestamp_;
  f.image = image_;
  // A sweep ended early (device flag, end of recording) keeps its full height: stream.yaml
  // has one frame size, and empty rows are simply no measurements.
  std::fill(image_.data.begin(), image_.data.end(), 0);
  row_ = 0;
  any_ = false;
  return f;
}

std::vector<Frame> SweepAssembler::add(const Profile& p) {
  std::vector<Frame> done;
  auto next_row = [&] {
    if (++row_ < rows_per_sweep_) return;
    if (any_) done.push_back(take());
    row_ = 0;
  };
  if (last_sequence_) {
    // Profiles the device numbered but never delivered keep their (empty) rows, so the rows
    // after them stay at the right distance along the travel. Unsigned arithmetic wraps; a
    // jump of more than a few sweeps is a restarted device, not lost profiles.
    const std::uint32_t missing = p.sequence - *last_sequence_ - 1;
    if (missing > 0) {
      gaps_ += missing < 0x80000000u ? missing : 1;
      if (missing <= static_cast<std::uint32_t>(4 * rows_per_sweep_))
        for (std::uint32_t k = 0; k < missing; ++k) next_row();
    }
  }
  last_sequence_ = p.sequence;
  if (!any_) sweep_timestamp_ = p.timestamp_us * 1e-6;
  any_ = true;
  const double fx = info_.camera_matrix(0, 0), cx = info_.camera_matrix(0, 2);
  std::uint16_t* row = &image_.data[static_cast<std::size_t>(row_) * image_.width];
  for (std::size_t i = 0; i < p.z_mm.size(); ++i) {
    const double z = p.z_mm[i];
    if (!(z > 0)) continue;
    const double u = std::round(fx * p.x_mm[i] / z + cx);
    const double counts = std::round(z / info_.depth_unit_mm);
    if (!(u >= 0 && u < image_.width) || !(counts >= 1 && counts <= 65535)) {
      ++outside_;
      continue;
    }
    std::uint16_t& cell = row[static_cast<int>(u)];
    const auto c = static_cast<std::uint16_t>(counts);
    if (cell == 0 || c < cell) cell = c;  // the nearest return occludes the others
  }
  if (p.end_of_sweep) {
    done.push_back(take());
    return done;
  }
  next_row();
  return done;
}

std::optional<Frame> SweepAssembler::flush() {
  if (!any_) return std::nullopt;
  return take();
}

}  // namespace s2c
