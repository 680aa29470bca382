#include "header_check.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>
#include <vector>

#include <fmt/format.h>

#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "ply_header.h"

namespace fs = std::filesystem;

namespace s2c::io_detail {
namespace {

[[noreturn]] void fail(const fs::path& p, const std::string& what) {
  throw InvalidInput(fmt::format("{}: {}", p.string(), what));
}

std::string read_prefix(const fs::path& p, std::size_t n) {
  std::ifstream f(p, std::ios::binary);
  if (!f) throw IoError(fmt::format("{}: cannot open", p.string()));
  std::string s(n, '\0');
  f.read(s.data(), static_cast<std::streamsize>(n));
  s.resize(static_cast<std::size_t>(f.gcount()));
  return s;
}

// Parses a header count; anything that is not a plain non-negative integer is malformed.
std::uint64_t parse_count(const fs::path& p, const std::string& tok, const char* what) {
  if (tok.empty() || tok.size() > 18 || tok.find_first_not_of("0123456789") != std::string::npos)
    fail(p, fmt::format("header: {} count '{}' is not a non-negative integer", what, tok));
  return std::stoull(tok);
}

int ply_type_size(const std::string& t) {
  PlyType type;
  return parse_ply_type(t, type) ? ply_size(type) : 0;
}

// Lines holding data after byte `offset` (comments and blank lines excluded). OpenMesh's ASCII
// readers do not notice end-of-file and repeat the last record, so truncation is found here.
std::uint64_t data_lines(const fs::path& p, std::uintmax_t offset) {
  std::ifstream f(p, std::ios::binary);
  f.seekg(static_cast<std::streamoff>(offset));
  std::uint64_t n = 0;
  std::string line;
  while (std::getline(f, line)) {
    const auto first = line.find_first_not_of(" \t\r");
    if (first != std::string::npos && line[first] != '#') ++n;
  }
  return n;
}

/// The list lengths of an ASCII PLY's records: each a non-negative integer that fits its declared
/// type, with that many values after it. OpenMesh's ASCII reader takes a length as it comes and
/// reads that many values: a length of 3.4e16 held it for good (found by fuzzing).
void check_ascii_ply_lists(const fs::path& p, std::uint64_t header_lines) {
  PlyHeader header;
  if (!read_ply_header(p, header)) return;  // check_ply reports what is wrong with the header
  bool any_list = false;
  for (const PlyElement& e : header.elements)
    for (const PlyProperty& prop : e.properties) any_list |= prop.list;
  if (!any_list) return;
  std::ifstream in(p, std::ios::binary);
  in.seekg(static_cast<std::streamoff>(header.body));
  std::string line, tok;
  std::istringstream ls;
  std::uint64_t line_no = header_lines;
  auto next = [&]() {  // the next value, across line ends; false at the end of the file
    while (!(ls >> tok)) {
      if (!std::getline(in, line)) return false;
      ++line_no;
      ls.clear();
      ls.str(line);
    }
    return true;
  };
  for (const PlyElement& e : header.elements)
    for (std::uint64_t r = 0; r < e.count; ++r)
      for (const PlyProperty& prop : e.properties) {
        if (!next()) return;  // too few records: the record count check has said so
        if (!prop.list) continue;
        // The largest count its type holds: 0xFF, 0xFFFF, or 0xFFFFFFFF from 4 bytes on.
        const int size = ply_size(prop.count_type);
        const std::uint64_t max = size < 4 ? (std::uint64_t{1} << (8 * size)) - 1 : 0xFFFFFFFFu;
        char* end = nullptr;
        errno = 0;
        const unsigned long long n = std::strtoull(tok.c_str(), &end, 10);
        if (tok[0] == '-' || end == tok.c_str() || *end || errno == ERANGE || n > max)
          fail(p, fmt::format("line {}: {} {}: list '{}' has the length '{}', not a count of 0 to {}", line_no, e.name, r,
                              prop.name, tok.substr(0, 40), max));
        for (unsigned long long k = 0; k < n; ++k)
          if (!next())
            fail(p, fmt::format("truncated: {} {} of {} ends inside its list '{}' ({} values of {})", e.name, r,
                                e.count, prop.name, k, n));
      }
}

DeclaredCounts check_ply(const fs::path& p, std::uintmax_t size) {
  const std::string head = read_prefix(p, 1 << 16);
  if (head.compare(0, 3, "ply") != 0) fail(p, "not a PLY file (it does not start with 'ply')");
  // "end_header" must be a line of its own ("vertend_header" is not one: OpenMesh's reader then
  // loops forever, found by fuzzing).
  std::size_t end = std::string::npos;
  for (std::size_t at = head.find("\nend_header"); at != std::string::npos; at = head.find("\nend_header", at + 1)) {
    const std::size_t after = at + 11;
    if (after == head.size() || head[after] == '\n' || head[after] == '\r') {
      end = at + 1;
      break;
    }
  }
  if (end == std::string::npos) fail(p, "PLY header has no 'end_header' line in its first 64 KiB");
  // Control bytes in the header (a form feed, found by fuzzing) also send OpenMesh's reader into
  // an endless loop.
  for (std::size_t i = 0; i < end; ++i) {
    const auto c = static_cast<unsigned char>(head[i]);
    if ((c < 0x20 && c != '\n' && c != '\r' && c != '\t') || c == 0x7f)
      fail(p, fmt::format("PLY header contains the control byte 0x{:02x}", c));
  }
  std::size_t body_start = head.find('\n', end);
  body_start = body_start == std::string::npos ? head.size() : body_start + 1;

  struct Element { std::string name; std::uint64_t count; std::uint64_t min_bytes = 0; int props = 0; bool xyz[3] = {}; };
  std::vector<Element> elements;
  std::istringstream lines(head.substr(0, end));
  std::string line, format;
  int line_no = 0;
  while (std::getline(lines, line)) {
    ++line_no;
    std::istringstream ls(line);
    std::string kw;
    ls >> kw;
    if (kw == "format") {
      std::string version, extra;
      ls >> format >> version;
      // OpenMesh's reader loops forever on some malformed format lines (found by fuzzing).
      if (version != "1.0" || (ls >> extra))
        fail(p, fmt::format("header line {}: expected 'format ascii|binary_little_endian|binary_big_endian 1.0'", line_no));
      if (format != "ascii" && format != "binary_little_endian" && format != "binary_big_endian")
        fail(p, fmt::format("header line {}: unknown PLY format '{}'", line_no, format));
    } else if (kw == "element") {
      std::string name, count;
      ls >> name >> count;
      elements.push_back({name, parse_count(p, count, name.c_str())});
    } else if (kw == "property") {
      if (elements.empty()) fail(p, fmt::format("header line {}: property before any element", line_no));
      Element& e = elements.back();
      std::string type, a, b, name;
      ls >> type;
      const bool binary = format != "ascii";
      if (type == "list") {
        ls >> a >> b >> name;
        const int cs = ply_type_size(a), is = ply_type_size(b);
        if (!cs || !is) fail(p, fmt::format("header line {}: unknown list types '{} {}'", line_no, a, b));
        // Without a name OpenMesh's reader loops forever (found by fuzzing).
        if (name.empty()) fail(p, fmt::format("header line {}: the list property has no name", line_no));
        // A face needs at least three indices; other lists may be empty.
        const bool face_list = e.name == "face" && (name == "vertex_indices" || name == "vertex_index");
        e.min_bytes += binary ? cs + (face_list ? 3 * is : 0) : (face_list ? 8 : 2);
      } else {
        ls >> name;
        const int s = ply_type_size(type);
        if (!s) fail(p, fmt::format("header line {}: unknown property type '{}'", line_no, type));
        if (name.empty()) fail(p, fmt::format("header line {}: the property has no name", line_no));
        e.min_bytes += binary ? s : 2;
        if (e.name == "vertex" && (name == "x" || name == "y" || name == "z")) e.xyz[name[0] - 'x'] = true;
      }
      ++e.props;
    } else if (kw != "ply" && kw != "comment" && kw != "obj_info" && !kw.empty()) {
      fail(p, fmt::format("header line {}: unknown PLY header keyword '{}'", line_no, kw.substr(0, 40)));
    }
  }
  if (format.empty()) fail(p, "PLY header has no 'format' line");
  DeclaredCounts out;
  out.binary = format != "ascii";
  long double need = 0;
  for (const Element& e : elements) {
    need += static_cast<long double>(e.count) * static_cast<long double>(e.min_bytes);
    if (e.name == "vertex") {
      out.vertices = e.count;
      if (!(e.xyz[0] && e.xyz[1] && e.xyz[2])) fail(p, "PLY vertex element lacks x, y or z");
    }
    if (e.name == "face") out.faces = e.count;
  }
  if (!out.vertices) fail(p, "PLY header declares no 'vertex' element");
  const std::uintmax_t body = size > body_start ? size - body_start : 0;
  if (need > static_cast<long double>(body))
    fail(p, fmt::format("truncated or corrupt: the header declares {} vertices and {} faces, which need at least "
                        "{:.0f} bytes after the header, but only {} bytes follow it",
                        *out.vertices, out.faces.value_or(0), static_cast<double>(need), body));
  if (!out.binary) {
    std::uint64_t records = 0;
    for (const Element& e : elements) records += e.count;
    const std::uint64_t found = data_lines(p, body_start);
    if (found < records)
      fail(p, fmt::format("truncated: the header declares {} records (vertices, faces, ...) but only {} data lines follow",
                          records, found));
    check_ascii_ply_lists(p, static_cast<std::uint64_t>(std::count(head.begin(), head.begin() + body_start, '\n')));
  }
  return out;
}

DeclaredCounts check_stl(const fs::path& p, std::uintmax_t size) {
  const std::string head = read_prefix(p, 512);
  std::size_t i = head.find_first_not_of(" \t\r\n");
  const bool says_solid = i != std::string::npos && head.compare(i, 5, "solid") == 0;
  DeclaredCounts out;
  if (size >= 84) {
    std::uint32_t n = 0;
    std::memcpy(&n, head.data() + 80, 4);
    const std::uint64_t expect = 84 + 50ull * n;
    if (expect == size || (!says_solid && expect <= size)) {
      out.binary = true;
      out.faces = n;
      return out;
    }
    if (!says_solid)
      fail(p, fmt::format("truncated binary STL: the header declares {} triangles ({} bytes) but the file has {} bytes",
                          n, expect, size));
  } else if (!says_solid) {
    fail(p, fmt::format("not an STL file: {} bytes is shorter than a binary STL header and it does not start with 'solid'", size));
  }
  // ASCII STL: a complete file ends with "endsolid".
  std::ifstream f(p, std::ios::binary);
  const std::uintmax_t tail_len = std::min<std::uintmax_t>(size, 1024);
  f.seekg(static_cast<std::streamoff>(size - tail_len));
  std::string tail(tail_len, '\0');
  f.read(tail.data(), static_cast<std::streamsize>(tail_len));
  if (tail.find("endsolid") == std::string::npos)
    fail(p, "truncated ASCII STL: no 'endsolid' at the end of the file");
  return out;
}

/// The face lines of an ASCII OFF: a corner count of 3..1000, then that many indices below the
/// vertex count. OpenMesh's reader loops forever on an index too large for its integer parsing
/// (found by fuzzing), so every face is checked before it reads the file.
void check_off_faces(const fs::path& p, std::uint64_t header_lines, std::uint64_t vertices, std::uint64_t faces) {
  std::ifstream in(p, std::ios::binary);
  std::string line;
  std::uint64_t data = 0, face = 0;
  int no = 0;
  while (face < faces && std::getline(in, line)) {
    ++no;
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    if (line.find_first_not_of(" \t\r") == std::string::npos) continue;
    if (++data <= header_lines + vertices) continue;  // header and vertex lines
    ++face;
    std::istringstream ls(line);
    std::string tok;
    auto integer = [&](const char* what) {
      if (!(ls >> tok)) fail(p, fmt::format("line {}: face line ends early", no));
      char* end = nullptr;
      errno = 0;
      const unsigned long long v = std::strtoull(tok.c_str(), &end, 10);
      if (tok[0] == '-' || end == tok.c_str() || *end || errno == ERANGE)
        fail(p, fmt::format("line {}: {} '{}' is not a non-negative integer", no, what, tok.substr(0, 40)));
      return v;
    };
    const auto n = integer("corner count");
    if (n < 3 || n > 1000) fail(p, fmt::format("line {}: a face with {} corners (3 to 1000)", no, n));
    for (std::uint64_t k = 0; k < n; ++k) {
      const auto i = integer("vertex index");
      if (i >= vertices)
        fail(p, fmt::format("line {}: face refers to vertex {} but there are only {} vertices", no, i, vertices));
    }
  }
}

DeclaredCounts check_off(const fs::path& p, std::uintmax_t size) {
  const std::string head = read_prefix(p, 4096);
  std::istringstream in(head);
  std::string tok;
  std::vector<std::string> toks;
  std::string line;
  // Header keyword, then the first non-comment numbers: nv nf ne.
  std::uint64_t header_lines = 0;
  std::size_t keyword_line_tokens = 0;
  while (toks.size() < 4 && std::getline(in, line)) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    const std::size_t before = toks.size();
    while (toks.size() < 4 && ls >> tok) toks.push_back(tok);
    header_lines += toks.size() > before;
    if (before == 0) keyword_line_tokens = toks.size();
  }
  if (toks.empty() || toks[0].find("OFF") == std::string::npos) fail(p, "not an OFF file (no 'OFF' keyword)");
  // The keyword exactly as OpenMesh knows it ([ST][C][N][4][n]OFF): with anything else in it
  // (a control byte, found by fuzzing) its reader never returns.
  static const std::regex keyword("^(ST)?C?N?4?n?OFF$");
  if (!std::regex_match(toks[0], keyword)) fail(p, fmt::format("unknown OFF keyword '{}'", toks[0].substr(0, 20)));
  if (toks.size() < 3) fail(p, "OFF header lacks vertex and face counts");
  DeclaredCounts out;
  out.binary = toks.size() > 1 && toks[1] == "BINARY";
  if (out.binary) return out;  // binary OFF: counts are checked after reading
  // OpenMesh takes the whole first line as the keyword and reads the counts from the next one:
  // counts on the keyword line would be read from the vertex data (a negative "face count" made
  // its reader loop for billions of faces; found by fuzzing).
  if (keyword_line_tokens > 1)
    fail(p, "the vertex and face counts must be on the line after 'OFF', not on the same line");
  out.vertices = parse_count(p, toks[1], "vertex");
  out.faces = parse_count(p, toks[2], "face");
  const long double need = 6.0L * *out.vertices + 8.0L * *out.faces;
  if (need > static_cast<long double>(size))
    fail(p, fmt::format("truncated or corrupt: the header declares {} vertices and {} faces, more than {} bytes can hold",
                        *out.vertices, *out.faces, size));
  const std::uint64_t lines = data_lines(p, 0) - std::min(header_lines, data_lines(p, 0));
  if (lines < *out.vertices + *out.faces)
    fail(p, fmt::format("truncated: the header declares {} vertices and {} faces but only {} data lines follow",
                        *out.vertices, *out.faces, lines));
  check_off_faces(p, header_lines, *out.vertices, *out.faces);
  return out;
}

/// OBJ has no header: every line is checked instead. OpenMesh's reader asserts (aborts the
/// process) on face indices out of range of the normals or texture coordinates read so far and
/// on mangled face tokens (found by fuzzing), so those are refused here with the line.
DeclaredCounts check_obj(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  if (!in) throw IoError(fmt::format("{}: cannot open", p.string()));
  std::string line;
  std::uint64_t v = 0, vt = 0, vn = 0;
  int no = 0;
  auto number = [&](const std::string& t) {
    char* end = nullptr;
    const double x = std::strtod(t.c_str(), &end);
    if (end == t.c_str() || *end || !std::isfinite(x)) fail(p, fmt::format("line {}: '{}' is not a number", no, t.substr(0, 40)));
  };
  // One index of a face corner: 1-based, or negative (relative to the end); 0 is never valid.
  auto index = [&](const std::string& t, std::uint64_t count, const char* what) {
    char* end = nullptr;
    const long long i = std::strtoll(t.c_str(), &end, 10);
    if (t.empty() || *end) fail(p, fmt::format("line {}: face index '{}' is not an integer", no, t.substr(0, 40)));
    const long long n = static_cast<long long>(count);
    if (i == 0 || i > n || i < -n)
      fail(p, fmt::format("line {}: face refers to {} {} but only {} are defined before it", no, what, i, count));
  };
  while (std::getline(in, line)) {
    ++no;
    if (!line.empty() && line.back() == '\r') line.pop_back();
    for (unsigned char c : line)
      if (c < 0x20 && c != '\t') fail(p, fmt::format("line {}: control byte 0x{:02x}: not a text OBJ file", no, c));
    std::istringstream ls(line);
    std::string kw, t;
    ls >> kw;
    std::vector<std::string> toks;
    while (ls >> t) toks.push_back(t);
    if (kw == "v" || kw == "vn" || kw == "vt") {
      const std::size_t need = kw == "vt" ? 1 : 3;
      if (toks.size() < need) fail(p, fmt::format("line {}: '{}' needs {} numbers", no, kw, need));
      for (const auto& x : toks) number(x);
      (kw == "v" ? v : kw == "vn" ? vn : vt) += 1;
    } else if (kw == "f") {
      if (toks.size() < 3) fail(p, fmt::format("line {}: a face needs at least 3 corners", no));
      for (const auto& corner : toks) {
        // i, i/t, i//n or i/t/n
        std::vector<std::string> part;
        std::size_t at = 0;
        for (std::size_t slash; (slash = corner.find('/', at)) != std::string::npos; at = slash + 1)
          part.push_back(corner.substr(at, slash - at));
        part.push_back(corner.substr(at));
        if (part.size() > 3) fail(p, fmt::format("line {}: face corner '{}' is malformed", no, corner.substr(0, 40)));
        index(part[0], v, "vertex");
        if (part.size() > 1 && !part[1].empty()) index(part[1], vt, "texture coordinate");
        if (part.size() > 2) index(part[2], vn, "normal");
      }
    }
  }
  return {};  // counts are not compared: OpenMesh's OBJ reader may skip what it cannot use
}

}  // namespace

