#pragma once
/// \file Registration of the views of a scan into one frame.
/// With recorded poses: each view is refined against the union of its nearest neighbours
/// (generalized ICP, coarse to fine), in passes over all views, so the error of one pair is
/// shared out instead of piling up around a turntable loop. Without poses: FPFH features + SampleConsensusPrerejective give a
/// global alignment of each view to the views placed so far, refined the same way.
#include <string>
#include <vector>

#include "s2c/reconstruct/views.h"

namespace s2c {

enum class RegistrationMode { automatic, refine, global, off };

struct RegistrationOptions {
  RegistrationMode mode = RegistrationMode::automatic;  ///< automatic: refine if poses exist, else global
  int rounds = 2;             ///< multi-view refinement passes
  int neighbours = 4;         ///< views each view is refined against (nearest sensor positions)
  double min_overlap = 0.2;   ///< share of a view's points that must find a partner
  double max_correction_deg = 10;  ///< refinement moving a recorded pose further is distrusted
};

struct ViewAlignment {
  std::string name;
  double rms_mm = 0;       ///< point-to-plane residual against the other views
  double overlap = 0;      ///< share of points within 3 spacings of another view
  double corrected_mm = 0, corrected_deg = 0;  ///< how far registration moved the recorded pose
  bool rejected = false;
  std::string reason;      ///< why rejected, or what was kept
};

/// Returns a sensor-to-world pose per view (view 0 fixes the frame when there are no poses).
/// Rejected views are flagged in `report` and must not be fused.
/// \throw ProcessingError when fewer than one view can be placed.
std::vector<Eigen::Isometry3d> register_views(const std::vector<View>& views, double spacing_mm,
                                              const RegistrationOptions& options, std::vector<ViewAlignment>& report);

}  // namespace s2c
