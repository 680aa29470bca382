#include "ply_header.h"

#include <fstream>
#include <map>
#include <sstream>

namespace s2c::io_detail {

bool parse_ply_type(const std::string& name, PlyType& out) {
  static const std::map<std::string, PlyType> types = {
      {"char", PlyType::int8},     {"int8", PlyType::int8},       {"uchar", PlyType::uint8},
      {"uint8", PlyType::uint8},   {"short", PlyType::int16},     {"int16", PlyType::int16},
      {"ushort", PlyType::uint16}, {"uint16", PlyType::uint16},   {"int", PlyType::int32},
      {"int32", PlyType::int32},   {"uint", PlyType::uint32},     {"uint32", PlyType::uint32},
      {"float", PlyType::float32}, {"float32", PlyType::float32}, {"double", PlyType::float64},
      {"float64", PlyType::float64}};
  const auto it = types.find(name);
  if (it == types.end()) return false;
  out = it->second;
  return true;
}

int ply_size(PlyType t) {
  switch (t) {
    case PlyType::int8:
    case PlyType::uint8: return 1;
    case PlyType::int16:
    case PlyType::uint16: return 2;
    case PlyType::int32:
    case PlyType::uint32:
    case PlyType::float32: return 4;
    case PlyType::float64: return 8;
  }
  return 0;
}

int PlyElement::find(const std::string& wanted) const {
  for (std::size_t i = 0; i < properties.size(); ++i)
    if (properties[i].name == wanted) return static_cast<int>(i);
  return -1;
}

bool read_ply_header(const std::filesystem::path& path, PlyHeader& out) {
  std::ifstream f(path, std::ios::binary);
  std::string line;
  out = PlyHeader{};
  while (std::getline(f, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string kw;
    ls >> kw;
    if (kw == "format") {
      std::string format;
      ls >> format;
      out.format = format == "ascii"                  ? PlyHeader::Format::ascii
                   : format == "binary_big_endian" ? PlyHeader::Format::binary_big_endian
                                                      : PlyHeader::Format::binary_little_endian;
    } else if (kw == "element") {
      PlyElement e;
      if (!(ls >> e.name >> e.count)) return false;
      out.elements.push_back(std::move(e));
    } else if (kw == "property") {
      if (out.elements.empty()) return false;
      PlyProperty p;
      std::string type;
      ls >> type;
      if (type == "list") {
        std::string count_type;
        ls >> count_type >> type;
        p.list = true;
        if (!parse_ply_type(count_type, p.count_type)) return false;
      }
      if (!parse_ply_type(type, p.type) || !(ls >> p.name)) return false;
      out.elements.back().properties.push_back(std::move(p));
    } else if (kw == "end_header") {
      const auto at = f.tellg();
      if (at < 0) return false;
      out.body = static_cast<std::uint64_t>(at);
      return true;
    }
  }
  return false;
}

}  // namespace s2c::io_detail
