#include "binary_ply.h"

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <type_traits>
#include <vector>

#include <fmt/format.h>

#include "s2c/core/errors.h"
#include "soup_importer.h"

namespace fs = std::filesystem;

namespace s2c::io_detail {
namespace {

/// The file's bytes from an offset on, through a buffer refilled as the records are taken; a
/// record longer than the buffer grows it, only when the file holds that many bytes (a list
/// length of four billion in a small file is refused, not allocated).
class ByteSource {
 public:
  ByteSource(const fs::path& path, std::uint64_t offset) : in_(path, std::ios::binary), buffer_(kChunk) {
    std::error_code ec;
    const std::uintmax_t size = fs::file_size(path, ec);
    if (!in_ || ec) throw IoError(fmt::format("{}: cannot open", path.string()));
    unread_ = size > offset ? size - offset : 0;
    in_.seekg(static_cast<std::streamoff>(offset));
  }

  /// The next n bytes, or null when the file ends before them.
  const char* take(std::size_t n) {
    if (end_ - pos_ < n && (n - (end_ - pos_) > unread_ || !refill(n))) return nullptr;
    const char* p = buffer_.data() + pos_;
    pos_ += n;
    return p;
  }

 private:
  static constexpr std::size_t kChunk = std::size_t{1} << 20;

  bool refill(std::size_t n) {
    std::memmove(buffer_.data(), buffer_.data() + pos_, end_ - pos_);
    end_ -= pos_;
    pos_ = 0;
    if (buffer_.size() < n) buffer_.resize(std::max(n, 2 * buffer_.size()));
    while (end_ < n && in_) {
      in_.read(buffer_.data() + end_, static_cast<std::streamsize>(buffer_.size() - end_));
      const auto got = static_cast<std::size_t>(in_.gcount());
      end_ += got;
      unread_ -= std::min<std::uint64_t>(got, unread_);
    }
    return end_ >= n;
  }

  std::ifstream in_;
  std::vector<char> buffer_;
  std::size_t pos_ = 0, end_ = 0;
  std::uint64_t unread_ = 0;  // bytes of the file not yet in the buffer
};

/// Values of a file in one byte order.
class Decoder {
 public:
  explicit Decoder(bool big_endian) : swap_(big_endian != host_big_endian()) {}

  double real(PlyType t, const char* p) const {
    return visit<double>(t, p, [](auto v) { return static_cast<double>(v); });
  }
  /// An integer value; a real one is truncated towards zero, as OpenMesh's reader does, with NaN
  /// and values out of range mapped to -1 (no vertex: the face is then refused).
  std::int64_t integer(PlyType t, const char* p) const {
    return visit<std::int64_t>(t, p, [](auto v) -> std::int64_t {
      if constexpr (std::is_floating_point_v<decltype(v)>)
        return v >= -1e18 && v <= 1e18 ? static_cast<std::int64_t>(v) : -1;
      else
        return v;
    });
  }

 private:
  /// f(the value at p, in its own type).
  template <class R, class F>
  R visit(PlyType t, const char* p, F f) const {
    switch (t) {
      case PlyType::int8: return f(get<std::int8_t>(p));
      case PlyType::uint8: return f(get<std::uint8_t>(p));
      case PlyType::int16: return f(get<std::int16_t>(p));
      case PlyType::uint16: return f(get<std::uint16_t>(p));
      case PlyType::int32: return f(get<std::int32_t>(p));
      case PlyType::uint32: return f(get<std::uint32_t>(p));
      case PlyType::float32: return f(get<float>(p));
      case PlyType::float64: break;
    }
    return f(get<double>(p));
  }
  static bool host_big_endian() {
    const std::uint16_t one = 1;
    unsigned char first;
    std::memcpy(&first, &one, 1);
    return first == 0;
  }
  template <class T>
  T get(const char* p) const {
    unsigned char b[sizeof(T)];
    std::memcpy(b, p, sizeof(T));
    if (swap_) std::reverse(b, b + sizeof(T));
    T v;
    std::memcpy(&v, b, sizeof(T));
    return v;
  }

  bool swap_;
};

/// Reads the records of one element through `on_property(index, bytes, count)`, called once per
/// property of each record, in order: `count` values of the property's type at `bytes` (one for
/// a scalar, the entries of a list).
class RecordWalker {
 public:
  RecordWalker(const fs::path& path, ByteSource& src, const Decoder& dec) : path_(path), src_(src), dec_(dec) {}

  template <class OnProperty>
  void walk(const PlyElement& e, OnProperty&& on_property) {
    for (std::uint64_t r = 0; r < e.count; ++r)
      for (std::size_t k = 0; k < e.properties.size(); ++k) {
        const PlyProperty& p = e.properties[k];
        std::uint64_t n = 1;
        if (p.list) {
          const std::int64_t len = dec_.integer(p.count_type, need(ply_size(p.count_type), e, r));
          if (len < 0) fail(e, r, fmt::format("its list '{}' has the negative length {}", p.name, len));
          n = static_cast<std::uint64_t>(len);
        }
        on_property(k, need(n * static_cast<std::uint64_t>(ply_size(p.type)), e, r), n);
      }
  }

