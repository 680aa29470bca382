#include "s2c/core/distance.h"

#include <cmath>
#include <limits>

#include <embree3/rtcore.h>

#include "s2c/core/errors.h"

namespace s2c {

Eigen::Vector3d closest_point_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                                          const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double denom = va + vb + vc;
  if (!(std::abs(denom) > 0)) return a;  // degenerate triangle
  const double v = vb / denom, w = vc / denom;
  return a + ab * v + ac * w;
}

struct SurfaceQuery::Impl {
  const TriangleSoup* soup = nullptr;
  Eigen::Vector3d origin;  // Embree works in float: coordinates are stored relative to the centre
  RTCDevice device = nullptr;
  RTCScene scene = nullptr;
  std::vector<float> vertices;  // x y z pad
  std::vector<unsigned> indices;
};

namespace {

struct QueryState {
  const TriangleSoup* soup;
  Eigen::Vector3d p;
  SurfacePoint best;
  bool found = false;
};

bool point_query(RTCPointQueryFunctionArguments* args) {
  auto* st = static_cast<QueryState*>(args->userPtr);
  const auto& f = st->soup->faces[args->primID];
  const Eigen::Vector3d q = closest_point_on_triangle(st->p, st->soup->vertices[f[0]], st->soup->vertices[f[1]],
                                                      st->soup->vertices[f[2]]);
  const double d = (q - st->p).norm();
  if (d < args->query->radius) {
    // Shrinking the radius prunes the rest of the traversal.
    args->query->radius = static_cast<float>(d) + 1e-6f * (1.0f + static_cast<float>(d));
    if (!st->found || d < st->best.distance) {
      st->best = {q, static_cast<int>(args->primID), d};
      st->found = true;
    }
    return true;
  }
  return false;
}

struct CollectState {
  const TriangleSoup* soup;
  Eigen::Vector3d p;
  double radius;
  std::vector<int>* faces;
};

bool collect_query(RTCPointQueryFunctionArguments* args) {
  auto* st = static_cast<CollectState*>(args->userPtr);
  const auto& f = st->soup->faces[args->primID];
  const Eigen::Vector3d q = closest_point_on_triangle(st->p, st->soup->vertices[f[0]], st->soup->vertices[f[1]],
                                                      st->soup->vertices[f[2]]);
  if ((q - st->p).norm() <= st->radius) st->faces->push_back(static_cast<int>(args->primID));
  return false;  // keep the radius: we want all of them
}

RTCPointQuery make_query(const Eigen::Vector3d& local, double radius) {
  RTCPointQuery q;
  q.x = static_cast<float>(local.x());
  q.y = static_cast<float>(local.y());
  q.z = static_cast<float>(local.z());
  q.time = 0;
  // float boxes: pad the radius so rounding never prunes a face that is within it
  q.radius = static_cast<float>(std::min(radius, 1e30)) * (1 + 1e-5f) + 1e-4f;
  return q;
}

}  // namespace

std::vector<int> SurfaceQuery::faces_within(const Eigen::Vector3d& p, double radius) const {
  std::vector<int> faces;
  CollectState st{impl_->soup, p, radius, &faces};
  RTCPointQuery q = make_query(p - impl_->origin, radius);
  RTCPointQueryContext ctx;
  rtcInitPointQueryContext(&ctx);
  rtcPointQuery(impl_->scene, &q, &ctx, collect_query, &st);
  return faces;
}

