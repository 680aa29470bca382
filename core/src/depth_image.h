#pragma once
// Private to core: the depth frame codecs (depth_image.cpp) and the stream reader share this.
#include <cstdint>
#include <filesystem>
#include <optional>
#include <utility>

namespace s2c {

/// A PNG's size from its IHDR, read before decoding: a header claiming 100000 × 100000 pixels is
/// refused instead of allocated. Non-PNG files (TIFF frames) give nothing.
std::optional<std::pair<std::uint32_t, std::uint32_t>> png_size(const std::filesystem::path& path);

}  // namespace s2c
