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

/// Builds the report. Stages that did not run or failed are absent from the page (their old
/// files and reports are not used). \throw InvalidInput when run_dir has no readable manifest.json,
/// a run file has unexpected content, the reference is unreadable, the output is not .html or its
/// pictures folder exists and is not a report's; IoError when the output cannot be written.
/// A failure leaves the previous report (if any) and no temporary files.
RunReportResult write_run_report(const RunReportOptions& options, nlohmann::json* counts = nullptr);

}  // namespace s2c::report