 private:
  const char* need(std::uint64_t bytes, const PlyElement& e, std::uint64_t r) {
    const char* p = src_.take(static_cast<std::size_t>(bytes));
    if (!p) fail(e, r, "the file ends inside it (truncated or malformed)");
    return p;
  }
  [[noreturn]] void fail(const PlyElement& e, std::uint64_t r, const std::string& what) const {
    throw InvalidInput(fmt::format("{}: {} {} of {}: {}", path_.string(), e.name, r, e.count, what));
  }

  const fs::path& path_;
  ByteSource& src_;
  const Decoder& dec_;
};

/// Where the vertex record's x, y, z and nx, ny, nz are (-1: absent).
struct VertexFields {
  int xyz[3] = {-1, -1, -1}, normal[3] = {-1, -1, -1};
  explicit VertexFields(const PlyElement& e) {
    for (int k = 0; k < 3; ++k) {
      xyz[k] = e.find(std::string(1, static_cast<char>('x' + k)));
      normal[k] = e.find(std::string("n") + static_cast<char>('x' + k));
    }
  }
  bool has_normals() const { return normal[0] >= 0 && normal[1] >= 0 && normal[2] >= 0; }
};

void read_vertices(const PlyElement& e, RecordWalker& walker, const Decoder& dec, TriangleSoup& soup) {
  const VertexFields at(e);
  // check_header refused a vertex element without x, y or z, and counts the file cannot hold,
  // so the count is safe to allocate.
  soup.vertices.resize(e.count, Eigen::Vector3d::Zero());
  if (at.has_normals()) soup.normals.resize(e.count, Eigen::Vector3d::Zero());
  // Which coordinate (0-2), or normal component (3-5), each property holds; -1 for none.
  std::vector<int> slot(e.properties.size(), -1);
  for (int k = 0; k < 3; ++k) {
    if (at.xyz[k] >= 0) slot[at.xyz[k]] = k;
    if (at.has_normals()) slot[at.normal[k]] = 3 + k;
  }
  std::size_t v = 0;
  const std::size_t last = e.properties.size() - 1;
  walker.walk(e, [&](std::size_t k, const char* bytes, std::uint64_t n) {
    const int s = slot[k];
    if (s >= 0 && n > 0 && !e.properties[k].list) {
      const double value = dec.real(e.properties[k].type, bytes);
      if (s < 3)
        soup.vertices[v][s] = value;
      else
        soup.normals[v][s - 3] = value;
    }
    if (k == last) ++v;
  });
}

void read_faces(const fs::path& path, const PlyElement& e, std::uint64_t vertex_count, RecordWalker& walker,
                const Decoder& dec, TriangleSoup& soup, std::size_t& face_records) {
  int list = e.find("vertex_indices");
  if (list < 0) list = e.find("vertex_index");
  if (list >= 0 && !e.properties[list].list) list = -1;
  soup.faces.reserve(e.count);  // check_header bounded the count by the file's size
  std::vector<std::int64_t> corners;
  std::string first_error;
  const std::size_t last = e.properties.size() - 1;
  walker.walk(e, [&](std::size_t k, const char* bytes, std::uint64_t n) {
    if (static_cast<int>(k) == list) {
      const PlyType t = e.properties[k].type;
      const int size = ply_size(t);
      corners.resize(n);
      for (std::uint64_t i = 0; i < n; ++i) corners[i] = dec.integer(t, bytes + i * size);
      add_polygon(soup, corners.data(), corners.size(), vertex_count, face_records, first_error);
      if (!first_error.empty()) throw InvalidInput(fmt::format("{}: {}", path.string(), first_error));
    }
    if (k == last) ++face_records;
  });
}

}  // namespace

TriangleSoup read_binary_ply(const fs::path& path, const PlyHeader& header, std::size_t& face_records) {
  ByteSource src(path, header.body);
  const Decoder dec(header.format == PlyHeader::Format::binary_big_endian);
  RecordWalker walker(path, src, dec);
  TriangleSoup soup;
  face_records = 0;
  bool vertices_read = false, faces_read = false;
  std::uint64_t vertex_count = 0;
  for (const PlyElement& e : header.elements)
    if (e.name == "vertex") {
      vertex_count = e.count;
      break;
    }
  for (const PlyElement& e : header.elements) {
    if (e.properties.empty()) continue;  // records of no bytes
    if (e.name == "vertex" && !vertices_read) {
      read_vertices(e, walker, dec, soup);
      vertices_read = true;
    } else if (e.name == "face" && !faces_read) {
      read_faces(path, e, vertex_count, walker, dec, soup, face_records);
      faces_read = true;
    } else {
      walker.walk(e, [](std::size_t, const char*, std::uint64_t) {});
    }
  }
  return soup;
}

}  // namespace s2c::io_detail
