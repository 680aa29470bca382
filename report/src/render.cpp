#include "s2c/report/render.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <random>

#include <embree3/rtcore.h>
#include <fmt/format.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <opencv2/core.hpp>
#include <opencv2/flann.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>

#include "s2c/core/errors.h"
#include "s2c/core/files.h"

namespace s2c::report {
namespace {

constexpr unsigned kNoHit = RTC_INVALID_GEOMETRY_ID;

struct Camera {
  Eigen::Vector3d eye, forward, right, up;
  double tan_half_fov = 0, aspect = 1;
  double distance = 0, radius = 0;  // eye to the framed box's centre; the box's bounding sphere
  int width = 0, height = 0;

  /// The (unit) ray direction through pixel (x, y) of a width × height raster.
  Eigen::Vector3d ray(double x, double y) const {
    const double u = (2 * (x + 0.5) / width - 1) * tan_half_fov * aspect;
    const double v = (1 - 2 * (y + 0.5) / height) * tan_half_fov;
    return (forward + u * right + v * up).normalized();
  }
  /// Pixel coordinates and depth along `forward` of a point; depth <= 0 behind the camera.
  Eigen::Vector3d project(const Eigen::Vector3d& p) const {
    const Eigen::Vector3d d = p - eye;
    const double z = d.dot(forward);
    const double u = d.dot(right) / (z * tan_half_fov * aspect), v = d.dot(up) / (z * tan_half_fov);
    return {(u + 1) * width / 2 - 0.5, (1 - v) * height / 2 - 0.5, z};
  }
};

/// Fits the box's bounding sphere into the view (both axes) with a small margin.
Camera make_camera(const View& view, const Bounds& box, int width, int height, double fov_deg) {
  Camera c;
  c.width = width;
  c.height = height;
  c.aspect = double(width) / height;
  c.tan_half_fov = std::tan(fov_deg * M_PI / 360);
  const double radius = std::max(0.5 * box.diagonal(), 1e-6);
  const double half_fov = std::atan(c.tan_half_fov * std::min(1.0, c.aspect));
  const double distance = 1.08 * radius / std::sin(half_fov);
  c.forward = -view.direction.normalized();
  Eigen::Vector3d up = view.up;
  if (std::abs(c.forward.dot(up.normalized())) > 0.99) up = Eigen::Vector3d::UnitY();
  c.right = c.forward.cross(up).normalized();
  c.up = c.right.cross(c.forward);
  c.eye = box.center() - distance * c.forward;
  c.distance = distance;
  c.radius = radius;
  return c;
}

Colour background(double y01) {
  return Colour(0.97f, 0.975f, 0.98f) * float(1 - y01) + Colour(0.84f, 0.86f, 0.89f) * float(y01);
}

/// What one ray saw.
struct Sample {
  Colour colour = Colour::Zero();
  float depth = std::numeric_limits<float>::infinity();  ///< along the camera axis; inf = background
  bool surface = false;  ///< a mesh (outlined), not a point of a cloud
  bool outline = false;
};

/// The most samples (pixels × supersampling²) one picture may use: about 20 bytes each.
constexpr std::size_t kMaxSamples = std::size_t(1) << 25;

/// Embree reports errors through this callback (throwing through Embree is not safe): the first
/// message is kept and turned into an exception after the call that failed.
void embree_error(void* user, RTCError code, const char* message) {
  auto* first = static_cast<std::string*>(user);
  if (first->empty()) *first = fmt::format("Embree error {}: {}", int(code), message ? message : "");
}

/// Feature lines, rasterised over the ray-traced depth: drawn where no surface is in front.
void draw_lines(std::vector<Sample>& samples, int W, int H, const Camera& cam, double diagonal, float half_width,
                     const std::vector<Polyline>& lines) {
  const double tolerance = 0.004 * diagonal;
  const int r = int(std::ceil(half_width));
  for (const Polyline& line : lines) {
    const std::size_t n = line.points.size();
    for (std::size_t i = 0; i + 1 < n + (line.closed ? 1 : 0); ++i) {
      const Eigen::Vector3d a = cam.project(line.points[i]), b = cam.project(line.points[(i + 1) % n]);
      if (!(a.z() > 0 && b.z() > 0) || !a.allFinite() || !b.allFinite()) continue;  // behind the camera
      const double length = (b.head<2>() - a.head<2>()).norm();
      if (!(length < 4.0 * (W + H))) continue;  // cannot happen for lines on the framed part
      const int steps = std::max(1, int(std::ceil(length)));
      for (int k = 0; k <= steps; ++k) {
        const Eigen::Vector3d p = a + (b - a) * (double(k) / steps);
        if (!(p.x() > -r - 1 && p.y() > -r - 1 && p.x() < W + r && p.y() < H + r)) continue;
        const int cx = int(std::lround(p.x())), cy = int(std::lround(p.y()));
        for (int dy = -r; dy <= r; ++dy)
          for (int dx = -r; dx <= r; ++dx) {
            if (dx * dx + dy * dy > half_width * half_width + 0.25f) continue;
            const int x = cx + dx, y = cy + dy;
            if (x < 0 || y < 0 || x >= W || y >= H) continue;
            Sample& t = samples[std::size_t(y) * W + x];
            if (p.z() <= t.depth + tolerance) t.colour = line.colour;
          }
      }
    }
  }
}

/// Outlines: mesh silhouettes (next to background) and depth steps (one part in front of another).
void mark_outlines(std::vector<Sample>& samples, int W, int H, float step) {
  tbb::parallel_for(tbb::blocked_range<int>(1, H - 1, 16), [&](const tbb::blocked_range<int>& rows) {
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 1; x < W - 1; ++x) {
        Sample& here = samples[std::size_t(y) * W + x];
        if (!std::isfinite(here.depth) || !here.surface) continue;
        for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
          const float e = samples[std::size_t(y + dy) * W + x + dx].depth;
          if (!std::isfinite(e) || e - here.depth > step) {
            here.outline = true;
            break;
          }
        }
      }
  });
}

