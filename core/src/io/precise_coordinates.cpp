// OpenMesh's readers parse coordinates into floats (7 digits). A CAD pipeline keeps what the
// file says, so after OpenMesh has read the structure we read the vertex coordinates again at
// full precision where the file has more than float precision: OBJ, OFF and ASCII PLY text
// (binary PLY does not go through OpenMesh). Every value is cross-checked against OpenMesh's
// float; on any doubt the float values stay.
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "header_check.h"
#include "ply_header.h"

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

// ASCII PLY only: binary PLY is read at full precision in the first place (binary_ply.cpp).
bool read_ply(const fs::path& p, std::size_t nv, std::vector<Eigen::Vector3d>& v) {
  PlyHeader header;  // the vertex count comes from OpenMesh's reading; the header gives the layout
  if (!read_ply_header(p, header) || header.format != PlyHeader::Format::ascii || header.elements.empty()) return false;
  const PlyElement& vertex = header.elements.front();
  if (vertex.name != "vertex") return false;
  int xyz[3];
  for (int k = 0; k < 3; ++k)
    if ((xyz[k] = vertex.find(std::string(1, static_cast<char>('x' + k)))) < 0) return false;
  for (const PlyProperty& prop : vertex.properties)
    if (prop.list) return false;
  std::ifstream f(p, std::ios::binary);
  f.seekg(static_cast<std::streamoff>(header.body));
  std::string line;
  std::vector<double> vals(vertex.properties.size());
  while (v.size() < nv && std::getline(f, line)) {
    if (!is_data_line(line)) continue;
    std::istringstream ls(line);
    for (auto& x : vals)
      if (!(ls >> x)) return false;
    v.emplace_back(vals[xyz[0]], vals[xyz[1]], vals[xyz[2]]);
  }
  return v.size() == nv;
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