DeclaredCounts check_header(const fs::path& path, MeshFormat format) {
  std::error_code ec;
  if (!fs::exists(path, ec)) throw InvalidInput(fmt::format("{}: no such file", path.string()));
  if (!fs::is_regular_file(path, ec)) throw InvalidInput(fmt::format("{}: not a regular file", path.string()));
  const std::uintmax_t size = fs::file_size(path, ec);
  if (ec) throw IoError(fmt::format("{}: cannot read size: {}", path.string(), ec.message()));
  if (size == 0) throw InvalidInput(fmt::format("{}: empty file", path.string()));
  switch (format) {
    case MeshFormat::ply: return check_ply(path, size);
    case MeshFormat::stl: return check_stl(path, size);
    case MeshFormat::off: return check_off(path, size);
    case MeshFormat::obj: return check_obj(path);
    case MeshFormat::vtk: return {};
  }
  return {};
}

// ---------------------------------------------------------------------------------------------
// Legacy VTK POLYDATA (ASCII).

namespace {

class Tokens {
 public:
  Tokens(const fs::path& p, const std::string& text) : path_(p), in_(text) {}
  bool next(std::string& tok) {
    while (!(ls_ >> tok)) {
      std::string line;
      if (!std::getline(in_, line)) return false;
      ++line_;
      ls_.clear();
      ls_.str(line);
    }
    return true;
  }
  std::string need(const char* what) {
    std::string t;
    if (!next(t)) fail(path_, fmt::format("line {}: file ends where {} was expected (truncated)", line_, what));
    return t;
  }
  double number(const char* what) {
    const std::string t = need(what);
    char* e = nullptr;
    const double v = std::strtod(t.c_str(), &e);
    if (e == t.c_str() || *e) fail(path_, fmt::format("line {}: '{}' is not a number ({})", line_, t, what));
    return v;
  }
  std::uint64_t count(const char* what) { return parse_count(path_, need(what), what); }
  std::string rest_of_line() {
    std::string r;
    std::getline(ls_, r);
    return r;
  }
  std::string line() {
    std::string l;
    if (!std::getline(in_, l)) fail(path_, fmt::format("line {}: unexpected end of file", line_));
    ++line_;
    ls_.clear();
    ls_.str("");
    return l;
  }
  int line_no() const { return line_; }