/// The mean of each ss × ss block (a box filter: what antialiasing by supersampling needs).
Image downsample(const std::vector<Sample>& samples, int W, int H, int ss) {
  Image image;
  image.width = W / ss;
  image.height = H / ss;
  image.rgb.resize(std::size_t(image.width) * image.height * 3);
  const float norm = 1.0f / float(ss * ss);
  tbb::parallel_for(0, image.height, [&](int y) {
    for (int x = 0; x < image.width; ++x) {
      Colour sum = Colour::Zero();
      for (int j = 0; j < ss; ++j)
        for (int i = 0; i < ss; ++i) {
          const Sample& t = samples[std::size_t(y * ss + j) * W + x * ss + i];
          sum += t.colour * (t.outline ? 0.25f : 1.0f);
        }
      for (int k = 0; k < 3; ++k)
        image.rgb[(std::size_t(y) * image.width + x) * 3 + k] =
            std::uint8_t(std::lround(std::clamp(sum[k] * norm, 0.0f, 1.0f) * 255));
    }
  });
  return image;
}

}  // namespace

View view_named(const std::string& name) {
  static const std::vector<std::pair<std::string, Eigen::Vector3d>> presets = {
      {"iso", {1, -1.2, 0.9}}, {"iso-back", {-1, 1.2, -0.7}}, {"front", {0, -1, 0}}, {"back", {0, 1, 0}},
      {"left", {-1, 0, 0}},    {"right", {1, 0, 0}},          {"top", {0, 0, 1}},    {"bottom", {0, 0, -1}}};
  for (const auto& [n, d] : presets)
    if (n == name) return {n, d.normalized()};
  double x, y, z;
  char tail;
  if (std::sscanf(name.c_str(), "%lf,%lf,%lf%c", &x, &y, &z, &tail) == 3) {
    const Eigen::Vector3d d(x, y, z);
    if (std::isfinite(d.norm()) && d.norm() > 1e-9) return {"custom", d.normalized()};
  }
  throw InvalidInput(fmt::format("view '{}': expected {}", name, view_names()));
}

std::string view_names() { return "iso, iso-back, front, back, left, right, top, bottom, or a direction X,Y,Z"; }

double point_spacing(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 2) return 0;
  cv::Mat data(int(points.size()), 3, CV_32F);
  for (int i = 0; i < data.rows; ++i)
    for (int k = 0; k < 3; ++k) data.at<float>(i, k) = float(points[i][k]);
  cv::flann::Index index(data, cv::flann::KDTreeIndexParams(1));
  std::mt19937 rng(7);  // fixed: the same cloud always gets the same spacing
  std::uniform_int_distribution<int> pick(0, data.rows - 1);
  const int samples = std::min(data.rows, 1000);
  std::vector<float> nearest;
  cv::Mat query(1, 3, CV_32F), indices, dists;
  for (int s = 0; s < samples; ++s) {
    data.row(samples == data.rows ? s : pick(rng)).copyTo(query);
    index.knnSearch(query, indices, dists, 2, cv::flann::SearchParams(64));
    if (dists.at<float>(0, 1) > 0) nearest.push_back(std::sqrt(dists.at<float>(0, 1)));
  }
  if (nearest.empty()) return 0;
  std::nth_element(nearest.begin(), nearest.begin() + nearest.size() / 2, nearest.end());
  return nearest[nearest.size() / 2];
}

