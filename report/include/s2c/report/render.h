#pragma once
/// \file Shaded pictures of meshes, point clouds and feature lines, ray traced on the CPU with
/// Embree (no GPU, no display): the pictures of report.html and of `scan2cad render`.
#include <cstdint>
#include <filesystem>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "s2c/core/mesh.h"

namespace s2c::report {

using Colour = Eigen::Vector3f;  ///< RGB in [0, 1], written to the PNG as is (×255, no gamma curve)

/// The grey of a plain mesh, the orange of filled holes, the purple of edited regions.
inline const Colour kMeshGrey{0.74f, 0.76f, 0.79f};
inline const Colour kFilledOrange{1.0f, 0.55f, 0.10f};
inline const Colour kEditedPurple{0.62f, 0.30f, 0.85f};
inline const Colour kCloudBlue{0.35f, 0.55f, 0.85f};

/// A triangle mesh and how to colour it: per vertex (interpolated) if `vertex_colours` is set,
/// else per face if `face_colours` is set, else `colour`.
struct MeshLayer {
  TriangleSoup soup;
  std::vector<Colour> vertex_colours, face_colours;
  Colour colour = kMeshGrey;
};

/// Points drawn as small discs facing along their normals (spheres where normals are unknown).
struct PointLayer {
  std::vector<Eigen::Vector3d> points, normals;  ///< normals: empty or one per point
  double radius = 0;                             ///< mm; 0: derived from the point density
  Colour colour = kCloudBlue;
};

/// A polyline drawn on top of the surfaces, hidden where a surface is in front of it.
struct Polyline {
  std::vector<Eigen::Vector3d> points;
  bool closed = false;
  Colour colour{0.08f, 0.08f, 0.08f};
};

/// Where the camera looks from: a direction from the centre of the framed box to the eye.
struct View {
  std::string name;             ///< "iso", "back", "top", … (file names, captions)
  Eigen::Vector3d direction = Eigen::Vector3d(1, -1.2, 0.9).normalized();  ///< from the target towards the eye
  Eigen::Vector3d up = Eigen::Vector3d::UnitZ();
};

/// iso (front-right-above), iso-back (back-left-below), front, back, left, right, top, bottom,
/// or "X,Y,Z" (a direction). \throw InvalidInput naming the value for anything else.
View view_named(const std::string& name);
/// The names view_named accepts (for --help and messages).
std::string view_names();

struct RenderOptions {
  int width = 640, height = 480;
  int supersample = 2;    ///< rays per pixel per axis (antialiasing); lowered for huge pictures
                          ///< so that a picture takes at most ~2^25 samples (~700 MB)
  double fov_deg = 30;    ///< vertical field of view
  bool outlines = true;   ///< dark silhouettes and depth steps, as CAD viewers draw them
  bool cutaway = false;   ///< rays start just before the plane through the framed box's centre:
                          ///< what lies in front of it is cut away (a close-up of the far side of a
                          ///< bore's wall through the near side and the part around it)
  float line_width_px = 2.0f;
};

/// An 8-bit RGB image, rows top to bottom.
struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;
};

/// The things to draw. Add everything, then render from several views: the BVH is built on the
/// first render and reused (adding after that throws ProcessingError).
class Scene {
 public:
  Scene();
  ~Scene();
  Scene(const Scene&) = delete;
  Scene& operator=(const Scene&) = delete;

  /// \throw InvalidInput for face indices out of range or colour / normal counts that do not match.
  void add(MeshLayer mesh);
  void add(PointLayer points);
  void add(Polyline line);
  /// Frames this box instead of the scene's own bounds (so that the pictures of several scenes
  /// show the part at the same place and scale).
  void frame(const Bounds& box);
  /// Bounds of every mesh and point added.
  Bounds bounds() const;
  bool empty() const;

  /// \throw ProcessingError when the scene is empty or Embree fails; InvalidInput for a size
  ///        beyond 8192 per side or 2^25 pixels, a field of view outside 1..170°.
  Image render(const View& view, const RenderOptions& options = {}) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// Writes a PNG atomically (OpenCV's encoder). \throw IoError
void write_png(const Image& image, const std::filesystem::path& path);

/// A typical spacing of the points, mm: the median distance to the nearest neighbour of a sample.
double point_spacing(const std::vector<Eigen::Vector3d>& points);

}  // namespace s2c::report