 private:
  const fs::path& path_;
  std::istringstream in_;
  std::istringstream ls_;
  int line_ = 0;
};

}  // namespace

TriangleSoup read_vtk(const fs::path& path) {
  const std::string text = read_file(path);
  Tokens t(path, text);
  if (t.line().rfind("# vtk DataFile", 0) != 0) fail(path, "line 1: not a legacy VTK file ('# vtk DataFile' expected)");
  t.line();  // title
  const std::string enc = t.line();
  if (enc.rfind("ASCII", 0) != 0) fail(path, "line 3: only ASCII legacy VTK is supported (found '" + enc + "')");
  if (t.need("DATASET") != "DATASET" || t.need("POLYDATA") != "POLYDATA")
    fail(path, fmt::format("line {}: only 'DATASET POLYDATA' is supported", t.line_no()));
  TriangleSoup soup;
  const std::size_t bytes = text.size();
  std::string kw;
  while (t.next(kw)) {
    if (kw == "POINTS") {
      const std::uint64_t n = t.count("point");
      t.need("point type");
      if (n * 6 > bytes) fail(path, fmt::format("line {}: {} points cannot fit in a {}-byte file", t.line_no(), n, bytes));
      soup.vertices.resize(n);
      for (auto& v : soup.vertices)
        for (int k = 0; k < 3; ++k) v[k] = t.number("point coordinate");
    } else if (kw == "POLYGONS" || kw == "TRIANGLE_STRIPS" || kw == "VERTICES" || kw == "LINES") {
      const std::uint64_t n = t.count("cell");
      t.count("cell list size");
      if (n * 2 > bytes) fail(path, fmt::format("line {}: {} cells cannot fit in a {}-byte file", t.line_no(), n, bytes));
      for (std::uint64_t c = 0; c < n; ++c) {
        const std::uint64_t k = t.count("cell size");
        if (k > soup.vertices.size() + 3) fail(path, fmt::format("line {}: cell of {} points", t.line_no(), k));
        std::vector<int> idx(k);
        for (auto& i : idx) {
          const double v = t.number("point index");
          if (v < 0 || v >= static_cast<double>(soup.vertices.size()) || v != static_cast<int>(v))
            fail(path, fmt::format("line {}: point index {} out of range (the file has {} points)", t.line_no(), v,
                                   soup.vertices.size()));
          i = static_cast<int>(v);
        }
        if (kw == "VERTICES" || kw == "LINES" || k < 3) continue;
        for (std::size_t j = 1; j + 1 < k; ++j) {
          std::array<int, 3> f = kw == "POLYGONS" ? std::array<int, 3>{idx[0], idx[j], idx[j + 1]}
                                 : (j % 2) ? std::array<int, 3>{idx[j - 1], idx[j], idx[j + 1]}
                                           : std::array<int, 3>{idx[j], idx[j - 1], idx[j + 1]};
          if (f[0] == f[1] || f[1] == f[2] || f[0] == f[2]) { ++soup.faces_dropped; continue; }
          soup.faces.push_back(f);
        }
        if (kw == "POLYGONS" && k > 3) ++soup.polygons_triangulated;
      }
    } else if (kw == "POINT_DATA" || kw == "CELL_DATA" || kw == "FIELD") {
      break;  // attributes: not needed
    } else if (kw == "METADATA") {
      break;
    } else {
      fail(path, fmt::format("line {}: unexpected keyword '{}'", t.line_no(), kw));
    }
  }
  return soup;
}

}  // namespace s2c::io_detail