struct Scene::Impl {
  std::vector<MeshLayer> meshes;
  std::vector<PointLayer> points;
  std::vector<Polyline> lines;
  std::optional<Bounds> framed;

  // Built on the first render (Scene::render is const; impl_ is reached through a pointer).
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<int> geometry_layer;  // Embree geometry id → index into meshes (≥ 0) or points (-1 - i)
  Eigen::Vector3d origin = Eigen::Vector3d::Zero();  // subtracted before converting to float
  std::string embree_message;

  ~Impl() { release(); }
  void release() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
    scene = nullptr;
    device = nullptr;
    geometry_layer.clear();
  }
  void check_embree() {
    if (!embree_message.empty()) throw ProcessingError(embree_message);
  }
  template <typename T>
  T* buffer(RTCGeometry g, RTCBufferType type, RTCFormat format, std::size_t stride, std::size_t count) {
    void* b = rtcSetNewGeometryBuffer(g, type, 0, format, stride, count);
    if (!b) {
      rtcReleaseGeometry(g);
      check_embree();
      throw ProcessingError("Embree: out of memory for a geometry buffer");
    }
    return static_cast<T*>(b);
  }

  Bounds own_bounds() const {
    std::optional<Bounds> b;
    auto grow = [&](const Eigen::Vector3d& p) {
      if (!b) b = Bounds{p, p};
      b->min = b->min.cwiseMin(p);
      b->max = b->max.cwiseMax(p);
    };
    for (const auto& m : meshes)
      for (const auto& f : m.soup.faces)
        for (int v : f) grow(m.soup.vertices[v]);
    for (const auto& p : points)
      for (const auto& q : p.points) grow(q);
    return b ? *b : Bounds{};
  }

  /// Builds the BVH; on failure everything is released (a later render may try again).
  void build() {
    try {
      build_scene();
    } catch (...) {
      release();
      throw;
    }
  }

  void build_scene() {
    device = rtcNewDevice("threads=0");
    if (!device) throw ProcessingError("Embree: no device (unsupported CPU?)");
    rtcSetDeviceErrorFunction(device, embree_error, &embree_message);
    scene = rtcNewScene(device);
    check_embree();
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_MEDIUM);
    for (std::size_t i = 0; i < meshes.size(); ++i) {
      const TriangleSoup& s = meshes[i].soup;
      if (s.faces.empty()) continue;
      RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      check_embree();
      auto* v = buffer<float>(g, RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT3, 3 * sizeof(float), s.vertices.size());
      for (std::size_t k = 0; k < s.vertices.size(); ++k)
        for (int a = 0; a < 3; ++a) v[3 * k + a] = float(s.vertices[k][a] - origin[a]);
      auto* idx = buffer<unsigned>(g, RTC_BUFFER_TYPE_INDEX, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), s.faces.size());
      for (std::size_t k = 0; k < s.faces.size(); ++k)
        for (int a = 0; a < 3; ++a) idx[3 * k + a] = unsigned(s.faces[k][a]);
      attach(g, int(i));
    }
    for (std::size_t i = 0; i < points.size(); ++i) {
      const PointLayer& p = points[i];
      if (p.points.empty()) continue;
      const bool oriented = p.normals.size() == p.points.size();
      double radius = p.radius > 0 ? p.radius : 0.9 * point_spacing(p.points);
      if (!(radius > 0)) radius = 1e-3 * std::max(own_bounds().diagonal(), 1.0);
      RTCGeometry g = rtcNewGeometry(device, oriented ? RTC_GEOMETRY_TYPE_ORIENTED_DISC_POINT : RTC_GEOMETRY_TYPE_SPHERE_POINT);
      check_embree();
      auto* v = buffer<float>(g, RTC_BUFFER_TYPE_VERTEX, RTC_FORMAT_FLOAT4, 4 * sizeof(float), p.points.size());
      for (std::size_t k = 0; k < p.points.size(); ++k) {
        for (int a = 0; a < 3; ++a) v[4 * k + a] = float(p.points[k][a] - origin[a]);
        v[4 * k + 3] = float(radius);
      }
      if (oriented) {
        auto* n = buffer<float>(g, RTC_BUFFER_TYPE_NORMAL, RTC_FORMAT_FLOAT3, 3 * sizeof(float), p.points.size());
        for (std::size_t k = 0; k < p.points.size(); ++k) {
          Eigen::Vector3d d = p.normals[k];
          if (!std::isfinite(d.squaredNorm()) || !(d.norm() > 1e-12)) d = Eigen::Vector3d::UnitZ();
          d.normalize();
          for (int a = 0; a < 3; ++a) n[3 * k + a] = float(d[a]);
        }
      }
      attach(g, -1 - int(i));
    }
    rtcCommitScene(scene);
    check_embree();
  }

  void attach(RTCGeometry g, int layer) {
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
    check_embree();
    if (geometry_layer.size() <= id) geometry_layer.resize(id + 1, 0);
    geometry_layer[id] = layer;
  }

  /// Shades one hit: two-sided (back faces tinted, so that the inside of an open mesh shows),
  /// a key light above the camera and a little specular.
  Colour shade(const RTCRayHit& rh, const Camera& cam, const Eigen::Vector3d& dir) const {
    Eigen::Vector3d n(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z);
    n.normalize();
    const int layer = geometry_layer[rh.hit.geomID];
    Colour base;
    bool back = n.dot(dir) > 0;
    if (layer >= 0) {
      const MeshLayer& m = meshes[layer];
      const unsigned f = rh.hit.primID;
      if (!m.vertex_colours.empty()) {
        const auto& t = m.soup.faces[f];
        base = (1 - rh.hit.u - rh.hit.v) * m.vertex_colours[t[0]] + rh.hit.u * m.vertex_colours[t[1]] +
               rh.hit.v * m.vertex_colours[t[2]];
      } else if (!m.face_colours.empty()) {
        base = m.face_colours[f];
      } else {
        base = m.colour;
      }
    } else {
      base = points[-1 - layer].colour;
      back = false;  // discs and spheres have no inside to show
    }
    if (n.dot(dir) > 0) n = -n;
    if (back) base = 0.35f * base + 0.65f * Colour(0.55f, 0.25f, 0.25f);
    // A headlight (every visible face lit, whichever side the view is from) and a key light from
    // the upper left of the picture (the shape reads from the difference).
    const Eigen::Vector3d key = (-dir + 0.8 * cam.up - 0.6 * cam.right).normalized();
    const double head = std::max(0.0, -n.dot(dir)), diffuse = std::max(0.0, n.dot(key));
    const Eigen::Vector3d half = (key - dir).normalized();
    const double specular = back ? 0 : std::pow(std::max(0.0, n.dot(half)), 48);
    Colour c = base * float(0.25 + 0.45 * head + 0.35 * diffuse) + Colour::Constant(float(0.15 * specular));
    return c.cwiseMin(1.0f);
  }
};

