#pragma once
// As-Rigid-As-Possible surface deformation (Sorkine & Alexa 2007) on a region of a mesh: the
// energy runs over the region's faces, the unknowns are the given vertices and every other vertex
// of those faces is a constraint (a handle placed by an edit, or fixed). The cotangent Laplacian
// of the unknowns is factored once; solve() may be called again with new constraint positions and
// reuses the factorisation (interactive dragging of the same features).
#include <array>
#include <memory>
#include <vector>

#include <Eigen/Core>

namespace s2c::edit {

struct ArapStats {
  int iterations = 0;
  double energy = 0.0;
};

class ArapSolver {
 public:
  /// `rest`: positions of every mesh vertex (#V) before the edit; `faces`: the region's triangles
  /// (global vertex indices); `unknowns`: the vertices to solve (a subset of the faces' vertices).
  /// Cotangent weights are clamped to a small positive value so that obtuse CAD triangles keep the
  /// system positive definite. \throw ProcessingError when the system cannot be factored.
  ArapSolver(const std::vector<Eigen::Vector3d>& rest, const std::vector<std::array<int, 3>>& faces,
             std::vector<int> unknowns);
  ~ArapSolver();

  /// Solves for the unknowns given the constraint positions in `positions` (#V, global indices);
  /// writes the unknowns into `positions`. Starts from the positions given: `warm` when they are a
  /// previous solution of this region (interactive dragging), else from the Laplacian solve.
  ArapStats solve(std::vector<Eigen::Vector3d>& positions, int max_iterations, double tolerance, bool warm = false) const;

  const std::vector<int>& unknowns() const;
  const std::vector<std::array<int, 3>>& faces() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace s2c::edit
