// Depth frames as 16-bit single-channel PNG (read and written) and TIFF (read: the PCL Kinect
// frames), with libpng and libtiff directly. OpenCV's image codecs did this before and pulled in
// GDAL and ~140 shared libraries: 54 MB of resident memory and 70 ms of start-up in every process
// that reads a stream, for three image operations.
#include <png.h>
#include <tiffio.h>

#include <csetjmp>
#include <cstdarg>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <utility>

#include <fmt/format.h>

#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "s2c/core/stream.h"
#include "depth_image.h"

namespace fs = std::filesystem;

namespace s2c {
namespace {

/// zlib level 1: depth images compress nearly as well as at 9 (runs of zeros, smooth surfaces),
/// several times faster, which a recorder at 30 fps needs.
constexpr int kPngCompression = 1;
/// Larger frames are refused before anything is allocated for them.
constexpr std::uint32_t kMaxSide = 16384;

struct FileCloser {
  void operator()(std::FILE* f) const { std::fclose(f); }
};

/// libpng reports errors by longjmp to the setjmp of the function that called it; the message is
/// kept here so the exception thrown afterwards can say what was wrong.
struct PngErrors {
  std::jmp_buf jump;
  char message[256] = "";
};

void png_fail(png_structp png, png_const_charp message) {
  auto* e = static_cast<PngErrors*>(png_get_error_ptr(png));
  std::snprintf(e->message, sizeof e->message, "%s", message);
  std::longjmp(e->jump, 1);
}

void png_ignore_warning(png_structp, png_const_charp) {}

/// Decodes the PNG in `file` into `out`, 16-bit grey only. Returns an empty string on success,
/// else what is wrong. No object with a destructor lives in this frame across the setjmp.
std::string decode_png(std::FILE* file, DepthImage& out) {
  PngErrors errors;
  png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &errors, png_fail, png_ignore_warning);
  if (!png) return "out of memory";
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_read_struct(&png, nullptr, nullptr);
    return "out of memory";
  }
  if (setjmp(errors.jump)) {
    png_destroy_read_struct(&png, &info, nullptr);
    return fmt::format("unreadable or truncated image ({})", errors.message);
  }
  png_init_io(png, file);
  png_set_user_limits(png, kMaxSide, kMaxSide);
  png_read_info(png, info);
  const png_uint_32 width = png_get_image_width(png, info), height = png_get_image_height(png, info);
  const int depth = png_get_bit_depth(png, info), colour = png_get_color_type(png, info);
  if (depth != 16 || colour != PNG_COLOR_TYPE_GRAY) {
    png_destroy_read_struct(&png, &info, nullptr);
    const int channels = colour == PNG_COLOR_TYPE_GRAY ? 1 : colour == PNG_COLOR_TYPE_GRAY_ALPHA ? 2
                         : colour == PNG_COLOR_TYPE_RGB_ALPHA                                    ? 4
                                                                                                 : 3;
    return fmt::format("frame must be a 16-bit single-channel PNG (found {} channels, {} bits)", channels, depth);
  }
  png_set_swap(png);  // PNG samples are big-endian
  png_read_update_info(png, info);
  out.width = static_cast<int>(width);
  out.height = static_cast<int>(height);
  out.data.resize(static_cast<std::size_t>(width) * height);
  for (png_uint_32 r = 0; r < height; ++r)
    png_read_row(png, reinterpret_cast<png_bytep>(out.data.data() + static_cast<std::size_t>(r) * width), nullptr);
  png_read_end(png, nullptr);
  png_destroy_read_struct(&png, &info, nullptr);
  return {};
}

DepthImage read_png(const fs::path& path) {
  std::unique_ptr<std::FILE, FileCloser> file(std::fopen(path.c_str(), "rb"));
  if (!file) throw InvalidInput(fmt::format("{}: cannot open the frame", path.string()));
  DepthImage d;
  if (const std::string error = decode_png(file.get(), d); !error.empty())
    throw InvalidInput(fmt::format("{}: {}", path.string(), error));
  return d;
}

/// libtiff's messages go to stderr by default; they are collected instead (per thread) so the
/// exception names what was wrong.
thread_local std::string tiff_message;

void tiff_handler(const char* module, const char* format, va_list args) {
  char buffer[256];
  std::vsnprintf(buffer, sizeof buffer, format, args);
  if (tiff_message.empty()) tiff_message = fmt::format("{}{}{}", module ? module : "", module ? ": " : "", buffer);
}

void quiet_tiff() {
  static std::once_flag once;
  std::call_once(once, [] {
    TIFFSetErrorHandler(tiff_handler);
    TIFFSetWarningHandler(nullptr);
  });
}

struct TiffCloser {
  void operator()(TIFF* t) const { TIFFClose(t); }
};

