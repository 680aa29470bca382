#pragma once
/// \file Pure decoders, separate from the transports that deliver the bytes: V4L2 Z16/Y16 frames
/// and the USB laser profile packet (layout in docs/formats.md). No I/O, no device state, so they
/// are tested and fuzzed on bytes alone.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "s2c/acquire/frame_source.h"
#include "s2c/core/stream.h"

namespace s2c {

/// Why a buffer could not be decoded.
enum class DecodeError { none, short_buffer, bad_magic, bad_version, bad_header, too_many_points };
const char* to_string(DecodeError e);

/// A Z16 (or Y16) frame: `height` rows of `width` little-endian uint16, `bytes_per_line` apart.
/// Returns std::nullopt (and sets `error`) when `size` is short of what the format needs.
std::optional<DepthImage> decode_z16(const std::uint8_t* data, std::size_t size, int width, int height,
                                     int bytes_per_line, DecodeError* error = nullptr);

/// One laser profile as the scanner measured it: points in the sensor's x–z plane (mm).
struct Profile {
  std::uint32_t sequence = 0;
  std::uint64_t timestamp_us = 0;
  bool end_of_sweep = false;
  std::vector<float> x_mm, z_mm;       ///< z = 0: no return on that ray
  std::vector<std::uint8_t> intensity;
};

/// The profile packet of docs/formats.md ("S2CL", version 1): a 36-byte little-endian header
/// (magic, version, header size, sequence, timestamp, point count, flags, scale, x and z
/// offsets) and 6 bytes per point (int16 x, uint16 z, uint8 intensity, uint8 reserved).
constexpr std::uint32_t kProfileMagic = 0x4C433253;  // "S2CL" little-endian
constexpr std::size_t kProfileHeaderBytes = 36;
constexpr std::size_t kProfilePointBytes = 6;
constexpr std::uint16_t kProfileMaxPoints = 8192;
constexpr std::uint16_t kProfileFlagEndOfSweep = 1;

/// Decodes one packet. Returns std::nullopt (and sets `error`) for anything malformed; never
/// reads past `size`.
std::optional<Profile> decode_profile(const std::uint8_t* data, std::size_t size, DecodeError* error = nullptr);

/// Encodes a profile with the given quantisation (counts = (v − offset) / scale): what a scanner's
/// firmware does; used by the emulated scanner and the tests.
std::vector<std::uint8_t> encode_profile(const Profile& p, float scale_mm, float x_offset_mm, float z_offset_mm);

/// Bytes of a packet holding `points` points.
constexpr std::size_t profile_packet_bytes(std::size_t points) {
  return kProfileHeaderBytes + points * kProfilePointBytes;
}

/// Builds laser sweeps (docs/formats.md: one profile per row, one fan ray per column) from
/// profiles: each point goes to the column of its ray, u = fx·x/z + cx, stored as z in counts;
/// the nearest return wins a column. Lost profiles (sequence gaps) leave empty rows, so row r
/// keeps meaning r·profile_step_mm of travel.
class SweepAssembler {
 public:
  SweepAssembler(const StreamInfo& info, int profiles_per_sweep);
  /// Adds a profile; returns the sweeps it completed (usually none or one).
  std::vector<Frame> add(const Profile& p);
  /// The partial sweep, if any rows were filled (at the end of a recording).
  std::optional<Frame> flush();
  std::uint64_t sequence_gaps() const { return gaps_; }
  std::uint64_t points_outside() const { return outside_; }

 private:
  Frame take();
  StreamInfo info_;
  int rows_per_sweep_;
  DepthImage image_;
  int row_ = 0;
  bool any_ = false;
  std::optional<std::uint32_t> last_sequence_;
  double sweep_timestamp_ = 0;
  std::uint64_t sweeps_ = 0, gaps_ = 0, outside_ = 0;
};

}  // namespace s2c
