#pragma once
// One CAD edge as one feature line on a noisy mesh. A scan rounds its part's edges, the rounding
// stays a freeform band or falls into crumbs, and the chain along the edge changes its pair of
// patches wherever the band starts, ends or pinches: the pocket scan's top edges came out as
// 20-40 pieces each, 0.2-5 mm long, none of which states the edge's length. The pieces that are
// fitted with the same two shapes' intersection lie on one curve: they are joined across gaps of
// a few edges, and a straight edge's ends move to its corners, where a third plane next to both
// of its patches cuts it.
#include <vector>

#include "lines.h"

namespace s2c::features {

/// Shaped patches that meet along a crease or across a freeform band (both next to it).
class RegionNeighbours {
 public:
  /// From the traced lines' patch pairs (line edges between two patches, and bands' sides).
  RegionNeighbours(const Segmentation& seg, const std::vector<TracedLine>& lines);
  bool adjacent(int a, int b) const;
  const std::vector<int>& of(int r) const { return nbr_[r]; }

 private:
  std::vector<std::vector<int>> nbr_;  ///< sorted
};

/// Gives each piece of `lines` along a band or a crumb (a patch under `min_area` mm², or a freeform
/// one) the two large shaped patches whose intersection it follows: the pair of neighbours of
/// its own patches (or of theirs) whose intersection curve lies within `tolerance` (RMS) of its
/// vertices, the closest. The fit becomes that curve, edge_a / edge_b that pair.
void identify_edges(const MeshArrays& m, const Segmentation& seg, const RegionNeighbours& neighbours, double min_area,
                    double tolerance, std::vector<TracedLine>& lines);

/// Joins the pieces of `lines` that are the same edge (TracedLine::edge_a / edge_b, a line or a
/// circle) across gaps of at most `max_gap` mm where the mesh between them has no patch of
/// `min_area` mm² or more but the edge's two: the joined line has their vertices in order along
/// the curve and the intersection fitted to them, kept when its RMS distance is at most
/// `tolerance`. A circle whose pieces go all the way round is closed.
void join_edge_pieces(const MeshArrays& m, const Segmentation& seg, double min_area, double max_gap, double tolerance,
                      std::vector<TracedLine>& lines);

/// Moves each end of a straight edge (edge_a / edge_b both planes) to its corner: the point where a
/// plane of at least `min_area` mm² next to both of its patches cuts it, within `reach` mm of the
/// end and of that plane's patch.
void end_at_corners(const MeshArrays& m, const Segmentation& seg, const RegionNeighbours& neighbours, double min_area,
                    double reach,
                    std::vector<TracedLine>& lines);

}  // namespace s2c::features