DepthImage read_tiff(const fs::path& path) {
  quiet_tiff();
  tiff_message.clear();
  auto bad = [&](const std::string& what) -> InvalidInput {
    return InvalidInput(fmt::format("{}: {}{}", path.string(), what, tiff_message.empty() ? "" : " (" + tiff_message + ")"));
  };
  std::unique_ptr<TIFF, TiffCloser> tif(TIFFOpen(path.c_str(), "r"));
  if (!tif) throw bad("unreadable or truncated image");
  std::uint32_t width = 0, height = 0;
  std::uint16_t bits = 0, samples = 1, format = SAMPLEFORMAT_UINT;
  TIFFGetField(tif.get(), TIFFTAG_IMAGEWIDTH, &width);
  TIFFGetField(tif.get(), TIFFTAG_IMAGELENGTH, &height);
  TIFFGetFieldDefaulted(tif.get(), TIFFTAG_BITSPERSAMPLE, &bits);
  TIFFGetFieldDefaulted(tif.get(), TIFFTAG_SAMPLESPERPIXEL, &samples);
  TIFFGetFieldDefaulted(tif.get(), TIFFTAG_SAMPLEFORMAT, &format);
  if (width == 0 || height == 0 || width > kMaxSide || height > kMaxSide)
    throw bad(fmt::format("TIFF of {}x{} pixels (1 to {} a side)", width, height, kMaxSide));
  if (bits != 16 || samples != 1 || format != SAMPLEFORMAT_UINT)
    throw bad(fmt::format("frame must be a 16-bit single-channel TIFF (found {} channels, {} bits)", samples, bits));
  if (TIFFIsTiled(tif.get())) throw bad("tiled TIFF frames are not supported (write it in strips)");
  DepthImage d;
  d.width = static_cast<int>(width);
  d.height = static_cast<int>(height);
  d.data.resize(static_cast<std::size_t>(width) * height);
  if (static_cast<std::size_t>(TIFFScanlineSize(tif.get())) != std::size_t{width} * 2)
    throw bad("unexpected TIFF scanline layout");
  for (std::uint32_t r = 0; r < height; ++r)
    if (TIFFReadScanline(tif.get(), d.data.data() + static_cast<std::size_t>(r) * width, r) < 0)
      throw bad(fmt::format("unreadable or truncated image at row {}", r));
  return d;
}

/// What a frame file's first bytes say: whether it is a PNG, and a PNG's size from its IHDR.
struct FrameHeader {
  bool png = false;
  std::optional<std::pair<std::uint32_t, std::uint32_t>> size;
};

FrameHeader frame_header(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  unsigned char h[24] = {};
  in.read(reinterpret_cast<char*>(h), sizeof h);
  FrameHeader out;
  out.png = in.gcount() >= 8 && png_sig_cmp(h, 0, 8) == 0;
  if (!out.png || in.gcount() < static_cast<std::streamsize>(sizeof h) || std::memcmp(h + 12, "IHDR", 4) != 0) return out;
  auto be32 = [&](int o) { return std::uint32_t(h[o]) << 24 | std::uint32_t(h[o + 1]) << 16 | std::uint32_t(h[o + 2]) << 8 | h[o + 3]; };
  out.size = std::make_pair(be32(16), be32(20));
  return out;
}

/// Appends what libpng writes to a string.
void append_bytes(png_structp png, png_bytep data, png_size_t length) {
  static_cast<std::string*>(png_get_io_ptr(png))->append(reinterpret_cast<const char*>(data), length);
}

void no_flush(png_structp) {}

/// Encodes `d` into `out`; false (with `error` set) when libpng fails. As decode_png: nothing
/// with a destructor is created in this frame after the setjmp.
bool encode_png(const DepthImage& d, std::string& out, PngErrors& errors) {
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &errors, png_fail, png_ignore_warning);
  if (!png) return false;
  png_infop info = png_create_info_struct(png);
  if (!info) {
    png_destroy_write_struct(&png, nullptr);
    return false;
  }
  if (setjmp(errors.jump)) {
    png_destroy_write_struct(&png, &info);
    return false;
  }
  png_set_write_fn(png, &out, append_bytes, no_flush);
  // One filter for every row and a fixed zlib level: the bytes depend on the image only.
  png_set_filter(png, PNG_FILTER_TYPE_BASE, PNG_FILTER_SUB);
  png_set_compression_level(png, kPngCompression);
  png_set_IHDR(png, info, static_cast<png_uint_32>(d.width), static_cast<png_uint_32>(d.height), 16,
               PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_BASE, PNG_FILTER_TYPE_BASE);
  png_write_info(png, info);
  png_set_swap(png);
  for (int r = 0; r < d.height; ++r)
    png_write_row(png, reinterpret_cast<png_const_bytep>(d.data.data() + static_cast<std::size_t>(r) * d.width));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return true;
}

}  // namespace

std::optional<std::pair<std::uint32_t, std::uint32_t>> png_size(const fs::path& path) { return frame_header(path).size; }

DepthImage read_depth_png(const fs::path& path) {
  if (!fs::exists(path)) throw InvalidInput(fmt::format("{}: frame file does not exist", path.string()));
  const FrameHeader header = frame_header(path);
  if (const auto& size = header.size; size && (size->first > kMaxSide || size->second > kMaxSide))
    throw InvalidInput(fmt::format("{}: PNG header claims {}x{} pixels (at most {}x{})", path.string(), size->first,
                                   size->second, kMaxSide, kMaxSide));
  return header.png ? read_png(path) : read_tiff(path);
}

std::string encode_depth_png(const DepthImage& d) {
  if (d.width <= 0 || d.height <= 0 || d.data.size() != static_cast<std::size_t>(d.width) * d.height)
    throw IoError(fmt::format("cannot encode a {}x{} depth frame of {} pixels as PNG", d.width, d.height, d.data.size()));
  std::string bytes;
  PngErrors errors;
  if (!encode_png(d, bytes, errors))
    throw IoError(fmt::format("cannot encode a depth frame as PNG{}", errors.message[0] ? fmt::format(" ({})", errors.message) : ""));
  return bytes;
}

void write_depth_png(const fs::path& path, const DepthImage& d) { write_file_atomic(path, encode_depth_png(d)); }

}  // namespace s2c
