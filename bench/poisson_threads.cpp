// PCL's Poisson alone, on a fused cloud written by `scan2cad reconstruct --cloud-out`, with the
// reconstruct stage's settings, on one or more threads: how long it takes and whether its runs
// give the same mesh (issue 3: why the Poisson default cannot reach the speed target, bench/README.md).
// Usage: s2c-bench-poisson CLOUD.ply [--depth 8] [--threads 1] [--repeat 3] [--every 1] [--solver-divide 6] [--iso-divide 6]
// (--every N: every Nth point only, to see how the time depends on the number of points; the
// divides: the octree depth of the blocks PCL solves and extracts in, the stage's by default.)
// Prints one line per run (seconds, faces, FNV-1a hash of the vertices and triangles) and whether
// all runs agree.
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <set>
#include <string>
#include <utility>

#include <pcl/io/ply_io.h>
#include <pcl/point_types.h>
#include <pcl/surface/poisson.h>

#include "s2c/reconstruct/reconstruct.h"

namespace {

std::uint64_t fnv1a(const void* data, std::size_t n, std::uint64_t h) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < n; ++i) h = (h ^ p[i]) * 1099511628211ull;
  return h;
}

std::uint64_t mesh_hash(const pcl::PolygonMesh& pm) {
  std::uint64_t h = 14695981039346656037ull;
  h = fnv1a(pm.cloud.data.data(), pm.cloud.data.size(), h);
  for (const auto& poly : pm.polygons) h = fnv1a(poly.vertices.data(), poly.vertices.size() * sizeof(poly.vertices[0]), h);
  return h;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || std::string(argv[1]) == "--help") {
    std::fprintf(stderr, "usage: s2c-bench-poisson CLOUD.ply [--depth 8] [--threads 1] [--repeat 3] [--every 1] "
                         "[--solver-divide 6] [--iso-divide 6]\n");
    return argc < 2 ? 2 : 0;
  }
  int depth = 8, threads = 1, repeat = 3, every = 1, solver_divide = 0, iso_divide = 0;
  const std::pair<const char*, int*> options[] = {{"--depth", &depth},   {"--threads", &threads},
                                                   {"--repeat", &repeat}, {"--every", &every},
                                                   {"--solver-divide", &solver_divide}, {"--iso-divide", &iso_divide}};
  for (int i = 2; i < argc; i += 2) {
    const std::string key = argv[i];
    int* target = nullptr;
    for (const auto& [name, slot] : options)
      if (key == name) target = slot;
    char* end = nullptr;
    const long value = i + 1 < argc ? std::strtol(argv[i + 1], &end, 10) : 0;
    if (!target || i + 1 >= argc || *end != '\0' || value < 1 || value > 64) {
      std::fprintf(stderr, "s2c-bench-poisson: %s needs a whole number from 1 to 64 (options: --depth --threads --repeat "
                           "--every --solver-divide --iso-divide)\n",
                   key.c_str());
      return 2;
    }
    *target = static_cast<int>(value);
  }
  auto cloud = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
  if (pcl::io::loadPLYFile(argv[1], *cloud) < 0 || cloud->empty()) {
    std::fprintf(stderr, "%s: cannot read a cloud with normals\n", argv[1]);
    return 2;
  }
  if (every > 1) {
    auto thinned = std::make_shared<pcl::PointCloud<pcl::PointNormal>>();
    for (std::size_t i = 0; i < cloud->size(); i += static_cast<std::size_t>(every)) thinned->push_back((*cloud)[i]);
    cloud = thinned;
  }
  std::set<std::uint64_t> hashes;
  for (int r = 0; r < repeat; ++r) {
    // The reconstruct stage's settings (s2c/reconstruct/reconstruct.h), threads aside.
    pcl::Poisson<pcl::PointNormal> poisson;
    poisson.setDepth(depth);
    poisson.setInputCloud(cloud);
    poisson.setSamplesPerNode(s2c::kPoissonSamplesPerNode);
    poisson.setThreads(threads);
    poisson.setSolverDivide(solver_divide > 0 ? solver_divide : s2c::poisson_block_depth(depth));
    poisson.setIsoDivide(iso_divide > 0 ? iso_divide : s2c::poisson_block_depth(depth));
    pcl::PolygonMesh pm;
    const auto t0 = std::chrono::steady_clock::now();
    poisson.reconstruct(pm);
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    const std::uint64_t h = mesh_hash(pm);
    hashes.insert(h);
    std::printf("run %d: %zu points, depth %d, blocks %d/%d, %d thread(s): %.2f s, %zu faces, hash %016llx\n", r + 1,
                cloud->size(), depth, poisson.getSolverDivide(), poisson.getIsoDivide(), threads, s, pm.polygons.size(),
                static_cast<unsigned long long>(h));
  }
  std::printf("%zu distinct mesh(es) in %d runs\n", hashes.size(), repeat);
  return 0;
}