Scene::Scene() : impl_(std::make_unique<Impl>()) {}
Scene::~Scene() = default;

namespace {
void refuse_after_render(const RTCScene scene) {
  if (scene) throw ProcessingError("Scene::add after the first render: the BVH is built; make a new Scene");
}
}  // namespace

void Scene::add(MeshLayer mesh) {
  refuse_after_render(impl_->scene);
  const std::size_t nv = mesh.soup.vertices.size(), nf = mesh.soup.faces.size();
  for (const auto& t : mesh.soup.faces)
    for (int v : t)
      if (v < 0 || std::size_t(v) >= nv) throw InvalidInput(fmt::format("render: a face refers to vertex {} of {}", v, nv));
  if (!mesh.vertex_colours.empty() && mesh.vertex_colours.size() != nv)
    throw InvalidInput(fmt::format("render: {} vertex colours for {} vertices", mesh.vertex_colours.size(), nv));
  if (!mesh.face_colours.empty() && mesh.face_colours.size() != nf)
    throw InvalidInput(fmt::format("render: {} face colours for {} faces", mesh.face_colours.size(), nf));
  impl_->meshes.push_back(std::move(mesh));
}
void Scene::add(PointLayer points) {
  refuse_after_render(impl_->scene);
  if (!points.normals.empty() && points.normals.size() != points.points.size())
    throw InvalidInput(fmt::format("render: {} normals for {} points", points.normals.size(), points.points.size()));
  impl_->points.push_back(std::move(points));
}
void Scene::add(Polyline line) {
  refuse_after_render(impl_->scene);
  impl_->lines.push_back(std::move(line));
}
void Scene::frame(const Bounds& box) { impl_->framed = box; }
Bounds Scene::bounds() const { return impl_->own_bounds(); }
bool Scene::empty() const {
  for (const auto& m : impl_->meshes)
    if (!m.soup.faces.empty()) return false;
  for (const auto& p : impl_->points)
    if (!p.points.empty()) return false;
  return true;
}

