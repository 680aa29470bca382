#pragma once
/// \file The defect taxonomy of ../shared/papers/repair-survey.txt, measured on a soup, and the
/// cleaning steps that need no geometry invention: duplicate and degenerate faces, loose tiny
/// components, unreferenced vertices, inconsistent or inward orientation.
#include <cstddef>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "s2c/core/check.h"
#include "s2c/core/mesh.h"

namespace s2c::repair {

struct DefectReport {
  CheckResult check;                  ///< topology, orientation, self-intersections (exact)
  std::size_t zero_area_faces = 0;    ///< exactly collinear corners
  std::size_t needles = 0;            ///< shortest/longest edge < 0.01 (and not zero area)
  std::size_t caps = 0;               ///< an angle above 177° (and not zero area, not a needle)
  std::size_t tiny_components = 0;    ///< open components with < 0.5% of the total area
  std::size_t gaps = 0;               ///< boundary vertices within the gap tolerance of another boundary's edge
  double gap_tolerance = 0;           ///< mm
};

/// Measures every defect class. \param self_intersections the exact O(F log F) test (slowest part).
DefectReport find_defects(const TriangleSoup& soup, bool self_intersections = true);
nlohmann::json to_json(const DefectReport& report);

struct CleanStats {
  std::size_t duplicate_faces_removed = 0;   ///< same corners (either orientation: both copies of an opposed pair go)
  std::size_t degenerate_faces_removed = 0;  ///< repeated corners or zero area
  std::size_t tiny_components_removed = 0;
  std::size_t unreferenced_vertices_removed = 0;
  std::size_t faces_flipped = 0;             ///< to agree with their neighbours or to point outward
  bool edge_manifold = true;                 ///< no edge with more than two faces remains
};

/// Cleans `soup` in place (see the file comment). Orientation: faces are made consistent across
/// manifold edges; each closed component then points outward, or inward when it lies inside
/// another one (a cavity).
CleanStats clean(TriangleSoup& soup);

}  // namespace s2c::repair
