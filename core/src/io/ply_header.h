#pragma once
// The layout a PLY header declares: elements in file order, each with its properties, and where
// the data starts. check_header has already refused malformed headers; this only describes
// well-formed ones, for the readers that walk the data (binary_ply.cpp, precise_coordinates.cpp).
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace s2c::io_detail {

enum class PlyType : unsigned char { int8, uint8, int16, uint16, int32, uint32, float32, float64 };

/// The type a header names ("float", "uint8", ...); false for a name PLY does not have.
bool parse_ply_type(const std::string& name, PlyType& out);

/// Bytes of one value of `t` in a binary file.
int ply_size(PlyType t);

struct PlyProperty {
  std::string name;
  PlyType type = PlyType::float32;  ///< of the value, or of a list's entries
  bool list = false;
  PlyType count_type = PlyType::uint8;  ///< of a list's length
};

struct PlyElement {
  std::string name;
  std::uint64_t count = 0;
  std::vector<PlyProperty> properties;
  /// Index of the property called `name`, or -1.
  int find(const std::string& name) const;
};

struct PlyHeader {
  enum class Format { ascii, binary_little_endian, binary_big_endian } format = Format::ascii;
  std::vector<PlyElement> elements;
  std::uint64_t body = 0;  ///< byte offset of the first data byte
};

/// Reads the header of a PLY file. False when it cannot be described (no end_header, an unknown
/// type): check_header names the problem for the user.
bool read_ply_header(const std::filesystem::path& path, PlyHeader& out);

}  // namespace s2c::io_detail