Image Scene::render(const View& view, const RenderOptions& o) const {
  if (empty()) throw ProcessingError("nothing to render: the scene has no faces and no points");
  if (o.width < 8 || o.height < 8 || o.width > 8192 || o.height > 8192)
    throw InvalidInput(fmt::format("image size {}x{}: each side must be 8..8192 pixels", o.width, o.height));
  if (!(o.fov_deg >= 1 && o.fov_deg <= 170)) throw InvalidInput(fmt::format("field of view {}°: must be 1..170", o.fov_deg));
  if (!std::isfinite(view.direction.squaredNorm()) || !(view.direction.norm() > 0))
    throw InvalidInput("view direction must be a non-zero vector");
  // Fewer samples per pixel for big pictures, so that memory stays bounded (~20 B per sample).
  const std::size_t pixels = std::size_t(o.width) * o.height;
  int ss = std::clamp(o.supersample, 1, 4);
  while (ss > 1 && pixels * ss * ss > kMaxSamples) --ss;
  if (pixels > kMaxSamples)
    throw InvalidInput(fmt::format("image size {}x{}: at most {} pixels", o.width, o.height, kMaxSamples));
  Impl& s = *impl_;
  const Bounds box = s.framed ? *s.framed : s.own_bounds();
  if (!s.scene) {
    s.origin = box.center();
    s.build();
  }
  const int W = o.width * ss, H = o.height * ss;
  Camera cam = make_camera(view, box, W, H, o.fov_deg);
  std::vector<Sample> samples(std::size_t(W) * H);
  const Eigen::Vector3d eye = cam.eye - s.origin;
  // Cutaway: rays start just before the plane through the framed box's centre (facing the camera).
  const float tnear = o.cutaway ? float(std::max(0.0, cam.distance - 0.1 * cam.radius)) : 0.0f;
  tbb::parallel_for(tbb::blocked_range<int>(0, H, 8), [&](const tbb::blocked_range<int>& rows) {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    for (int y = rows.begin(); y < rows.end(); ++y)
      for (int x = 0; x < W; ++x) {
        const Eigen::Vector3d dir = cam.ray(x, y);
        RTCRayHit rh{};
        rh.ray.org_x = float(eye.x());
        rh.ray.org_y = float(eye.y());
        rh.ray.org_z = float(eye.z());
        rh.ray.dir_x = float(dir.x());
        rh.ray.dir_y = float(dir.y());
        rh.ray.dir_z = float(dir.z());
        rh.ray.tnear = tnear;
        rh.ray.tfar = std::numeric_limits<float>::infinity();
        rh.ray.mask = ~0u;
        rh.hit.geomID = kNoHit;
        rh.hit.instID[0] = kNoHit;
        rtcIntersect1(s.scene, &context, &rh);
        Sample& out = samples[std::size_t(y) * W + x];
        if (rh.hit.geomID == kNoHit) {
          out.colour = background(double(y) / H);
        } else {
          out.colour = s.shade(rh, cam, dir);
          out.depth = float(rh.ray.tfar * dir.dot(cam.forward));
          out.surface = s.geometry_layer[rh.hit.geomID] >= 0;
        }
      }
  });
  draw_lines(samples, W, H, cam, box.diagonal(), 0.5f * o.line_width_px * ss, s.lines);
  if (o.outlines) mark_outlines(samples, W, H, float(0.02 * box.diagonal()));
  return downsample(samples, W, H, ss);
}

void write_png(const Image& image, const std::filesystem::path& path) {
  if (image.width <= 0 || image.height <= 0 || image.rgb.size() != std::size_t(image.width) * image.height * 3)
    throw ProcessingError(fmt::format("{}: the image has no pixels or a wrong buffer size", path.string()));
  cv::Mat rgb(image.height, image.width, CV_8UC3, const_cast<std::uint8_t*>(image.rgb.data())), bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  std::vector<unsigned char> bytes;
  if (!cv::imencode(".png", bgr, bytes)) throw IoError(fmt::format("{}: PNG encoding failed", path.string()));
  write_file_atomic(path, std::string(bytes.begin(), bytes.end()));
}

}  // namespace s2c::report
