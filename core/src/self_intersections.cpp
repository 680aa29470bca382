// Candidate face pairs from Embree's BVH-vs-BVH collision (user geometry with conservative
// float boxes), then the exact predicate on each candidate.
#include <algorithm>
#include <cmath>
#include <mutex>

#include <embree3/rtcore.h>
#include <fmt/format.h>

#include "s2c/core/check.h"
#include "s2c/core/errors.h"
#include "s2c/core/predicates.h"

namespace s2c {
namespace {

struct CollideData {
  const TriangleSoup* soup;
  std::mutex mutex;
  std::vector<std::pair<int, int>> pairs;
};

float down(double x) {
  float f = static_cast<float>(x);
  return static_cast<double>(f) > x ? std::nextafter(f, -INFINITY) : f;
}
float up(double x) {
  float f = static_cast<float>(x);
  return static_cast<double>(f) < x ? std::nextafter(f, INFINITY) : f;
}

void face_bounds(const RTCBoundsFunctionArguments* args) {
  const auto* soup = static_cast<const TriangleSoup*>(args->geometryUserPtr);
  const auto& f = soup->faces[args->primID];
  Eigen::Vector3d lo = soup->vertices[f[0]], hi = lo;
  for (int k = 1; k < 3; ++k) {
    lo = lo.cwiseMin(soup->vertices[f[k]]);
    hi = hi.cwiseMax(soup->vertices[f[k]]);
  }
  RTCBounds* b = args->bounds_o;
  b->lower_x = down(lo.x()); b->lower_y = down(lo.y()); b->lower_z = down(lo.z());
  b->upper_x = up(hi.x()); b->upper_y = up(hi.y()); b->upper_z = up(hi.z());
}

void on_collide(void* user, RTCCollision* collisions, unsigned int n) {
  auto* d = static_cast<CollideData*>(user);
  const TriangleSoup& s = *d->soup;
  std::vector<std::pair<int, int>> found;
  for (unsigned int i = 0; i < n; ++i) {
    int a = static_cast<int>(collisions[i].primID0), b = static_cast<int>(collisions[i].primID1);
    if (a >= b) continue;  // self-collision reports both orders and the diagonal
    const auto &fa = s.faces[a], &fb = s.faces[b];
    const std::array<Eigen::Vector3d, 3> p{s.vertices[fa[0]], s.vertices[fa[1]], s.vertices[fa[2]]};
    const std::array<Eigen::Vector3d, 3> q{s.vertices[fb[0]], s.vertices[fb[1]], s.vertices[fb[2]]};
    if (faces_self_intersect(p, fa, q, fb)) found.emplace_back(a, b);
  }
  if (!found.empty()) {
    std::lock_guard<std::mutex> lock(d->mutex);
    d->pairs.insert(d->pairs.end(), found.begin(), found.end());
  }
}

}  // namespace

std::vector<std::pair<int, int>> self_intersecting_pairs(const TriangleSoup& soup) {
  if (soup.faces.size() < 2) return {};
  RTCDevice device = rtcNewDevice(nullptr);
  if (!device) throw ProcessingError("Embree device could not be created");
  RTCScene scene = rtcNewScene(device);
  rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
  RTCGeometry geom = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
  rtcSetGeometryUserPrimitiveCount(geom, static_cast<unsigned>(soup.faces.size()));
  rtcSetGeometryUserData(geom, const_cast<TriangleSoup*>(&soup));
  rtcSetGeometryBoundsFunction(geom, face_bounds, const_cast<TriangleSoup*>(&soup));
  rtcCommitGeometry(geom);
  rtcAttachGeometry(scene, geom);
  rtcReleaseGeometry(geom);
  rtcCommitScene(scene);
  CollideData data;
  data.soup = &soup;
  rtcCollide(scene, scene, on_collide, &data);
  const RTCError err = rtcGetDeviceError(device);
  rtcReleaseScene(scene);
  rtcReleaseDevice(device);
  if (err != RTC_ERROR_NONE) throw ProcessingError(fmt::format("Embree collision query failed (error {})", static_cast<int>(err)));
  std::sort(data.pairs.begin(), data.pairs.end());
  data.pairs.erase(std::unique(data.pairs.begin(), data.pairs.end()), data.pairs.end());
  return data.pairs;
}

}  // namespace s2c
