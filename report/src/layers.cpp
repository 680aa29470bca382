#include "s2c/report/layers.h"

#include <algorithm>
#include <limits>
#include <unordered_map>

#include <fmt/format.h>
#include <tbb/parallel_for.h>

#include "s2c/core/disjoint_sets.h"
#include "s2c/core/distance.h"
#include "s2c/core/errors.h"
#include "s2c/features/analyze.h"
#include "soup_util.h"

namespace s2c::report {

PointLayer cloud_layer(const TriangleSoup& cloud, std::size_t max_points) {
  PointLayer layer;
  const std::size_t n = cloud.vertices.size();
  const std::size_t stride = std::max<std::size_t>(1, (n + max_points - 1) / std::max<std::size_t>(max_points, 1));
  const bool normals = cloud.normals.size() == n;
  for (std::size_t i = 0; i < n; i += stride) {
    layer.points.push_back(cloud.vertices[i]);
    if (normals) layer.normals.push_back(cloud.normals[i]);
  }
  return layer;
}

ChangedRegions changed_regions(TriangleSoup mesh, const TriangleSoup& base, double threshold, const Colour& highlight) {
  ChangedRegions r;
  std::vector<char> changed(mesh.faces.size(), 0);
  if (!base.faces.empty()) {
    const SurfaceQuery query(base);
    tbb::parallel_for(std::size_t(0), mesh.faces.size(), [&](std::size_t f) {
      const auto& t = mesh.faces[f];
      const Eigen::Vector3d centre = (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3;
      changed[f] = !query.closest(centre, threshold);  // bounded query: fast, and nullopt = farther
    });
  }
  r.layer.face_colours.assign(mesh.faces.size(), kMeshGrey);
  DisjointSets sets(mesh.vertices.size());  // regions: changed faces that share a vertex
  for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
    if (!changed[f]) continue;
    const auto& t = mesh.faces[f];
    r.layer.face_colours[f] = highlight;
    ++r.faces;
    r.area += face_area(mesh, f);
    sets.unite(t[0], t[1]);
    sets.unite(t[0], t[2]);
  }
  std::unordered_map<int, double> region_area;
  for (std::size_t f = 0; f < mesh.faces.size(); ++f)
    if (changed[f]) region_area[sets.find(mesh.faces[f][0])] += face_area(mesh, f);
  r.regions = region_area.size();
  if (!region_area.empty()) {
    const int biggest = std::max_element(region_area.begin(), region_area.end(),
                                         [](const auto& a, const auto& b) { return a.second < b.second; })->first;
    Eigen::Vector3d normal = Eigen::Vector3d::Zero(), centroid = Eigen::Vector3d::Zero();
    std::vector<std::size_t> members;
    for (std::size_t f = 0; f < mesh.faces.size(); ++f) {
      const auto& t = mesh.faces[f];
      if (!changed[f] || sets.find(t[0]) != biggest) continue;
      members.push_back(f);
      const Eigen::Vector3d n2 = (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
      normal += n2;
      centroid += n2.norm() * (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3;
      for (int v : t) {
        if (!r.largest) r.largest = Bounds{mesh.vertices[v], mesh.vertices[v]};
        r.largest->min = r.largest->min.cwiseMin(mesh.vertices[v]);
        r.largest->max = r.largest->max.cwiseMax(mesh.vertices[v]);
      }
    }
    // A band around a bore has normals that cancel: look instead along the normal of the face
    // nearest the region's centre (from the axis side, at the far half of the band).
    const double area2 = 2 * region_area[biggest];
    if (normal.norm() >= 0.3 * area2 && normal.norm() > 0) {
      r.largest_normal = normal.normalized();
    } else if (area2 > 0) {
      centroid /= area2;
      double best = std::numeric_limits<double>::infinity();
      for (std::size_t f : members) {
        const auto& t = mesh.faces[f];
        const Eigen::Vector3d c = (mesh.vertices[t[0]] + mesh.vertices[t[1]] + mesh.vertices[t[2]]) / 3;
        const Eigen::Vector3d n2 = (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]);
        if ((c - centroid).squaredNorm() < best && n2.norm() > 0) {
          best = (c - centroid).squaredNorm();
          r.largest_normal = n2.normalized();
        }
      }
    }
  }
  r.layer.soup = std::move(mesh);
  return r;
}

void add_features(Scene& scene, TriangleSoup mesh, const features::FeatureSet& fs) {
  const std::size_t faces = mesh.faces.size(), vertices = mesh.vertices.size();
  MeshLayer layer;
  layer.face_colours.assign(faces, kMeshGrey);
  for (std::size_t p = 0; p < fs.patches.size(); ++p) {
    const auto rgb = features::patch_colour(fs.patches[p].shape.type, int(p));
    const Colour c(rgb[0] / 255.0f, rgb[1] / 255.0f, rgb[2] / 255.0f);
    for (int f : fs.patches[p].faces) {
      if (f < 0 || std::size_t(f) >= faces)
        throw InvalidInput(fmt::format("features: patch {} refers to face {}, the mesh has {} faces (features of another mesh?)",
                                       fs.patches[p].id, f, faces));
      layer.face_colours[f] = c;
    }
  }
  for (const auto& line : fs.lines) {
    Polyline poly;
    poly.closed = line.closed;
    for (int v : line.vertices) {
      if (v < 0 || std::size_t(v) >= vertices)
        throw InvalidInput(fmt::format("features: line {} refers to vertex {}, the mesh has {} vertices (features of another mesh?)",
                                       line.id, v, vertices));
      poly.points.push_back(mesh.vertices[v]);
    }
    // Lines by shape: straight black, circles and arcs dark red, the rest dark grey.
    if (line.shape.type == features::ShapeType::circle || line.shape.type == features::ShapeType::arc)
      poly.colour = Colour(0.55f, 0.0f, 0.05f);
    else if (line.shape.type != features::ShapeType::line)
      poly.colour = Colour(0.25f, 0.25f, 0.25f);
    if (poly.points.size() >= 2) scene.add(std::move(poly));
  }
  layer.soup = std::move(mesh);
  scene.add(std::move(layer));
}

MeshLayer deviation_layer(TriangleSoup mesh, const Deviation& d, double range) {
  MeshLayer layer;
  layer.vertex_colours.resize(mesh.vertices.size());
  for (std::size_t v = 0; v < mesh.vertices.size(); ++v)
    layer.vertex_colours[v] = deviation_colour(v < d.distance.size() ? d.distance[v] : std::nan(""), range);
  layer.soup = std::move(mesh);
  return layer;
}

}  // namespace s2c::report
