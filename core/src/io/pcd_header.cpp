// PCD headers (PCL's point cloud format) checked before PCL reads the file: PCL allocates what
// the header promises, so "POINTS 2000000000" in a 100-byte file would be an out-of-memory kill.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "s2c/core/errors.h"
#include "s2c/core/io.h"

namespace fs = std::filesystem;

namespace s2c {
namespace {

[[noreturn]] void bad(const fs::path& p, int line, const std::string& what) {
  throw InvalidInput(fmt::format("{}: line {}: {}", p.string(), line, what));
}

std::uint64_t count(const fs::path& p, int line, const std::string& tok, const char* what, std::uint64_t max) {
  std::size_t used = 0;
  unsigned long long v = 0;
  try {
    v = std::stoull(tok, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used != tok.size() || tok.empty() || tok[0] == '-') bad(p, line, fmt::format("{} '{}' is not a count", what, tok));
  if (v > max) bad(p, line, fmt::format("{} {} is absurd (at most {})", what, v, max));
  return v;
}

}  // namespace

void check_pcd_header(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw IoError(fmt::format("{}: cannot open", p.string()));
  std::error_code ec;
  const std::uint64_t file_size = fs::file_size(p, ec);
  std::vector<std::string> fields;
  std::vector<std::uint64_t> sizes, counts;
  std::vector<char> types;
  std::uint64_t width = 0, height = 0, points = 0;
  bool have_width = false, have_height = false, have_points = false;
  std::string line, data;
  int no = 0;
  std::uint64_t header_bytes = 0;
  while (data.empty() && std::getline(in, line)) {
    ++no;
    header_bytes += line.size() + 1;
    if (no > 64 || header_bytes > 65536) bad(p, no, "no DATA line within the first 64 lines: not a PCD header");
    if (!line.empty() && line.back() == '\r') line.pop_back();
    if (!line.empty() && line[0] == '#') continue;
    // PCL's header parser crashes on some odd bytes and blank lines (found by fuzzing): a header
    // is printable ASCII, one entry per line.
    if (line.empty()) bad(p, no, "blank line in the header");
    for (unsigned char c : line)
      if (c < 0x20 || c > 0x7e) bad(p, no, fmt::format("byte 0x{:02x} in the header", c));
    std::istringstream ls(line);
    std::string kw, tok;
    ls >> kw;
    std::vector<std::string> toks;
    while (ls >> tok) toks.push_back(tok);
    if (kw == "VERSION") continue;
    if (kw == "VIEWPOINT") {
      if (toks.size() != 7) bad(p, no, "VIEWPOINT needs 7 numbers (tx ty tz qw qx qy qz)");
      for (const auto& t : toks) {
        char* end = nullptr;
        const double v = std::strtod(t.c_str(), &end);
        if (end == t.c_str() || *end || !std::isfinite(v)) bad(p, no, fmt::format("VIEWPOINT value '{}' is not a number", t));
      }
      continue;
    }
    if (kw == "FIELDS") {
      if (toks.empty() || toks.size() > 256) bad(p, no, "FIELDS must list 1 to 256 names");
      fields = toks;
    } else if (kw == "SIZE") {
      for (const auto& t : toks) {
        const auto s = count(p, no, t, "SIZE", 8);
        if (s != 1 && s != 2 && s != 4 && s != 8) bad(p, no, fmt::format("SIZE {} is not 1, 2, 4 or 8", s));
        sizes.push_back(s);
      }
    } else if (kw == "TYPE") {
      for (const auto& t : toks) {
        if (t.size() != 1 || (t[0] != 'I' && t[0] != 'U' && t[0] != 'F')) bad(p, no, fmt::format("TYPE '{}' is not I, U or F", t));
        types.push_back(t[0]);
      }
    } else if (kw == "COUNT") {
      for (const auto& t : toks) counts.push_back(count(p, no, t, "COUNT", 1 << 20));
    } else if (kw == "WIDTH" || kw == "HEIGHT" || kw == "POINTS") {
      if (toks.size() != 1) bad(p, no, kw + " needs one value");
      const auto v = count(p, no, toks[0], kw.c_str(), 1ULL << 40);
      if (kw == "WIDTH") width = v, have_width = true;
      else if (kw == "HEIGHT") height = v, have_height = true;
      else points = v, have_points = true;
    } else if (kw == "DATA") {
      if (toks.size() != 1 || (toks[0] != "ascii" && toks[0] != "binary" && toks[0] != "binary_compressed"))
        bad(p, no, "DATA must be ascii, binary or binary_compressed");
      data = toks[0];
    } else {
      bad(p, no, fmt::format("unknown header keyword '{}' (is this a PCD file?)", kw));
    }
  }
  if (data.empty()) bad(p, no, "the header ends without a DATA line");
  // PCL's header reader does not stop at DATA: it goes on reading lines and takes any that
  // starts like a header keyword as one (binary data beginning "COLUMNS" redefined the fields
  // and crashed it; found by fuzzing). The first non-blank line after DATA must not look like one.
  {
    std::string next;
    while (std::getline(in, next) && (next.empty() || next == "\r")) {
    }
    static const char* kKeywords[] = {"#", "VERSION", "FIELDS", "COLUMNS", "SIZE", "TYPE", "COUNT", "WIDTH",
                                      "HEIGHT", "VIEWPOINT", "POINTS", "DATA"};
    const std::string first = next.substr(0, next.find_first_of(" \t\r"));
    for (const char* k : kKeywords)
      if (!first.empty() && first.rfind(k, 0) == 0)
        bad(p, no + 1, fmt::format("the data after DATA starts with '{}', which PCL would read as a header line", k));
  }
  if (fields.empty()) bad(p, no, "no FIELDS line");
  if (sizes.size() != fields.size() || types.size() != fields.size())
    bad(p, no, fmt::format("{} FIELDS but {} SIZE and {} TYPE entries", fields.size(), sizes.size(), types.size()));
  if (counts.empty()) counts.assign(fields.size(), 1);
  if (counts.size() != fields.size()) bad(p, no, fmt::format("{} FIELDS but {} COUNT entries", fields.size(), counts.size()));
  if (!have_width || !have_height) bad(p, no, "WIDTH and HEIGHT are required");
  if (width > 0 && height > (1ULL << 40) / width) bad(p, no, "WIDTH × HEIGHT is absurd");
  if (have_points && points != width * height)
    bad(p, no, fmt::format("POINTS {} differs from WIDTH × HEIGHT = {}", points, width * height));
  points = width * height;
  for (std::size_t i = 0; i < fields.size(); ++i) {
    if (types[i] == 'F' && sizes[i] != 4 && sizes[i] != 8) bad(p, no, fmt::format("field '{}': TYPE F needs SIZE 4 or 8", fields[i]));
    // scan2cad reads x, y, z as 32-bit floats; PCL copies 4 bytes whatever the field holds.
    if ((fields[i] == "x" || fields[i] == "y" || fields[i] == "z") && (types[i] != 'F' || sizes[i] != 4 || counts[i] != 1))
      bad(p, no, fmt::format("field '{}' must be a 32-bit float (TYPE F, SIZE 4, COUNT 1)", fields[i]));
  }
  for (const char* axis : {"x", "y", "z"})
    if (std::find(fields.begin(), fields.end(), axis) == fields.end()) bad(p, no, fmt::format("no field '{}'", axis));
  std::uint64_t point_bytes = 0;
  for (std::size_t i = 0; i < fields.size(); ++i) point_bytes += sizes[i] * counts[i];
  const std::uint64_t body = file_size > header_bytes ? file_size - header_bytes : 0;
  // What the body must at least hold: binary, every byte; ASCII, a digit and a separator per value.
  std::uint64_t values = 0;
  for (auto c : counts) values += c;
  const std::uint64_t need = data == "binary" ? points * point_bytes : data == "ascii" ? points * 2 * values : 8;
  if (points > 0 && need > body)
    bad(p, no, fmt::format("the header promises {} points ({} bytes at least) but the file holds {} bytes after it",
                           points, need, body));
  if (data == "binary_compressed" && points > 0) {
    // PCL reads two uint32 sizes, then inflates to points × point_bytes.
    if (points * point_bytes > 0xffffffffULL) bad(p, no, "compressed cloud larger than 4 GiB");
  }
}

}  // namespace s2c
