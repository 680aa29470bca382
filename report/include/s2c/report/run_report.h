#pragma once
/// \file report.html of a `scan2cad run` folder: pictures of every stage, the deviation map
/// against a reference part, and tables (stage timings, defects found and fixed, features and
/// constraints, the CAD-ready check). Self-contained: the HTML plus a folder of PNGs beside it.
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "s2c/report/deviation.h"
#include "s2c/report/render.h"

namespace s2c::report {

struct RunReportOptions {
  std::filesystem::path run_dir;    ///< holds manifest.json (scan2cad run --out)
  std::filesystem::path output;     ///< report.html; the pictures go to <stem>_files/ beside it
  std::filesystem::path reference;  ///< the true part (same coordinates as the scan); empty: no deviation map
  double range = 0;                 ///< deviation colour range ±mm; 0: from the data (default_range)
  RenderOptions render;             ///< picture size
  std::vector<std::string> views = {"iso", "iso-back"};
};

struct RunReportResult {
  int pictures = 0;
  std::optional<DeviationStats> deviation;
  double deviation_range = 0;
  std::size_t filled_faces = 0, edited_faces = 0;
  std::filesystem::path pictures_dir;
};

/// Builds the report. Missing stages (not run, failed) are said so on the page, not an error.
/// \throw InvalidInput when run_dir has no readable manifest.json or the reference is unreadable,
///        IoError when the output cannot be written. Nothing is left behind on failure.
RunReportResult write_run_report(const RunReportOptions& options, nlohmann::json* counts = nullptr);

}  // namespace s2c::report
