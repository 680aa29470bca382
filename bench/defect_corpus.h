#pragma once
/// \file Deterministic defective variants of a clean closed mesh, for tests and benchmarks of the
/// repair stage (bench/make_defects.cpp is the command line around it).
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <string>
#include <vector>

#include "s2c/core/check.h"
#include "s2c/core/mesh.h"

namespace s2c::bench {

struct DefectOptions {
  std::uint64_t seed = 1;
  /// The clean mesh is first refined (longest-edge bisection) until no edge is longer than
  /// this, mm, so that defects stay local on CAD meshes with long facets; 0 = bbox diagonal / 40.
  double edge_length = 0;
  /// Separation of the two sides of the gap, mm.
  double gap = 0.02;
};

/// One variant: the soup and what was put into it.
struct DefectVariant {
  std::string name;                            ///< file stem: holes, nested, flipped, ...
  TriangleSoup soup;
  std::map<std::string, std::size_t> defects;  ///< e.g. {"holes": 2}
  CheckResult check;                           ///< check_mesh of `soup` (verified to show the defects)
};

struct DefectCorpus {
  TriangleSoup clean;        ///< the refined clean mesh every variant starts from
  double edge_length = 0;    ///< mm, the refinement target used
  std::vector<DefectVariant> variants;
};

/// Variants (in this order): holes (two geodesic face discs removed), nested (two face discs
/// touching at one vertex, and an outer hole with an island of faces touching it at one
/// vertex), flipped (a face patch with reversed orientation), duplicates (5 faces twice),
/// gap (cut along a plane section, one side moved off by `gap`, not welded), self_intersections
/// (a small patch pushed through the opposite wall), loose (3 tiny isolated triangles), and
/// everything (all of them in one mesh, at separate places). Every variant is checked with
/// check_mesh to hold exactly its defects; a placement that does not is retried elsewhere.
/// Same input and options give the same output, bit for bit.
/// \throw InvalidInput if `clean` is not closed and edge-manifold or too small to place them.
DefectCorpus make_defect_corpus(const TriangleSoup& clean, const DefectOptions& options = {});

/// Writes a soup as binary little-endian PLY (double coordinates) exactly as it is: unlike
/// write_mesh, which goes through OpenMesh, it keeps non-manifold vertices and duplicate faces.
/// Atomic (temporary file + rename). \throw IoError
void write_soup_ply(const TriangleSoup& soup, const std::filesystem::path& path);

}  // namespace s2c::bench