SurfaceQuery::SurfaceQuery(const TriangleSoup& soup) : impl_(std::make_unique<Impl>()) {
  auto& m = *impl_;
  m.soup = &soup;
  const Bounds b = bounds(soup);
  m.origin = b.center();
  m.device = rtcNewDevice(nullptr);
  if (!m.device) throw ProcessingError("Embree device could not be created");
  m.scene = rtcNewScene(m.device);
  rtcSetSceneFlags(m.scene, RTC_SCENE_FLAG_ROBUST);
  RTCGeometry g = rtcNewGeometry(m.device, RTC_GEOMETRY_TYPE_TRIANGLE);
  auto* vb = static_cast<float*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                         3 * sizeof(float), soup.vertices.size() + 1));
  for (std::size_t i = 0; i < soup.vertices.size(); ++i)
    for (int k = 0; k < 3; ++k) vb[3 * i + k] = static_cast<float>(soup.vertices[i][k] - m.origin[k]);
  auto* ib = static_cast<unsigned*>(rtcSetNewGeometryBuffer(g, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                            3 * sizeof(unsigned), soup.faces.size()));
  for (std::size_t i = 0; i < soup.faces.size(); ++i)
    for (int k = 0; k < 3; ++k) ib[3 * i + k] = static_cast<unsigned>(soup.faces[i][k]);
  rtcCommitGeometry(g);
  rtcAttachGeometry(m.scene, g);
  rtcReleaseGeometry(g);
  rtcCommitScene(m.scene);
}

SurfaceQuery::~SurfaceQuery() {
  if (impl_->scene) rtcReleaseScene(impl_->scene);
  if (impl_->device) rtcReleaseDevice(impl_->device);
}

const TriangleSoup& SurfaceQuery::soup() const { return *impl_->soup; }

std::optional<SurfacePoint> SurfaceQuery::closest(const Eigen::Vector3d& p, double max_distance) const {
  QueryState st{impl_->soup, p, {}, false};
  RTCPointQuery q = make_query(p - impl_->origin, max_distance);
  RTCPointQueryContext ctx;
  rtcInitPointQueryContext(&ctx);
  rtcPointQuery(impl_->scene, &q, &ctx, point_query, &st);
  if (!st.found || st.best.distance > max_distance) return std::nullopt;
  return st.best;
}

std::optional<SurfaceQuery::Hit> SurfaceQuery::raycast(const Eigen::Vector3d& origin, const Eigen::Vector3d& dir,
                                                       double t_min, double t_max) const {
  RTCIntersectContext ctx;
  rtcInitIntersectContext(&ctx);
  RTCRayHit rh;
  const Eigen::Vector3d o = origin - impl_->origin;
  rh.ray.org_x = static_cast<float>(o.x());
  rh.ray.org_y = static_cast<float>(o.y());
  rh.ray.org_z = static_cast<float>(o.z());
  rh.ray.dir_x = static_cast<float>(dir.x());
  rh.ray.dir_y = static_cast<float>(dir.y());
  rh.ray.dir_z = static_cast<float>(dir.z());
  rh.ray.tnear = static_cast<float>(t_min);
  rh.ray.tfar = static_cast<float>(std::min(t_max, 1e30));
  rh.ray.mask = 0xffffffffu;
  rh.ray.flags = 0;
  rh.ray.time = 0;
  rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
  rtcIntersect1(impl_->scene, &ctx, &rh);
  if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
  // Re-intersect the hit triangle in double precision: the float t is only good to ~1e-5 mm·(range/mm).
  const auto& f = impl_->soup->faces[rh.hit.primID];
  const Eigen::Vector3d a = impl_->soup->vertices[f[0]], b = impl_->soup->vertices[f[1]], c = impl_->soup->vertices[f[2]];
  Eigen::Vector3d n = (b - a).cross(c - a);
  const double len = n.norm();
  Hit h;
  h.face = static_cast<int>(rh.hit.primID);
  h.t = rh.ray.tfar;
  if (len > 0) {
    n /= len;
    const double denom = n.dot(dir);
    if (std::abs(denom) > 1e-12) h.t = n.dot(a - origin) / denom;
    h.normal = n;
  } else {
    h.normal = Eigen::Vector3d(rh.hit.Ng_x, rh.hit.Ng_y, rh.hit.Ng_z).normalized();
  }
  return h;
}

}  // namespace s2c
