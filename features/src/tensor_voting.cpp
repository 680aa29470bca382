#include "tensor_voting.h"

#include <algorithm>
#include <cmath>

#include <Eigen/Eigenvalues>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include "s2c/core/distance.h"
#include "s2c/core/errors.h"
#include "vector_math.h"

namespace s2c::features {

VotingThresholds voting_thresholds(double min_crease_deg, double noise, double edge) {
  const double half = 0.5 * min_crease_deg * M_PI / 180.0;
  const double slope = edge > 0 ? noise / edge : 0.0;
  VotingThresholds t;
  t.crease = 0.5 * std::tan(half) * std::tan(half) + 2.0 * slope * slope;
  t.corner = 0.5 * t.crease + 2.0 * slope * slope;
  return t;
}

std::vector<VertexTensor> vote(const MeshArrays& m, const std::vector<Eigen::Vector3d>& normals, double radius,
                               const VotingThresholds& t) {
  const int nv = m.vertices(), nf = m.faces();
  std::vector<VertexTensor> out(nv);
  // μ_f = (A_f / A_max) exp(−d / (σ/3)) with σ the voting radius. Two deviations from the paper,
  // both for CAD tessellations with long skinny triangles: d is the distance from the vertex to
  // the triangle (not to its centroid, which can be far away for a face touching the vertex), and
  // the area is capped at the area of the voting disc so one huge face cannot outvote the rest.
  const double disc = M_PI * radius * radius;
  // Bounds with a margin over the radius for tests on squared distances: a face they reject is
  // farther than the radius whatever the rounding, so the faces voting are exactly those within it.
  const double far = radius * (1.0 + 1e-9), far2 = far * far * (1.0 + 1e-9);
  struct Scratch {
    std::vector<int> mark;      // face f queued for the current vertex: mark[f] == vertex
    std::vector<int> expanded;  // vertex u's faces queued: expanded[u] == vertex
    std::vector<int> queue;
    std::vector<int> voters;      // faces within the radius, in queue order
    std::vector<double> weights;  // their exp(−3d/r), computed together (vector_math.h)
  };
  // Per face its centroid and the radius of the ball about it holding the triangle, side by
  // side: the test that rejects most queued faces then reads one cache line, not two arrays.
  std::vector<Eigen::Vector4d> ball(nf);
  tbb::parallel_for(tbb::blocked_range<int>(0, nf, 4096), [&](const tbb::blocked_range<int>& range) {
    for (int f = range.begin(); f < range.end(); ++f) {
      double r2 = 0;
      for (int u : m.tri[f]) r2 = std::max(r2, (m.pos[u] - m.centroid[f]).squaredNorm());
      ball[f] << m.centroid[f], std::sqrt(r2);
    }
  });
  tbb::enumerable_thread_specific<Scratch> scratch(
      [nf, nv] { return Scratch{std::vector<int>(nf, -1), std::vector<int>(nv, -1), {}, {}, {}}; });
  // Vertices in the order the faces first reach them: neighbours are then voted on one after the
  // other and share the faces in cache (vertex numbering often follows refinement levels).
  std::vector<int> order;
  order.reserve(nv);
  {
    std::vector<char> seen(nv, 0);
    for (const auto& tri : m.tri)
      for (int u : tri)
        if (!seen[u]) seen[u] = 1, order.push_back(u);
    for (int u = 0; u < nv; ++u)
      if (!seen[u]) order.push_back(u);
  }
  tbb::parallel_for(tbb::blocked_range<int>(0, nv, 256), [&](const tbb::blocked_range<int>& range) {
    Scratch& s = scratch.local();
    for (int i = range.begin(); i < range.end(); ++i) {
      const int v = order[i];
      const Eigen::Vector3d p = m.pos[v];
      Eigen::Matrix3d T = Eigen::Matrix3d::Zero();
      s.queue.clear();
      s.expanded[v] = v;
      for (int k = m.vf_start[v]; k < m.vf_start[v + 1]; ++k) {
        s.mark[m.vf[k]] = v;
        s.queue.push_back(m.vf[k]);
      }
      const std::size_t incident_faces = s.queue.size();  // v's own faces come first
      s.voters.clear();
      s.weights.clear();
      for (std::size_t q = 0; q < s.queue.size(); ++q) {
        const int f = s.queue[q];
        const bool incident = q < incident_faces;
        double d = 0.0;
        if (!incident) {
          // The triangle lies in the ball of radius ball[f][3] about its centroid: most faces of
          // the search's outer ring are out of reach by that bound alone, without the closest
          // point. Compared squared, with a margin that keeps every face within reach: no square
          // root on the path of every queued face.
          const double beyond = (ball[f][3] + far) * (1.0 + 1e-9);
          if ((ball[f].head<3>() - p).squaredNorm() > beyond * beyond) continue;
          const auto& tri = m.tri[f];
          const double d2 = (closest_point_on_triangle(p, m.pos[tri[0]], m.pos[tri[1]], m.pos[tri[2]]) - p).squaredNorm();
          if (d2 > far2) continue;  // certainly beyond the radius: no square root either
          d = std::sqrt(d2);
          if (d > radius) continue;
        }
        s.voters.push_back(f);
        s.weights.push_back(-3.0 * d / radius);
        // A vertex's faces are queued once: after that every one of them is marked, so a second
        // pass over its list (up to three per vertex otherwise) would queue nothing.
        for (int u : m.tri[f]) {
          if (s.expanded[u] == v) continue;
          s.expanded[u] = v;
          for (int k = m.vf_start[u]; k < m.vf_start[u + 1]; ++k)
            if (s.mark[m.vf[k]] != v) {
              s.mark[m.vf[k]] = v;
              s.queue.push_back(m.vf[k]);
            }
        }
      }
      // The decay weights in one call: the vectorised exp does two at a time, and v's own faces
      // (the first voters: an incident face always votes) weigh 1.
      exp_in_place(s.weights.data() + incident_faces, s.weights.size() - incident_faces);
      for (std::size_t k = 0; k < s.voters.size(); ++k) {
        const int f = s.voters[k];
        const double mu = std::min(m.farea[f], disc) / disc * (k < incident_faces ? 1.0 : s.weights[k]);
        const Eigen::Vector3d& n = normals[f];
        T.noalias() += mu * n * n.transpose();
      }
      Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> es;
      es.computeDirect(T);
      const Eigen::Vector3d ev = es.eigenvalues();  // ascending
      VertexTensor& out_v = out[v];
      if (!(ev[2] > 0)) continue;  // isolated vertex or only degenerate faces: a face vertex
      out_v.lambda = Eigen::Vector3d(1.0, std::max(ev[1], 0.0) / ev[2], std::max(ev[0], 0.0) / ev[2]);
      out_v.e1 = es.eigenvectors().col(2);
      out_v.e3 = es.eigenvectors().col(0);
      out_v.cls = out_v.lambda[2] > t.corner ? VertexClass::corner
                  : out_v.lambda[1] > t.crease ? VertexClass::crease
                                               : VertexClass::face;
    }
  });
  return out;
}

}  // namespace s2c::features
