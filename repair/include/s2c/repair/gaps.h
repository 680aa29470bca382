#pragma once
/// \file Gap closing by vertex-edge contraction with a priority queue
/// (../shared/papers/repair-survey.txt): a boundary vertex close to another boundary edge is
/// snapped onto it (the edge is split at the closest point if that is interior), cheapest first.
#include <cstddef>

#include "s2c/core/mesh.h"

namespace s2c::repair {

struct GapOptions {
  /// Largest vertex-to-edge distance that is closed, mm; 0 = half the mean boundary edge length.
  double tolerance = 0;
};

struct GapStats {
  std::size_t contractions = 0;  ///< vertex-edge contractions done
  std::size_t edge_splits = 0;   ///< of which split the edge at an interior point
  double max_distance = 0;       ///< the largest distance closed, mm
};

/// Closes gaps between nearby boundaries of `soup` in place. Never creates non-manifold edges or
/// flipped faces (such contractions are skipped). Unreferenced vertices may remain.
GapStats close_gaps(TriangleSoup& soup, const GapOptions& options = {});

}  // namespace s2c::repair
