#include "html.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace s2c::report::html {
namespace {

std::string css_colour(const Colour& c) {
  auto b = [](float x) { return int(std::lround(std::clamp(x, 0.0f, 1.0f) * 255)); };
  return fmt::format("rgb({},{},{})", b(c.x()), b(c.y()), b(c.z()));
}

}  // namespace

std::string escape(const std::string& text) {
  std::string out;
  out.reserve(text.size());
  for (char c : text) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string number(double v) {
  if (!std::isfinite(v)) return "–";
  const double a = std::abs(v);
  if (a == 0) return "0";
  if (a >= 1e6 || a < 1e-4) return fmt::format("{:.3g}", v);
  if (a == std::floor(a) && a < 1e6) return fmt::format("{:.0f}", v);
  if (a >= 100) return fmt::format("{:.1f}", v);
  if (a >= 1) return fmt::format("{:.3f}", v);
  return fmt::format("{:.4f}", v);
}

std::string table(const std::vector<std::string>& header, const std::vector<std::vector<std::string>>& rows,
                  const std::string& css_class) {
  std::string out = css_class.empty() ? "<table>" : fmt::format("<table class=\"{}\">", css_class);
  out += "<thead><tr>";
  for (const auto& h : header) out += "<th>" + h + "</th>";
  out += "</tr></thead><tbody>";
  for (const auto& row : rows) {
    out += "<tr>";
    for (const auto& cell : row) out += "<td>" + cell + "</td>";
    out += "</tr>";
  }
  return out + "</tbody></table>\n";
}

std::string badge(bool ok, const std::string& yes, const std::string& no) {
  return ok ? "<span class=\"ok\">" + escape(yes) + "</span>" : "<span class=\"bad\">" + escape(no) + "</span>";
}

std::string legend_svg(double range) {
  const int height = 300, bar_w = 28, top = 10;
  std::string out = fmt::format(
      "<svg class=\"legend\" xmlns=\"http://www.w3.org/2000/svg\" width=\"130\" height=\"{}\" role=\"img\" "
      "aria-label=\"colour scale, mm\"><defs><linearGradient id=\"dev\" x1=\"0\" y1=\"1\" x2=\"0\" y2=\"0\">",
      height + 2 * top);
  for (int i = 0; i <= 20; ++i) {
    const double t = i / 20.0;
    out += fmt::format("<stop offset=\"{:.2f}\" stop-color=\"{}\"/>", t, css_colour(deviation_colour((2 * t - 1) * range, range)));
  }
  out += fmt::format("</linearGradient></defs><rect x=\"8\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"url(#dev)\" "
                     "stroke=\"#333\"/>",
                     top, bar_w, height);
  for (int i = 0; i <= 8; ++i) {
    const double value = range * (1 - i / 4.0);
    const double y = top + height * i / 8.0;
    out += fmt::format("<line x1=\"{}\" y1=\"{:.1f}\" x2=\"{}\" y2=\"{:.1f}\" stroke=\"#333\"/>", 8 + bar_w, y, 14 + bar_w, y);
    out += fmt::format("<text x=\"{}\" y=\"{:.1f}\" font-size=\"12\" dominant-baseline=\"middle\">{}{:g} mm</text>",
                       18 + bar_w, y, value > 0 ? "+" : "", std::abs(value) < 1e-12 ? 0.0 : value);
  }
  return out + "</svg>";
}

std::string histogram_svg(const std::vector<double>& shares, double range) {
  const int bins = int(shares.size()) - 2;
  const int width = 520, height = 220, left = 44, bottom = 36, top = 10, right = 10;
  const double plot_w = width - left - right, plot_h = height - top - bottom;
  const double peak = std::max(1e-9, *std::max_element(shares.begin(), shares.end()));
  std::string out = fmt::format(
      "<svg class=\"histogram\" xmlns=\"http://www.w3.org/2000/svg\" width=\"{}\" height=\"{}\" role=\"img\" "
      "aria-label=\"histogram of the deviation\">",
      width, height);
  const double slot_w = plot_w / (bins + 2);
  for (int i = 0; i < bins + 2; ++i) {
    const double h = plot_h * shares[i] / peak;
    double centre;
    if (i == 0)
      centre = -range * 1.05;
    else if (i == bins + 1)
      centre = range * 1.05;
    else
      centre = -range + (i - 0.5) * 2 * range / bins;
    const std::string fill = (i == 0 || i == bins + 1) ? "#777" : css_colour(deviation_colour(centre, range));
    out += fmt::format("<rect x=\"{:.1f}\" y=\"{:.1f}\" width=\"{:.1f}\" height=\"{:.1f}\" fill=\"{}\"><title>{:.1f}%</title></rect>",
                       left + i * slot_w + 0.5, top + plot_h - h, slot_w - 1, h, fill, 100 * shares[i]);
  }
  out += fmt::format("<line x1=\"{}\" y1=\"{:.1f}\" x2=\"{}\" y2=\"{:.1f}\" stroke=\"#333\"/>", left, top + plot_h,
                     width - right, top + plot_h);
  for (int k = -2; k <= 2; ++k) {
    const double x = left + slot_w + (k + 2) / 4.0 * (plot_w - 2 * slot_w);
    out += fmt::format("<text x=\"{:.1f}\" y=\"{}\" font-size=\"11\" text-anchor=\"middle\">{:g}</text>", x,
                       height - bottom + 16, range * k / 2);
  }
  out += fmt::format("<text x=\"{}\" y=\"{}\" font-size=\"11\" text-anchor=\"middle\">deviation, mm (grey: beyond ±{:g})</text>",
                     left + plot_w / 2, height - 4, range);
  out += fmt::format("<text x=\"4\" y=\"{}\" font-size=\"11\">{:.0f}%</text>", top + 10, 100 * peak);
  return out + "</svg>";
}

const char* stylesheet() {
  return R"(body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0;color:#1d2330;background:#f4f5f7}
header{background:#1d2330;color:#fff;padding:18px 28px}header h1{margin:0;font-size:22px}header p{margin:4px 0 0;color:#c8cdd8}
main{padding:10px 28px 40px;max-width:1400px}section{background:#fff;border-radius:8px;padding:14px 20px;margin:16px 0;box-shadow:0 1px 3px rgba(0,0,0,.08)}
h2{font-size:18px;margin:4px 0 12px}h3{font-size:15px;margin:14px 0 6px}
.cards{display:flex;flex-wrap:wrap;gap:12px}.card{background:#fff;border-radius:8px;padding:12px 18px;min-width:160px;box-shadow:0 1px 3px rgba(0,0,0,.08)}
.card .v{font-size:22px;font-weight:600}.card .k{color:#5b6475;font-size:13px}
.pictures{display:flex;flex-wrap:wrap;gap:10px}figure{margin:0}.pictures figure{flex:1 1 420px;max-width:640px}
figure img{border:1px solid #d5d9e0;border-radius:4px;display:block;width:100%;height:auto}.deviation figure{flex:0 1 640px}
figcaption{font-size:13px;color:#5b6475;margin-top:4px}
table{border-collapse:collapse;font-size:13px;margin:6px 0}th,td{border-bottom:1px solid #e3e6eb;padding:4px 10px;text-align:left;vertical-align:top}
th{background:#f0f2f5}td.n,th.n{text-align:right}.ok{color:#fff;background:#2e8b47;border-radius:3px;padding:1px 6px}
.bad{color:#fff;background:#c0392b;border-radius:3px;padding:1px 6px}.muted{color:#5b6475;font-size:13px}
.deviation{display:flex;flex-wrap:wrap;gap:16px;align-items:flex-start}details{margin:6px 0}summary{cursor:pointer;color:#2b5da8}
code{background:#f0f2f5;padding:1px 4px;border-radius:3px}
)";
}

}  // namespace s2c::report::html
