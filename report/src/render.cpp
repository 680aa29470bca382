#include "s2c/report/render.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <mutex>
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

#include "s2c/core/errors.h"
#include "s2c/core/files.h"

namespace s2c::report {
namespace {

constexpr unsigned kNoHit = RTC_INVALID_GEOMETRY_ID;

struct Camera {
  Eigen::Vector3d eye, forward, right, up;
  double tan_half_fov = 0, aspect = 1;
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
};

void embree_error(void*, RTCError code, const char* message) {
  throw ProcessingError(fmt::format("Embree error {}: {}", int(code), message ? message : ""));
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
  std::once_flag built;

  ~Impl() {
    if (scene) rtcReleaseScene(scene);
    if (device) rtcReleaseDevice(device);
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

  void build() {
    device = rtcNewDevice("threads=0");
    if (!device) throw ProcessingError("Embree: no device (unsupported CPU?)");
    rtcSetDeviceErrorFunction(device, embree_error, nullptr);
    scene = rtcNewScene(device);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_MEDIUM);
    for (std::size_t i = 0; i < meshes.size(); ++i) {
      const TriangleSoup& s = meshes[i].soup;
      if (s.faces.empty()) continue;
      RTCGeometry g = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
      auto* v = static_cast<float*>(
          rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), s.vertices.size()));
      for (std::size_t k = 0; k < s.vertices.size(); ++k)
        for (int a = 0; a < 3; ++a) v[3 * k + a] = float(s.vertices[k][a] - origin[a]);
      auto* idx = static_cast<unsigned*>(
          rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3, 3 * sizeof(unsigned), s.faces.size()));
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
      auto* v = static_cast<float*>(
          rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT4, 4 * sizeof(float), p.points.size()));
      for (std::size_t k = 0; k < p.points.size(); ++k) {
        for (int a = 0; a < 3; ++a) v[4 * k + a] = float(p.points[k][a] - origin[a]);
        v[4 * k + 3] = float(radius);
      }
      if (oriented) {
        auto* n = static_cast<float*>(
            rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_NORMAL, 0, RTC_FORMAT_FLOAT3, 3 * sizeof(float), p.points.size()));
        for (std::size_t k = 0; k < p.points.size(); ++k) {
          Eigen::Vector3d d = p.normals[k];
          if (!(d.norm() > 1e-12)) d = Eigen::Vector3d::UnitZ();
          d.normalize();
          for (int a = 0; a < 3; ++a) n[3 * k + a] = float(d[a]);
        }
      }
      attach(g, -1 - int(i));
    }
    rtcCommitScene(scene);
  }

  void attach(RTCGeometry g, int layer) {
    rtcCommitGeometry(g);
    const unsigned id = rtcAttachGeometry(scene, g);
    rtcReleaseGeometry(g);
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

void Scene::add(MeshLayer mesh) { impl_->meshes.push_back(std::move(mesh)); }
void Scene::add(PointLayer points) { impl_->points.push_back(std::move(points)); }
void Scene::add(Polyline line) { impl_->lines.push_back(std::move(line)); }
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
  Impl& s = *impl_;
  const Bounds box = s.framed ? *s.framed : s.own_bounds();
  std::call_once(s.built, [&] {
    s.origin = box.center();
    s.build();
  });
  const int ss = std::clamp(o.supersample, 1, 4);
  const int W = o.width * ss, H = o.height * ss;
  Camera cam = make_camera(view, box, W, H, o.fov_deg);
  std::vector<Sample> samples(std::size_t(W) * H);
  const Eigen::Vector3d eye = cam.eye - s.origin;
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
        rh.ray.tnear = 0;
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

  // Feature lines: rasterised over the ray-traced depth, drawn where no surface is in front.
  const double tolerance = 0.004 * box.diagonal();
  const float half_width = 0.5f * o.line_width_px * ss;
  for (const Polyline& line : s.lines) {
    const std::size_t n = line.points.size();
    for (std::size_t i = 0; i + 1 < n + (line.closed ? 1 : 0); ++i) {
      const Eigen::Vector3d a = cam.project(line.points[i]), b = cam.project(line.points[(i + 1) % n]);
      if (a.z() <= 0 || b.z() <= 0) continue;
      const int steps = std::max(1, int(std::ceil((b.head<2>() - a.head<2>()).norm())));
      if (steps > 4 * (W + H)) continue;  // a segment that long is off screen
      for (int k = 0; k <= steps; ++k) {
        const Eigen::Vector3d p = a + (b - a) * (double(k) / steps);
        const int r = int(std::ceil(half_width));
        for (int dy = -r; dy <= r; ++dy)
          for (int dx = -r; dx <= r; ++dx) {
            if (dx * dx + dy * dy > half_width * half_width + 0.25f) continue;
            const int x = int(std::lround(p.x())) + dx, y = int(std::lround(p.y())) + dy;
            if (x < 0 || y < 0 || x >= W || y >= H) continue;
            Sample& t = samples[std::size_t(y) * W + x];
            if (p.z() <= t.depth + tolerance) t.colour = line.colour;
          }
      }
    }
  }

  // Outlines: silhouettes (hit next to background) and depth steps (one part in front of another).
  std::vector<float> darken(samples.size(), 0.0f);
  if (o.outlines) {
    const float step = float(0.02 * box.diagonal());
    tbb::parallel_for(tbb::blocked_range<int>(1, H - 1, 16), [&](const tbb::blocked_range<int>& rows) {
      for (int y = rows.begin(); y < rows.end(); ++y)
        for (int x = 1; x < W - 1; ++x) {
          const Sample& here = samples[std::size_t(y) * W + x];
          const float d = here.depth;
          if (!std::isfinite(d) || !here.surface) continue;
          for (const auto& [dx, dy] : {std::pair{1, 0}, {-1, 0}, {0, 1}, {0, -1}}) {
            const float e = samples[std::size_t(y + dy) * W + x + dx].depth;
            if (!std::isfinite(e) || e - d > step) {
              darken[std::size_t(y) * W + x] = 1.0f;
              break;
            }
          }
        }
    });
  }

  cv::Mat big(H, W, CV_32FC3);
  for (int y = 0; y < H; ++y)
    for (int x = 0; x < W; ++x) {
      const std::size_t i = std::size_t(y) * W + x;
      Colour c = samples[i].colour * (1.0f - 0.75f * darken[i]);
      big.at<cv::Vec3f>(y, x) = cv::Vec3f(c.x(), c.y(), c.z());
    }
  cv::Mat small;
  if (ss > 1)
    cv::resize(big, small, cv::Size(o.width, o.height), 0, 0, cv::INTER_AREA);
  else
    small = big;
  Image image;
  image.width = o.width;
  image.height = o.height;
  image.rgb.resize(std::size_t(o.width) * o.height * 3);
  for (int y = 0; y < o.height; ++y)
    for (int x = 0; x < o.width; ++x) {
      const cv::Vec3f c = small.at<cv::Vec3f>(y, x);
      for (int k = 0; k < 3; ++k)
        image.rgb[(std::size_t(y) * o.width + x) * 3 + k] = std::uint8_t(std::lround(std::clamp(c[k], 0.0f, 1.0f) * 255));
    }
  return image;
}

void write_png(const Image& image, const std::filesystem::path& path) {
  cv::Mat rgb(image.height, image.width, CV_8UC3, const_cast<std::uint8_t*>(image.rgb.data())), bgr;
  cv::cvtColor(rgb, bgr, cv::COLOR_RGB2BGR);
  std::vector<unsigned char> bytes;
  if (!cv::imencode(".png", bgr, bytes)) throw IoError(fmt::format("{}: PNG encoding failed", path.string()));
  write_file_atomic(path, std::string(bytes.begin(), bytes.end()));
}

}  // namespace s2c::report
