#pragma once
// Tensor voting on a triangle mesh (Kim, Choi & Lee 2009): every face near a vertex votes with
// its normal, T = Σ μ_f n_f n_fᵀ; the eigenvalues λ1 ≥ λ2 ≥ λ3 classify the vertex.
#include <vector>

#include "mesh_arrays.h"
#include "s2c/features/analyze.h"

namespace s2c::features {

struct VotingThresholds {
  double crease = 0.0;  ///< λ2/λ1 above this: crease (or corner)
  double corner = 0.0;  ///< λ3/λ1 above this: corner
};

/// Thresholds from the smallest crease angle φ to detect and the noise: a crease of angle φ seen
/// with equal weight from both sides gives λ2/λ1 = tan²(φ/2); half of it keeps vertices one ring
/// off the crease in the band. Noise of slope s = noise/edge adds about s² to λ2/λ1 and λ3/λ1.
VotingThresholds voting_thresholds(double min_crease_deg, double noise, double edge);

/// Per face a ball about its centroid that holds it: centre, radius, in float (the centre rounded,
/// the radius grown by the rounding and rounded up; infinite where float cannot hold the face).
std::vector<Eigen::Vector4f> face_balls(const MeshArrays& m);

/// Vertices whose vote is plainly a face vote, without voting: every face within `radius` of the
/// vertex lies in one plane (its faces' normals within a small angle of one another, see
/// tensor_voting.cpp). Conservative: a vertex it leaves out is voted on as usual.
std::vector<char> plainly_flat(const MeshArrays& m, const std::vector<Eigen::Vector3d>& face_normals, double radius,
                               const VotingThresholds& t);

/// The tensors of all vertices. Plainly flat vertices get λ = (1, 0, 0) (exact up to tan² of 1e-3
/// rad) and e3 perpendicular to their faces' normal, without the walk over their neighbourhood.
std::vector<VertexTensor> vote(const MeshArrays& m, const std::vector<Eigen::Vector3d>& face_normals, double radius,
                               const VotingThresholds& t);

}  // namespace s2c::features
