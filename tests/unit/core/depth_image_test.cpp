// Depth frames: 16-bit PNG written and read back exactly, the same bytes for the same image,
// 16-bit TIFF read, and every other image refused with the file's name and what it is.
#include <png.h>
#include <tiffio.h>

#include <cstdio>
#include <random>

#include "../test_util.h"
#include "s2c/core/errors.h"
#include "s2c/core/stream.h"

namespace fs = std::filesystem;
using namespace s2c;

namespace {

DepthImage noisy_frame(int width, int height) {
  DepthImage d{width, height, std::vector<std::uint16_t>(static_cast<std::size_t>(width) * height)};
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> value(0, 65535);
  for (auto& v : d.data) v = static_cast<std::uint16_t>(value(rng) % 5 == 0 ? 0 : value(rng));
  return d;
}

/// An 8-bit grey PNG written with libpng directly (the codec only writes 16-bit ones).
void write_8bit_png(const fs::path& path, int width, int height) {
  std::FILE* f = std::fopen(path.c_str(), "wb");
  ASSERT_NE(f, nullptr);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  png_infop info = png_create_info_struct(png);
  png_init_io(png, f);
  png_set_IHDR(png, info, width, height, 8, PNG_COLOR_TYPE_GRAY, PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_BASE,
               PNG_FILTER_TYPE_BASE);
  png_write_info(png, info);
  std::vector<png_byte> row(width, 100);
  for (int r = 0; r < height; ++r) png_write_row(png, row.data());
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  std::fclose(f);
}

void write_tiff(const fs::path& path, const DepthImage& d, int bits) {
  TIFF* t = TIFFOpen(path.c_str(), "w");
  ASSERT_NE(t, nullptr);
  TIFFSetField(t, TIFFTAG_IMAGEWIDTH, d.width);
  TIFFSetField(t, TIFFTAG_IMAGELENGTH, d.height);
  TIFFSetField(t, TIFFTAG_BITSPERSAMPLE, bits);
  TIFFSetField(t, TIFFTAG_SAMPLESPERPIXEL, 1);
  TIFFSetField(t, TIFFTAG_PHOTOMETRIC, PHOTOMETRIC_MINISBLACK);
  TIFFSetField(t, TIFFTAG_PLANARCONFIG, PLANARCONFIG_CONTIG);
  TIFFSetField(t, TIFFTAG_ROWSPERSTRIP, 4);
  std::vector<std::uint8_t> row8(d.width);
  for (int r = 0; r < d.height; ++r) {
    const std::uint16_t* row = d.data.data() + static_cast<std::size_t>(r) * d.width;
    if (bits == 16) {
      TIFFWriteScanline(t, const_cast<std::uint16_t*>(row), r);
    } else {
      for (int c = 0; c < d.width; ++c) row8[c] = static_cast<std::uint8_t>(row[c] >> 8);
      TIFFWriteScanline(t, row8.data(), r);
    }
  }
  TIFFClose(t);
}

}  // namespace

TEST(DepthImage, PngRoundTripIsExactAndItsBytesDependOnTheImageOnly) {
  const fs::path dir = test::scratch_dir();
  const DepthImage d = noisy_frame(37, 23);  // odd sizes: no row padding assumed
  write_depth_png(dir / "a.png", d);
  const DepthImage back = read_depth_png(dir / "a.png");
  EXPECT_EQ(back.width, d.width);
  EXPECT_EQ(back.height, d.height);
  EXPECT_EQ(back.data, d.data) << "high and low bytes in the right order";
  EXPECT_EQ(encode_depth_png(d), encode_depth_png(back));
  DepthImage other = d;
  other.data[100] ^= 1;
  EXPECT_NE(encode_depth_png(other), encode_depth_png(d));
}

TEST(DepthImage, OtherPngsAreRefusedByName) {
  const fs::path dir = test::scratch_dir();
  write_8bit_png(dir / "grey8.png", 8, 4);
  test::expect_invalid_input([&] { read_depth_png(dir / "grey8.png"); }, {"grey8.png", "16-bit single-channel", "8 bits"});
  write_depth_png(dir / "cut.png", noisy_frame(64, 64));
  fs::resize_file(dir / "cut.png", fs::file_size(dir / "cut.png") / 2);
  test::expect_invalid_input([&] { read_depth_png(dir / "cut.png"); }, {"cut.png", "truncated"});
  test::write_text(dir / "text.png", "not an image at all");
  test::expect_invalid_input([&] { read_depth_png(dir / "text.png"); }, {"text.png"});
  EXPECT_THROW(encode_depth_png(DepthImage{4, 4, std::vector<std::uint16_t>(3)}), IoError);
}

TEST(DepthImage, ReadsSixteenBitTiffAndRefusesEightBit) {
  const fs::path dir = test::scratch_dir();
  const DepthImage d = noisy_frame(21, 9);
  write_tiff(dir / "frame_depth.tiff", d, 16);
  const DepthImage back = read_depth_png(dir / "frame_depth.tiff");
  EXPECT_EQ(back.width, d.width);
  EXPECT_EQ(back.height, d.height);
  EXPECT_EQ(back.data, d.data);
  write_tiff(dir / "grey8.tiff", d, 8);
  test::expect_invalid_input([&] { read_depth_png(dir / "grey8.tiff"); }, {"grey8.tiff", "16-bit single-channel TIFF"});
}
