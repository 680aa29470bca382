#include "peers/openvdb_remesh.h"

#include <chrono>

#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <openvdb/tools/VolumeToMesh.h>

#include "s2c/core/clock.h"

namespace s2c::bench {

OpenVdbResult openvdb_remesh(const TriangleSoup& input, double voxel, double half_width) {
  openvdb::initialize();
  const auto xform = openvdb::math::Transform::createLinearTransform(voxel);
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> tris;
  for (const auto& v : input.vertices) points.emplace_back(float(v.x()), float(v.y()), float(v.z()));
  for (const auto& f : input.faces) tris.emplace_back(f[0], f[1], f[2]);
  OpenVdbResult r;
  using Clock = std::chrono::steady_clock;
  auto t0 = Clock::now();
  auto grid = openvdb::tools::meshToLevelSet<openvdb::FloatGrid>(*xform, points, tris, float(half_width));
  r.seconds_to_volume = seconds_since(t0);
  r.active_voxels = grid->activeVoxelCount();
  r.bytes = grid->memUsage();
  t0 = Clock::now();
  std::vector<openvdb::Vec3s> out_points;
  std::vector<openvdb::Vec3I> out_tris;
  std::vector<openvdb::Vec4I> out_quads;
  openvdb::tools::volumeToMesh(*grid, out_points, out_tris, out_quads, 0.0);
  r.seconds_to_mesh = seconds_since(t0);
  for (const auto& p : out_points) r.mesh.vertices.emplace_back(p.x(), p.y(), p.z());
  for (const auto& t : out_tris) r.mesh.faces.push_back({int(t[0]), int(t[1]), int(t[2])});
  for (const auto& q : out_quads) {
    r.mesh.faces.push_back({int(q[0]), int(q[1]), int(q[2])});
    r.mesh.faces.push_back({int(q[0]), int(q[2]), int(q[3])});
  }
  return r;
}

}  // namespace s2c::bench
