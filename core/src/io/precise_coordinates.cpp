// OpenMesh's readers parse coordinates into floats (7 digits). A CAD pipeline keeps what the
// file says, so after OpenMesh has read the structure we read the vertex coordinates again at
// full precision where the file has more than float precision: OBJ, OFF and ASCII PLY text, and
// binary PLY with double x/y/z. Every value is cross-checked against OpenMesh's float; on any
// doubt the float values stay.
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "header_check.h"

namespace fs = std::filesystem;

namespace s2c::io_detail {
namespace {

bool parse3(const char* s, double out[3]) {
  char* end = nullptr;
  for (int k = 0; k < 3; ++k) {
    out[k] = std::strtod(s, &end);
    if (end == s) return false;
    s = end;
  }
  return true;
}

bool is_data_line(const std::string& line) {
  const auto first = line.find_first_not_of(" \t\r");
  return first != std::string::npos && line[first] != '#';
}

// Reads the coordinates of every vertex line; false if the layout is not what we expect.
bool read_obj(const fs::path& p, std::vector<Eigen::Vector3d>& v) {
  std::ifstream f(p);
  std::string line;
  while (std::getline(f, line)) {
    if (line.size() < 2 || line[0] != 'v' || (line[1] != ' ' && line[1] != '\t')) continue;
    double c[3];
    if (!parse3(line.c_str() + 1, c)) return false;
    v.emplace_back(c[0], c[1], c[2]);
  }
  return true;
}

bool read_off(const fs::path& p, std::size_t nv, std::vector<Eigen::Vector3d>& v) {
  std::ifstream f(p);
  std::string line, tok;
  int tokens = 0;
  // Skip the keyword and the three counts, wherever the lines break.
  while (tokens < 4 && std::getline(f, line)) {
    const auto hash = line.find('#');
    if (hash != std::string::npos) line.resize(hash);
    std::istringstream ls(line);
    while (tokens < 4 && ls >> tok) ++tokens;
    std::string rest;
    if (tokens == 4 && std::getline(ls, rest) && rest.find_first_not_of(" \t\r") != std::string::npos) return false;
  }
  while (v.size() < nv && std::getline(f, line)) {
    if (!is_data_line(line)) continue;
    double c[3];
    if (!parse3(line.c_str(), c)) return false;
    v.emplace_back(c[0], c[1], c[2]);
  }
  return v.size() == nv;
}

struct PlyLayout {
  bool ascii = false, little_endian = true;
  std::size_t body = 0;
  int prop_count = 0, xyz_index[3] = {-1, -1, -1};
  int xyz_offset[3] = {0, 0, 0}, stride = 0;
  bool xyz_double = false, vertex_first = false, fixed = true;
};

bool ply_layout(const fs::path& p, PlyLayout& L) {
  std::ifstream f(p, std::ios::binary);
  std::string line;
  bool in_vertex = false;
  int element = -1;
  while (std::getline(f, line)) {
    if (!line.empty() && line.back() == '\r') line.pop_back();
    std::istringstream ls(line);
    std::string kw;
    ls >> kw;
    if (kw == "format") {
      std::string fmt;
      ls >> fmt;
      L.ascii = fmt == "ascii";
      L.little_endian = fmt != "binary_big_endian";
    } else if (kw == "element") {
      std::string name;
      ls >> name;
      ++element;
      in_vertex = name == "vertex";
      if (in_vertex) {
        L.vertex_first = element == 0;
      } else if (element == 0) {
        return false;
      }
    } else if (kw == "property" && in_vertex) {
      std::string type, name;
      ls >> type;
      if (type == "list") return false;
      ls >> name;
      const int size = type == "double" || type == "float64" ? 8
                       : type == "float" || type == "float32" || type == "int" || type == "uint" ||
                               type == "int32" || type == "uint32" ? 4
                       : type == "short" || type == "ushort" || type == "int16" || type == "uint16" ? 2 : 1;
      for (int k = 0; k < 3; ++k)
        if (name == std::string(1, static_cast<char>('x' + k))) {
          L.xyz_index[k] = L.prop_count;
          L.xyz_offset[k] = L.stride;
          if (size == 8) L.xyz_double = true;
          else if (type != "float" && type != "float32") return false;
        }
      L.stride += size;
      ++L.prop_count;
    } else if (kw == "end_header") {
      L.body = static_cast<std::size_t>(f.tellg());
      break;
    }
  }
  return L.vertex_first && L.xyz_index[0] >= 0 && L.xyz_index[1] >= 0 && L.xyz_index[2] >= 0;
}

bool read_ply(const fs::path& p, std::size_t nv, std::vector<Eigen::Vector3d>& v) {
  PlyLayout L;  // the vertex count comes from OpenMesh's reading; the header gives the layout
  if (!ply_layout(p, L)) return false;
  std::ifstream f(p, std::ios::binary);
  f.seekg(static_cast<std::streamoff>(L.body));
  if (L.ascii) {
    std::string line;
    while (v.size() < nv && std::getline(f, line)) {
      if (!is_data_line(line)) continue;
      std::istringstream ls(line);
      std::vector<double> vals(L.prop_count);
      for (auto& x : vals)
        if (!(ls >> x)) return false;
      v.emplace_back(vals[L.xyz_index[0]], vals[L.xyz_index[1]], vals[L.xyz_index[2]]);
    }
    return v.size() == nv;
  }
  if (!L.xyz_double || !L.little_endian) return false;  // floats: OpenMesh already has them exactly
  std::vector<char> rec(L.stride);
  for (std::size_t i = 0; i < nv; ++i) {
    if (!f.read(rec.data(), L.stride)) return false;
    double c[3];
    for (int k = 0; k < 3; ++k) {
      double d;
      std::memcpy(&d, rec.data() + L.xyz_offset[k], 8);
      c[k] = d;
    }
    v.emplace_back(c[0], c[1], c[2]);
  }
  return true;
}

}  // namespace

void refine_coordinates(const fs::path& path, MeshFormat format, TriangleSoup& soup) {
  std::vector<Eigen::Vector3d> precise;
  precise.reserve(soup.vertices.size());
  bool ok = false;
  switch (format) {
    case MeshFormat::obj: ok = read_obj(path, precise); break;
    case MeshFormat::off: ok = read_off(path, soup.vertices.size(), precise); break;
    case MeshFormat::ply: ok = read_ply(path, soup.vertices.size(), precise); break;
    default: return;
  }
  if (!ok || precise.size() != soup.vertices.size()) return;
  for (std::size_t i = 0; i < precise.size(); ++i) {
    const Eigen::Vector3d& a = precise[i];
    const Eigen::Vector3d& b = soup.vertices[i];
    for (int k = 0; k < 3; ++k) {
      // Same number up to float rounding (or both non-finite: validation reports it later).
      if (!std::isfinite(a[k]) || !std::isfinite(b[k])) {
        if (std::isfinite(a[k]) != std::isfinite(b[k])) return;
        continue;
      }
      if (static_cast<float>(a[k]) != static_cast<float>(b[k]) &&
          std::abs(a[k] - b[k]) > 1e-6 * std::abs(a[k]) + 1e-30)
        return;
    }
  }
  soup.vertices.swap(precise);
}

}  // namespace s2c::io_detail
