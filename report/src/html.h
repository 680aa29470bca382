#pragma once
// Small builders for the report's HTML: escaping, tables, and the inline SVG charts (colour
// legend, histogram). Inline SVG keeps the page self-contained and crisp at any zoom.
#include <string>
#include <vector>

#include "s2c/report/deviation.h"

namespace s2c::report::html {

std::string escape(const std::string& text);

/// A number with a sensible number of digits for a table ("0.0123", "1234.5", "2.1e+06").
std::string number(double value);

/// <table> with a header row; cells are HTML already (escape text yourself).
std::string table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows,
                  const std::string& css_class = "");

/// A "yes"/"no" badge (green/red).
std::string badge(bool ok, const std::string& yes = "yes", const std::string& no = "no");

/// Vertical colour bar of deviation_colour over [−range, range] with tick labels in mm.
std::string legend_svg(double range);

/// Area-weighted histogram (see report::histogram) as bars coloured like the map, x axis in mm.
std::string histogram_svg(const std::vector<double>& shares, double range);

/// The CSS of the page.
const char* stylesheet();

}  // namespace s2c::report::html
