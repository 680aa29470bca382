#include <array>
#include <cstdint>
#include <cstring>
#include <string>

#include <fmt/format.h>

#include "s2c/core/files.h"
#include "s2c/features/analyze.h"

namespace s2c::features {
namespace {

template <typename T>
void put(std::string& out, T value) {
  char bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));
  out.append(bytes, sizeof(T));
}

}  // namespace

std::array<std::uint8_t, 3> patch_colour(ShapeType type, int index) {
  const double shade = 0.55 + 0.45 * ((index * 37) % 11) / 10.0;
  auto c = [&](double r, double g, double b) {
    return std::array<std::uint8_t, 3>{static_cast<std::uint8_t>(255 * r * shade), static_cast<std::uint8_t>(255 * g * shade),
                                       static_cast<std::uint8_t>(255 * b * shade)};
  };
  switch (type) {
    case ShapeType::plane: return c(0.30, 0.55, 1.0);
    case ShapeType::cylinder: return c(0.35, 0.85, 0.35);
    case ShapeType::cone: return c(1.0, 0.60, 0.20);
    case ShapeType::sphere: return c(0.75, 0.40, 0.95);
    default: return c(0.62, 0.62, 0.62);
  }
}

void write_segments_ply(const Mesh& mesh, const Analysis& analysis, const std::filesystem::path& path) {
  std::string out = fmt::format(
      "ply\nformat binary_little_endian 1.0\ncomment scan2cad features: segment = patch index (P<n>)\n"
      "element vertex {}\nproperty float x\nproperty float y\nproperty float z\n"
      "element face {}\nproperty list uchar int vertex_indices\nproperty int segment\n"
      "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n",
      mesh.n_vertices(), mesh.n_faces());
  for (auto v : mesh.vertices()) {
    const auto& p = mesh.point(v);
    for (int i = 0; i < 3; ++i) put(out, static_cast<float>(p[i]));
  }
  const auto& patches = analysis.features.patches;
  for (auto f : mesh.faces()) {
    put(out, std::uint8_t{3});
    for (auto v : mesh.fv_range(f)) put(out, static_cast<std::int32_t>(v.idx()));
    const int segment = f.idx() < static_cast<int>(analysis.face_patch.size()) ? analysis.face_patch[f.idx()] : -1;
    put(out, static_cast<std::int32_t>(segment));
    const ShapeType type = segment >= 0 ? patches[segment].shape.type : ShapeType::freeform;
    for (std::uint8_t c : patch_colour(type, segment)) put(out, c);
  }
  write_file_atomic(path, out);
}

}  // namespace s2c::features
