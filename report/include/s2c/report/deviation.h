#pragma once
/// \file Deviation of a measured mesh from a reference part, as metrology software shows it:
/// the signed distance of every measured vertex to the reference surface (positive outside the
/// material), area-weighted statistics, a histogram and a colour map.
#include <string>
#include <vector>

#include "s2c/core/mesh.h"
#include "s2c/report/render.h"

namespace s2c::report {

struct DeviationStats {
  double min = 0, max = 0;       ///< signed extremes, mm
  double mean = 0;               ///< signed, area-weighted, mm
  double mean_abs = 0, rms = 0;  ///< area-weighted, mm
  double max_abs = 0;
  double p95_abs = 0;            ///< 95% of the area is closer than this, mm
  double area = 0;               ///< measured area, mm²
  std::size_t vertices = 0;
};

struct Deviation {
  std::vector<double> distance;  ///< signed, per measured vertex, mm (NaN for unreferenced vertices)
  std::vector<double> weight;    ///< vertex area (a third of the adjacent faces' areas), mm²
  DeviationStats stats;
};

/// Signed distances from the measured vertices to the reference surface. The sign comes from
/// the angle-weighted pseudo-normal at the closest point (Bærentzen & Aanæs), which is right at
/// edges and corners too, where a face normal would give speckles of the wrong sign. "Outside"
/// is taken from the reference's enclosed volume, so an inward-wound reference gives the same signs.
/// \throw InvalidInput when the reference has no faces.
Deviation signed_deviation(const TriangleSoup& measured, const TriangleSoup& reference);

/// A colour scale symmetric about 0: blue (−range) → cyan → green (0) → yellow → red (+range),
/// clamped beyond the range.
Colour deviation_colour(double distance, double range);

/// A round colour-scale range for `stats`: 1.25 × the 95th percentile of |distance| rounded up
/// to 1, 2 or 5 × 10^k mm (so that a few outliers do not wash out the map), at least 0.001 mm.
double default_range(const DeviationStats& stats);

/// Area-weighted histogram over [−range, range] in `bins` equal bins plus the two overflows:
/// shares of the area in [0, 1]; first = below −range, last = above +range.
std::vector<double> histogram(const Deviation& deviation, double range, int bins);

}  // namespace s2c::report
