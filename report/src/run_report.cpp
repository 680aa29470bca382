#include "s2c/report/run_report.h"

#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <chrono>
#include <ctime>
#include <map>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "html.h"
#include "s2c/core/check.h"
#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "s2c/core/io.h"
#include "s2c/core/version.h"
#include "s2c/features/feature_set.h"
#include "s2c/report/layers.h"
#include "soup_util.h"

namespace s2c::report {
namespace fs = std::filesystem;
using nlohmann::json;

namespace {

/// One stage of the manifest: its status and the files its command names.
struct StageInfo {
  json entry;
  std::vector<std::string> args;
  bool ok() const { return entry.value("status", "") == "ok"; }
  /// The value after `flag`, or the first positional argument for flag "".
  std::string arg(const std::string& flag) const {
    if (flag.empty()) return args.empty() ? "" : args.front();
    for (std::size_t i = 0; i + 1 < args.size(); ++i)
      if (args[i] == flag) return args[i + 1];
    return "";
  }
};

/// The run's files: a stage's file as its command named it, or (when the run folder was moved
/// or the report is made from another directory) the file of that name in the run folder.
std::optional<fs::path> locate(const fs::path& run_dir, const std::string& named) {
  if (named.empty()) return std::nullopt;
  if (fs::exists(named)) return fs::path(named);
  const fs::path local = run_dir / fs::path(named).filename();
  if (fs::exists(local)) return local;
  return std::nullopt;
}

/// A path segment as it may stand in a URL (the pictures folder is named after the page).
std::string url_segment(const std::string& name) {
  std::string out;
  for (unsigned char c : name) {
    if (std::isalnum(c) || c == '.' || c == '_' || c == '-')
      out += char(c);
    else
      out += fmt::format("%{:02X}", c);
  }
  return out;
}

/// At most `max` bytes of UTF-8 text, cut at a character boundary, with an ellipsis when cut.
std::string shorten(const std::string& text, std::size_t max) {
  if (text.size() <= max) return text;
  std::size_t n = max;
  while (n > 0 && (static_cast<unsigned char>(text[n]) & 0xC0) == 0x80) --n;
  return text.substr(0, n) + "…";
}

/// A report's pictures folder holds this file: only such a folder is ever replaced.
constexpr const char* kPicturesMarker = ".scan2cad-report";

json read_json_or_null(const fs::path& path) {
  if (!fs::exists(path)) return nullptr;
  try {
    return json::parse(read_file(path));
  } catch (const json::exception&) {
    return nullptr;
  }
}

/// One picture set: a caption, a file stem and the rendered views.
struct Figure {
  std::string title, caption;
  std::vector<std::pair<std::string, std::string>> images;  // (file name, view name)
};

class Builder {
 public:
  explicit Builder(const RunReportOptions& o)
      : o_(o),
        out_dir_(o.output.parent_path().empty() ? fs::path(".") : o.output.parent_path()),
        pictures_name_(o.output.stem().string() + "_files") {
    pictures_tmp_ = out_dir_ / fmt::format(".{}.tmp-{}", pictures_name_, ::getpid());
  }
  const fs::path& pictures_tmp() const { return pictures_tmp_; }
  /// The page must be .html and its pictures folder new or a report's own (never someone's folder).
  void check_output() const {
    std::string ext = o_.output.extension().string();
    for (auto& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (ext != ".html" && ext != ".htm")
      throw InvalidInput(fmt::format("{}: the report is HTML: use a .html name", o_.output.string()));
    const fs::path pictures = out_dir_ / pictures_name_;
    if (fs::exists(pictures) && !fs::exists(pictures / kPicturesMarker))
      throw InvalidInput(fmt::format("{} exists and is not the pictures folder of a scan2cad report; choose another -o",
                                     pictures.string()));
  }

  RunReportResult build(json* counts);

 private:
  void load_manifest();
  std::optional<StageInfo> stage(const std::string& name) const {
    auto it = stages_.find(name);
    if (it == stages_.end()) return std::nullopt;
    return it->second;
  }
  /// reports/NAME.json of a stage that ran successfully (else null: an old report would describe
  /// another run's outputs).
  json stage_report(const std::string& name) const {
    const auto s = stage(name);
    if (!s || !s->ok()) return nullptr;
    return read_json_or_null(o_.run_dir / "reports" / (name + ".json"));
  }
  void publish(const std::string& page);
  /// A mesh or cloud of the run, each file read once (repaired.ply is usually the features' mesh
  /// and the final mesh too); nullptr without a path. allow_empty as read_soup's.
  const TriangleSoup* soup(const std::optional<fs::path>& path, bool allow_empty) {
    if (!path) return nullptr;
    const fs::path key = fs::weakly_canonical(*path);
    auto it = soups_.find(key);
    if (it == soups_.end()) it = soups_.emplace(key, read_soup(*path, allow_empty)).first;
    if (!allow_empty && it->second.faces.empty()) read_soup(*path, false);  // throws its "no faces" error
    return &it->second;
  }
  std::optional<fs::path> stage_file(const std::string& name, const std::string& flag) const {
    const auto s = stage(name);
    if (!s || !s->ok()) return std::nullopt;
    return locate(o_.run_dir, s->arg(flag));
  }
  void picture(Scene& scene, const std::string& stem, const std::string& title, const std::string& caption);
  /// One picture from `view` with its own framing and options (a close-up).
  void picture(Scene& scene, const std::string& stem, const std::string& title, const std::string& caption,
               const View& view, const Bounds& box, const RenderOptions& options);
  std::string stages_section() const;
  std::string defects_section() const;
  std::string features_section() const;
  std::string check_section() const;
  std::string deviation_section() const;
  std::string stage_details_section() const;

  const RunReportOptions& o_;
  json manifest_;
  std::map<std::string, StageInfo> stages_;
  std::vector<std::string> stage_order_;
  fs::path out_dir_, pictures_tmp_;
  std::string pictures_name_;
  int deviation_figure_ = -1;
  Bounds frame_;
  std::vector<Figure> figures_;
  RunReportResult result_;
  json raw_defects_, repaired_defects_;  // CheckResult as JSON (scan2cad check's keys)
  json check_json_, repair_report_;
  std::map<fs::path, TriangleSoup> soups_;
  std::optional<features::FeatureSet> features_;
  std::optional<Deviation> deviation_;
  double filled_area_ = 0, edited_area_ = 0, changed_threshold_ = 0;
  std::string reference_name_;
};

void Builder::load_manifest() {
  const fs::path path = o_.run_dir / "manifest.json";
  if (!fs::exists(path))
    throw InvalidInput(fmt::format("{}: no manifest.json: not a scan2cad run folder (scan2cad run INPUT --out {} makes one)",
                                   o_.run_dir.string(), o_.run_dir.string()));
  try {
    manifest_ = json::parse(read_file(path));
  } catch (const json::exception& e) {
    throw InvalidInput(fmt::format("{}: not valid JSON ({})", path.string(), e.what()));
  }
  if (!manifest_.is_object() || !manifest_.contains("stages") || !manifest_["stages"].is_array())
    throw InvalidInput(fmt::format("{}: no \"stages\" array: not a scan2cad manifest", path.string()));
  for (const auto& s : manifest_["stages"]) {
    if (!s.is_object() || !s.contains("name") || !s["name"].is_string()) continue;
    StageInfo info{s, {}};
    if (s.contains("command") && s["command"].is_array())
      for (const auto& a : s["command"])
        if (a.is_string()) info.args.push_back(a.get<std::string>());
    const std::string name = s["name"].get<std::string>();
    stage_order_.push_back(name);
    stages_[name] = std::move(info);
  }
}

void Builder::picture(Scene& scene, const std::string& stem, const std::string& title, const std::string& caption) {
  if (scene.empty()) return;
  scene.frame(frame_);
  Figure fig{title, caption, {}};
  for (const std::string& v : o_.views) {
    const View view = view_named(v);
    const std::string file = fmt::format("{}_{}.png", stem, view.name == "custom" ? std::to_string(fig.images.size()) : view.name);
    write_png(scene.render(view, o_.render), pictures_tmp_ / file);
    fig.images.emplace_back(file, view.name);
    ++result_.pictures;
  }
  figures_.push_back(std::move(fig));
}

void Builder::picture(Scene& scene, const std::string& stem, const std::string& title, const std::string& caption,
                      const View& view, const Bounds& box, const RenderOptions& options) {
  scene.frame(box);
  const std::string file = stem + ".png";
  write_png(scene.render(view, options), pictures_tmp_ / file);
  figures_.push_back(Figure{title, caption, {{file, view.name}}});
  ++result_.pictures;
}

RunReportResult Builder::build(json* counts) {
  check_output();
  load_manifest();
  for (const auto& v : o_.views) view_named(v);  // bad names fail before any work

  // The meshes of the run, as the stages named them.
  const auto cloud_path = stage_file("reconstruct", "--cloud-out");
  std::optional<fs::path> raw_path = stage_file("reconstruct", "-o");
  if (!raw_path && stage("repair")) raw_path = locate(o_.run_dir, stage("repair")->arg(""));
  const auto repaired_path = stage_file("repair", "-o");
  const auto features_path = stage_file("features", "-o");
  const auto features_mesh_path = stage("features") ? locate(o_.run_dir, stage("features")->arg("")) : std::nullopt;
  const auto edited_path = stage_file("edit", "-o");
  std::optional<fs::path> final_path = stage("check") ? locate(o_.run_dir, stage("check")->arg("")) : std::nullopt;
  if (!final_path) final_path = edited_path ? edited_path : repaired_path ? repaired_path : raw_path;
  if (!final_path && !cloud_path)
    throw InvalidInput(fmt::format("{}: the run has no mesh or cloud yet (did its first stage fail? see manifest.json)",
                                   o_.run_dir.string()));

  const TriangleSoup* raw = soup(raw_path, true);
  const TriangleSoup* repaired = soup(repaired_path, true);
  const TriangleSoup* final_mesh = soup(final_path, true);
  const TriangleSoup* cloud = soup(cloud_path, true);
  const TriangleSoup* features_mesh = features_path || edited_path ? soup(features_mesh_path, false) : nullptr;
  const TriangleSoup* reference = nullptr;
  if (!o_.reference.empty()) {
    if (!fs::exists(o_.reference)) throw InvalidInput(fmt::format("{}: reference part not found", o_.reference.string()));
    reference = soup(o_.reference, false);
    reference_name_ = o_.reference.filename().string();
  }

  // Every picture frames the same box, so that they compare at a glance.
  if (final_mesh && !final_mesh->faces.empty())
    frame_ = bounds(*final_mesh);
  else if (raw && !raw->faces.empty())
    frame_ = bounds(*raw);
  else if (cloud_path)
    frame_ = vertex_bounds(cloud->vertices);

  fs::remove_all(pictures_tmp_);
  fs::create_directories(pictures_tmp_);
  write_file_atomic(pictures_tmp_ / kPicturesMarker, "pictures of " + o_.output.filename().string() + "\n");

  if (cloud && !cloud->vertices.empty()) {
    Scene s;
    s.add(cloud_layer(*cloud));
    picture(s, "cloud", "Scan", fmt::format("The fused scan: {} points{}.", cloud->vertices.size(),
                                             cloud->normals.empty() ? "" : " with normals"));
  }
  if (raw && !raw->faces.empty()) {
    Scene s;
    s.add(MeshLayer{*raw, {}, {}, kMeshGrey});
    picture(s, "mesh", "Raw mesh",
            fmt::format("{} as meshed: {} faces. Dark red = the inside of the surface, seen through a hole.",
                        raw_path->filename().string(), raw->faces.size()));
  }
  if (repaired && !repaired->faces.empty()) {
    Scene s;
    changed_threshold_ = 1.5 * median_edge_length(*repaired);
    ChangedRegions filled = changed_regions(*repaired, raw ? *raw : TriangleSoup{}, changed_threshold_, kFilledOrange);
    result_.filled_faces = filled.faces;
    filled_area_ = filled.area;
    std::optional<Scene> closeup;
    if (filled.largest) {
      closeup.emplace();
      closeup->add(filled.layer);
    }
    s.add(std::move(filled.layer));
    picture(s, "repaired", "Repaired mesh",
            fmt::format("Orange: surface the repair added where the raw mesh had none (holes filled, gaps closed): "
                        "{} faces, {} mm² in {} regions (faces farther than {} mm from the raw mesh).",
                        result_.filled_faces, html::number(filled_area_), filled.regions, html::number(changed_threshold_)));
    if (closeup) {
      // The largest added region seen along its normal, whatever is in front of it cut away.
      const double half = std::max(0.5 * filled.largest->diagonal(), 0.03 * frame_.diagonal()) * 1.8;
      const Eigen::Vector3d c = filled.largest->center();
      const Bounds box{c - Eigen::Vector3d::Constant(half), c + Eigen::Vector3d::Constant(half)};
      RenderOptions options = o_.render;
      options.cutaway = true;
      picture(*closeup, "repaired_closeup", "Largest added region (close-up)",
              fmt::format("The largest region the repair added, {} mm across, seen along its normal; surfaces in "
                          "front of it are cut away.",
                          html::number(filled.largest->diagonal())),
              View{"close-up", filled.largest_normal}, box, options);
    }
  }
  if (features_path && features_mesh) {
    features_ = features::read_features(*features_path);
    Scene s;
    add_features(s, *features_mesh, *features_);
    picture(s, "features", "Features",
            fmt::format("Patches by type: planes blue, cylinders green, cones orange, spheres purple, freeform grey. "
                        "Feature lines: straight black, circles and arcs dark red. {} patches, {} lines.",
                        features_->patches.size(), features_->lines.size()));
  }
  if (edited_path && features_mesh) {
    const double threshold = std::max(1e-3, 0.5 * median_edge_length(*features_mesh));
    ChangedRegions moved = changed_regions(*soup(edited_path, false), *features_mesh, threshold, kEditedPurple);
    result_.edited_faces = moved.faces;
    edited_area_ = moved.area;
    Scene s;
    s.add(std::move(moved.layer));
    picture(s, "edited", "Edited result",
            fmt::format("Purple: surface the edit script moved (farther than {} mm from the mesh before the edit): {} faces.",
                        html::number(threshold), result_.edited_faces));
  }
  if (reference && final_mesh && !final_mesh->faces.empty()) {
    deviation_ = signed_deviation(*final_mesh, *reference);
    result_.deviation = deviation_->stats;
    result_.deviation_range = o_.range > 0 ? o_.range : default_range(deviation_->stats);
    Scene s;
    s.add(deviation_layer(*final_mesh, *deviation_, result_.deviation_range));
    deviation_figure_ = int(figures_.size());
    picture(s, "deviation", "Deviation from the reference",
            fmt::format("{} against {}: signed distance, positive = outside the true part.",
                        final_path->filename().string(), reference_name_));
  }

  // Defects before and after repair: as the repair's report counted them (the same check as
  // `scan2cad check`), or checked here when the repair did not run.
  if (const auto check_path = stage_file("check", "-o")) check_json_ = read_json_or_null(*check_path);
  repair_report_ = stage_report("repair");
  if (repair_report_.is_object() && repair_report_.contains("counts")) {
    raw_defects_ = repair_report_["counts"].value("defects_before", json());
    repaired_defects_ = repair_report_["counts"].value("defects_after", json());
  }
  if (!raw_defects_.is_object() && raw && !raw->faces.empty()) raw_defects_ = json::parse(to_json(check_mesh(*raw)));

  // The page.
  std::string page = "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">"
                     "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">";
  const std::string input = manifest_.contains("input") ? manifest_["input"].value("path", "") : "";
  page += fmt::format("<title>scan2cad report — {}</title><style>{}</style></head><body>\n",
                      html::escape(input), html::stylesheet());
  const std::time_t now = std::time(nullptr);
  char when[64];
  std::strftime(when, sizeof when, "%Y-%m-%d %H:%M", std::localtime(&now));
  page += fmt::format("<header><h1>scan2cad report</h1><p>{} · scan2cad {} · {}</p></header><main>\n",
                      html::escape(input), kVersion, when);

  // Summary cards.
  page += "<div class=\"cards\">";
  auto card = [&](const std::string& value, const std::string& key) {
    page += fmt::format("<div class=\"card\"><div class=\"v\">{}</div><div class=\"k\">{}</div></div>", value, key);
  };
  if (check_json_.is_object())
    card(html::badge(check_json_.value("cad_ready", false), "CAD-ready", "not CAD-ready"), "final mesh");
  if (final_mesh) card(html::number(double(final_mesh->faces.size())), "faces in the final mesh");
  if (deviation_) card(html::number(deviation_->stats.rms) + " mm", "RMS deviation from " + html::escape(reference_name_));
  if (features_) card(fmt::format("{} / {}", features_->patches.size(), features_->lines.size()), "patches / feature lines");
  double total = 0;
  for (const auto& [name, st] : stages_) total += st.entry.value("seconds", 0.0);
  card(html::number(total) + " s", "stage time (this run)");
  page += "</div>\n";

  page += "<section><h2>Pictures</h2><p class=\"muted\">Ray traced on the CPU (Embree); every picture frames the "
          "same box (the final mesh's) from the same viewpoints.</p>";
  for (const auto& fig : figures_) {
    page += fmt::format("<h3>{}</h3><div class=\"pictures\">", html::escape(fig.title));
    for (const auto& [file, view] : fig.images)
      page += fmt::format("<figure><img src=\"{}/{}\" width=\"{}\" height=\"{}\" alt=\"{} ({} view)\"><figcaption>{} view</figcaption></figure>",
                          html::escape(url_segment(pictures_name_)), html::escape(url_segment(file)), o_.render.width, o_.render.height,
                          html::escape(fig.title), html::escape(view), html::escape(view));
    page += fmt::format("</div><p class=\"muted\">{}</p>\n", html::escape(fig.caption));
  }
  page += "</section>\n";
  if (deviation_) page += deviation_section();
  page += stages_section();
  page += defects_section();
  page += check_section();
  page += features_section();
  page += stage_details_section();
  page += "</main></body></html>\n";

  publish(page);

  if (counts) {
    (*counts)["pictures"] = result_.pictures;
    (*counts)["filled_faces"] = result_.filled_faces;
    (*counts)["filled_area_mm2"] = filled_area_;
    (*counts)["edited_faces"] = result_.edited_faces;
    if (deviation_) {
      const auto& d = deviation_->stats;
      (*counts)["deviation"] = {{"min_mm", d.min},   {"max_mm", d.max},       {"mean_mm", d.mean},
                                {"mean_abs_mm", d.mean_abs}, {"rms_mm", d.rms}, {"max_abs_mm", d.max_abs},
                                {"p95_abs_mm", d.p95_abs}, {"range_mm", result_.deviation_range}, {"area_mm2", d.area}};
    }
  }
  return result_;
}

/// Pictures first, then the page that refers to them. The old pictures folder is kept aside
/// until the new page is written, and put back if that fails.
void Builder::publish(const std::string& page) {
  const fs::path pictures_dir = out_dir_ / pictures_name_;
  const fs::path aside = out_dir_ / fmt::format(".{}.old-{}", pictures_name_, ::getpid());
  const bool had_old = fs::exists(pictures_dir);
  if (had_old) fs::rename(pictures_dir, aside);
  try {
    fs::rename(pictures_tmp_, pictures_dir);
    write_file_atomic(o_.output, page);
  } catch (...) {
    std::error_code ec;
    if (had_old) {
      fs::remove_all(pictures_dir, ec);
      fs::rename(aside, pictures_dir, ec);
    }
    throw;
  }
  std::error_code ec;
  if (had_old) fs::remove_all(aside, ec);
  result_.pictures_dir = pictures_dir;
}

std::string Builder::deviation_section() const {
  const auto& s = deviation_->stats;
  const double range = result_.deviation_range;
  std::string out = fmt::format("<section><h2>Deviation from {}</h2>", html::escape(reference_name_));
  out += "<p class=\"muted\">Signed distance of every vertex of the final mesh to the true part (positive = "
         "material outside the part, negative = inside), area-weighted. The reference is used in the scan's "
         "coordinates (no best-fit alignment).</p><div class=\"deviation\">";
  if (deviation_figure_ >= 0 && !figures_[deviation_figure_].images.empty())
    out += fmt::format("<figure><img src=\"{}/{}\" width=\"{}\" height=\"{}\" alt=\"deviation map\"></figure>",
                       html::escape(url_segment(pictures_name_)),
                       html::escape(url_segment(figures_[deviation_figure_].images.front().first)), o_.render.width,
                       o_.render.height);
  out += html::legend_svg(range);
  out += "<div>" + html::histogram_svg(histogram(*deviation_, range, 40), range);
  auto mm = [](double v) { return html::number(v) + " mm"; };
  out += html::table({"statistic", "value"},
                     {{"max |d|", mm(s.max_abs)},
                      {"min / max", mm(s.min) + " / " + mm(s.max)},
                      {"mean (signed)", mm(s.mean)},
                      {"mean |d|", mm(s.mean_abs)},
                      {"RMS", mm(s.rms)},
                      {"95% of the area within", mm(s.p95_abs)},
                      {"colour range", "±" + mm(range)},
                      {"vertices / area", fmt::format("{} / {} mm²", s.vertices, html::number(s.area))}});
  return out + "</div></div></section>\n";
}

std::string Builder::stages_section() const {
  std::vector<std::vector<std::string>> rows;
  for (const auto& name : stage_order_) {
    const json& e = stages_.at(name).entry;
    const std::string status = e.value("status", "?");
    std::string shown = status == "ok" ? html::badge(true, e.value("skipped", false) ? "up to date" : "ok")
                        : status == "failed" ? html::badge(false, "", "failed")
                                             : html::escape(status + (e.contains("reason") ? " (" + e.value("reason", "") + ")" : ""));
    std::string steps;
    const json rep = stage_report(name);
    if (rep.is_object() && rep.contains("timings_s") && rep["timings_s"].is_object())
      for (const auto& [k, v] : rep["timings_s"].items())
        if (v.is_number()) steps += fmt::format("{}{} {} s", steps.empty() ? "" : ", ", html::escape(k), html::number(v.get<double>()));
    rows.push_back({html::escape(name), shown,
                    e.contains("seconds") && e["seconds"].is_number() ? html::number(e["seconds"].get<double>()) : "–",
                    steps});
  }
  return "<section><h2>Stages</h2>" + html::table({"stage", "status", "seconds", "steps (seconds)"}, rows) +
         "<p class=\"muted\">“up to date”: skipped because its inputs and options did not change since the run that made "
         "its outputs (times are that run's).</p></section>\n";
}

std::string Builder::defects_section() const {
  if (!raw_defects_.is_object() && !repaired_defects_.is_object()) return "";
  auto cell = [](const json& c, const char* key) -> std::string {
    if (!c.is_object() || !c.contains(key)) return "–";
    if (c[key].is_boolean()) return html::badge(c[key].get<bool>());
    return c[key].is_number() ? html::number(c[key].get<double>()) : "–";
  };
  std::vector<std::vector<std::string>> rows;
  const std::pair<const char*, const char*> defects[] = {
      {"boundary_loops", "boundary loops (holes, gaps)"}, {"boundary_edges", "boundary edges"},
      {"nonmanifold_edges", "non-manifold edges"},        {"nonmanifold_vertices", "non-manifold vertices"},
      {"orientation_conflicts", "orientation conflicts"}, {"components", "components"},
      {"self_intersections", "self-intersecting face pairs"}, {"degenerate_faces", "degenerate faces"},
      {"duplicate_faces", "duplicate faces"},             {"closed", "closed"},
      {"oriented", "oriented outward"},                   {"cad_ready", "CAD-ready"}};
  for (const auto& [key, label] : defects) rows.push_back({label, cell(raw_defects_, key), cell(repaired_defects_, key)});
  std::string out = "<section><h2>Defects found and fixed</h2>" +
                    html::table({"defect", "raw mesh", "repaired mesh"}, rows);
  out += fmt::format("<p class=\"muted\">Surface added by the repair: {} faces, {} mm² (orange in the pictures).</p>",
                     result_.filled_faces, html::number(filled_area_));
  if (repair_report_.is_object() && repair_report_.contains("counts") && repair_report_["counts"].is_object()) {
    std::vector<std::vector<std::string>> c;
    for (const auto& [k, v] : repair_report_["counts"].items())
      if (v.is_number() || v.is_boolean() || v.is_string()) c.push_back({html::escape(k), html::escape(v.dump())});
    if (!c.empty()) out += "<details><summary>What the repair counted</summary>" + html::table({"count", "value"}, c) + "</details>";
  }
  return out + "</section>\n";
}

std::string Builder::check_section() const {
  if (!check_json_.is_object()) return "";
  std::vector<std::vector<std::string>> rows;
  auto flag = [&](const char* key, bool want) {
    if (check_json_.contains(key) && check_json_[key].is_boolean())
      rows.push_back({key, html::badge(check_json_[key].get<bool>() == want, check_json_[key].dump(), check_json_[key].dump())});
  };
  auto zero = [&](const char* key) {
    if (check_json_.contains(key) && check_json_[key].is_number())
      rows.push_back({key, html::badge(check_json_[key].get<double>() == 0, check_json_[key].dump(), check_json_[key].dump())});
  };
  flag("cad_ready", true);
  flag("closed", true);
  flag("oriented", true);
  for (const char* k : {"boundary_loops", "nonmanifold_edges", "nonmanifold_vertices", "self_intersections", "degenerate_faces"})
    zero(k);
  if (check_json_.contains("components")) rows.push_back({"components", html::escape(check_json_["components"].dump())});
  std::string out = "<section><h2>CAD-ready check of the final mesh</h2>" + html::table({"check", "result"}, rows);
  if (check_json_.contains("problems") && check_json_["problems"].is_array() && !check_json_["problems"].empty()) {
    out += "<ul>";
    for (const auto& p : check_json_["problems"])
      if (p.is_string()) out += "<li>" + html::escape(p.get<std::string>()) + "</li>";
    out += "</ul>";
  }
  return out + "</section>\n";
}

std::string vec(const Eigen::Vector3d& v) {
  auto c = [](double x) { return std::abs(x) < 5e-5 ? 0.0 : x; };  // no "-0.0000"
  return fmt::format("({:.4f}, {:.4f}, {:.4f})", c(v.x()), c(v.y()), c(v.z()));
}

std::string shape_parameters(const features::Shape& s) {
  using features::ShapeType;
  switch (s.type) {
    case ShapeType::plane: return "normal " + vec(s.dir) + ", point " + vec(s.point);
    case ShapeType::cylinder: return "radius " + html::number(s.radius) + " mm, axis " + vec(s.dir) + " through " + vec(s.point);
    case ShapeType::sphere: return "radius " + html::number(s.radius) + " mm, centre " + vec(s.point);
    case ShapeType::cone: return "half angle " + html::number(s.half_angle_deg) + "°, apex " + vec(s.point) + ", axis " + vec(s.dir);
    case ShapeType::line: return "length " + html::number(s.length) + " mm, from " + vec(s.point) + " along " + vec(s.dir);
    case ShapeType::circle: return "radius " + html::number(s.radius) + " mm, centre " + vec(s.point) + ", normal " + vec(s.dir);
    case ShapeType::arc:
      return "radius " + html::number(s.radius) + " mm, " + html::number(s.angle_deg) + "°, centre " + vec(s.point);
    default: return "";
  }
}

std::string Builder::features_section() const {
  if (!features_) return "";
  constexpr std::size_t kRows = 150;  // the rest is in features.json
  std::string out = "<section><h2>Features</h2>";
  std::vector<std::vector<std::string>> rows;
  for (std::size_t i = 0; i < features_->patches.size() && i < kRows; ++i) {
    const auto& p = features_->patches[i];
    rows.push_back({html::escape(p.id), features::shape_name(p.shape.type), html::escape(shape_parameters(p.shape)),
                    html::number(p.area), html::number(p.rms), std::to_string(p.faces.size())});
  }
  out += fmt::format("<h3>Patches ({})</h3>", features_->patches.size()) +
         html::table({"id", "type", "fitted parameters", "area mm²", "RMS mm", "faces"}, rows);
  rows.clear();
  for (std::size_t i = 0; i < features_->lines.size() && i < kRows; ++i) {
    const auto& l = features_->lines[i];
    rows.push_back({html::escape(l.id), features::shape_name(l.shape.type), html::escape(shape_parameters(l.shape)),
                    html::number(l.rms), std::to_string(l.vertices.size()), l.closed ? "closed" : "open"});
  }
  out += fmt::format("<h3>Feature lines ({})</h3>", features_->lines.size()) +
         html::table({"id", "type", "fitted parameters", "RMS mm", "vertices", ""}, rows);
  rows.clear();
  std::size_t constraints = 0;
  for (const auto& g : features_->groups) {
    if (!g.constraint) continue;
    if (++constraints > kRows) continue;
    std::string members;
    for (const auto& m : g.members) members += (members.empty() ? "" : ", ") + m;
    rows.push_back({html::escape(g.id), features::constraint_name(*g.constraint), html::escape(members),
                    g.value ? html::number(*g.value) : ""});
  }
  out += fmt::format("<h3>Constraints ({})</h3>", constraints) + html::table({"id", "kind", "between", "value"}, rows);
  if (features_->patches.size() > kRows || features_->lines.size() > kRows || constraints > kRows)
    out += fmt::format("<p class=\"muted\">The first {} of each are listed; features.json has them all.</p>", kRows);
  return out + "</section>\n";
}

std::string Builder::stage_details_section() const {
  std::string out = "<section><h2>Parameters and counts per stage</h2><p class=\"muted\">From each stage's --report "
                    "(reports/STAGE.json in the run folder).</p>";
  for (const auto& name : stage_order_) {
    const json rep = stage_report(name);
    if (!rep.is_object()) continue;
    std::vector<std::vector<std::string>> rows;
    for (const char* part : {"parameters", "counts"})
      if (rep.contains(part) && rep[part].is_object())
        for (const auto& [k, v] : rep[part].items()) {
          const std::string text = shorten(v.dump(), 157);
          rows.push_back({part, html::escape(k), html::escape(text)});
        }
    if (!rows.empty())
      out += fmt::format("<details><summary>{}</summary>{}</details>", html::escape(name), html::table({"", "key", "value"}, rows));
  }
  return out + "</section>\n";
}

}  // namespace

RunReportResult write_run_report(const RunReportOptions& options, json* counts) {
  Builder builder(options);
  // No partial output: the pictures' temporary folder goes with any failure.
  auto discard = [&] {
    std::error_code ec;
    fs::remove_all(builder.pictures_tmp(), ec);
  };
  try {
    return builder.build(counts);
  } catch (const json::exception& e) {
    discard();
    throw InvalidInput(fmt::format("{}: a JSON file of the run has unexpected content ({})", options.run_dir.string(), e.what()));
  } catch (const fs::filesystem_error& e) {
    discard();
    throw IoError(e.what());
  } catch (...) {
    discard();
    throw;
  }
}

}  // namespace s2c::report
