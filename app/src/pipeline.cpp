#include "pipeline.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <fstream>
#include <sstream>

#include <fmt/format.h>
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "s2c/core/clock.h"
#include "s2c/core/errors.h"
#include "s2c/core/files.h"
#include "s2c/core/io.h"
#include "s2c/core/version.h"

extern char** environ;
namespace fs = std::filesystem;
using nlohmann::json;

namespace s2c::app {
namespace {

struct Stage {
  std::string name;
  std::string executable;            // scan2cad-<x>
  std::vector<std::string> args;     // after the executable
  std::vector<fs::path> inputs;      // hashed to decide whether to re-run
  std::vector<fs::path> outputs;     // must exist afterwards
  fs::path stdout_to;                // capture stdout into this file (atomically), if set
};

bool ply_has_faces(const fs::path& p) {
  std::ifstream f(p, std::ios::binary);
  std::string line;
  while (std::getline(f, line)) {
    if (line.rfind("end_header", 0) == 0) break;
    std::istringstream ls(line);
    std::string kw, name;
    std::uint64_t n = 0;
    if ((ls >> kw >> name >> n) && kw == "element" && name == "face") return n > 0;
  }
  return false;
}

// Runs argv with stdout optionally redirected to a file; returns the exit code (128+signal).
int spawn_and_wait(const std::vector<std::string>& argv, const fs::path& stdout_file) {
  std::vector<char*> cargv;
  for (const auto& a : argv) cargv.push_back(const_cast<char*>(a.c_str()));
  cargv.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  if (!stdout_file.empty())
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, stdout_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  pid_t pid = 0;
  const int err = posix_spawn(&pid, cargv[0], &actions, nullptr, cargv.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  if (err) throw IoError(fmt::format("cannot start {}: {}", argv[0], std::strerror(err)));
  int status = 0;
  while (waitpid(pid, &status, 0) < 0)
    if (errno != EINTR) throw IoError(fmt::format("waiting for {} failed: {}", argv[0], std::strerror(errno)));
  if (WIFEXITED(status)) return WEXITSTATUS(status);
  return 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

json hashes_of(const std::vector<fs::path>& paths) {
  json h = json::object();
  for (const auto& p : paths) h[p.string()] = fs::exists(p) ? hash_path(p) : "";
  return h;
}

bool up_to_date(const json& previous, const Stage& s, const json& command, const json& input_hashes) {
  if (!previous.is_object() || previous.value("status", "") != "ok") return false;
  if (previous.value("command", json()) != command || previous.value("inputs", json()) != input_hashes) return false;
  const json outs = previous.value("outputs", json::object());
  for (const auto& o : s.outputs) {
    // An output that is missing or differs from what was recorded is never trusted.
    if (!fs::exists(o) || !outs.contains(o.string()) || outs[o.string()] != hash_path(o)) return false;
  }
  return true;
}

// Stages whose executable is not in this build are listed (to be reported) but not run, and
// the stages after them take the last artifact that will exist.
std::vector<Stage> plan(const RunOptions& o, InputKind kind, fs::path& final_mesh) {
  const fs::path d = o.out_dir;
  const fs::path reports = d / "reports";
  std::vector<Stage> stages;
  auto available = [&](const std::string& exe) { return fs::exists(o.bin_dir / exe); };
  auto add = [&](Stage s) {
    if (s.name != "check") {
      s.args.push_back("--report");
      s.args.push_back((reports / (s.name + ".json")).string());
    }
    stages.push_back(std::move(s));
    return available(stages.back().executable);
  };
  if (!o.acquire.from.empty()) {
    Stage s{"acquire", "scan2cad-acquire", {"--from", o.acquire.from, "--out", o.input.string()}, {}, {o.input}, {}};
    if (!o.acquire.calibration.empty()) {
      s.args.insert(s.args.end(), {"--calibration", o.acquire.calibration.string()});
      s.inputs.push_back(o.acquire.calibration);
    }
    if (o.acquire.frames) s.args.insert(s.args.end(), {"--frames", std::to_string(o.acquire.frames)});
    // A replay's input is its stream; a live device has none: its recording, once made, is kept
    // and re-used by re-runs (--force records again).
    const std::string replay = "replay:";
    if (o.acquire.from.rfind(replay, 0) == 0) s.inputs.push_back(o.acquire.from.substr(replay.size()));
    add(std::move(s));
  }
  fs::path mesh = kind == InputKind::mesh ? o.input : fs::path();
  if (kind != InputKind::mesh) {
    Stage s{"reconstruct", "scan2cad-reconstruct",
            {o.input.string(), "-o", (d / "mesh.ply").string(), "--cloud-out", (d / "cloud.ply").string()},
            {o.input}, {d / "mesh.ply", d / "cloud.ply"}, {}};
    // Only when asked: the default's command (and so earlier runs' manifests) stays as it was.
    if (o.mesher != "poisson") s.args.insert(s.args.end(), {"--method", o.mesher});
    if (add(std::move(s))) mesh = d / "mesh.ply";
  }
  if (!mesh.empty() && add({"repair", "scan2cad-repair", {mesh.string(), "-o", (d / "repaired.ply").string()}, {mesh},
                            {d / "repaired.ply"}, {}}))
    mesh = d / "repaired.ply";
  fs::path features;
  if (!mesh.empty() && add({"features", "scan2cad-features",
                            {mesh.string(), "-o", (d / "features.json").string(), "--segments-out",
                             (d / "segments.ply").string()},
                            {mesh}, {d / "features.json", d / "segments.ply"}, {}}))
    features = d / "features.json";
  if (!o.edit_script.empty() && !features.empty() &&
      add({"edit", "scan2cad-edit",
           {mesh.string(), "--features", features.string(), "--script", o.edit_script.string(), "-o",
            (d / "edited.ply").string(), "--features-out", (d / "edited.features.json").string()},
           {mesh, features, o.edit_script}, {d / "edited.ply", d / "edited.features.json"}, {}}))
    mesh = d / "edited.ply";
  if (!mesh.empty())
    add({"check", "scan2cad-check", {mesh.string(), "-o", (d / "check.json").string(), "--quiet"}, {mesh},
         {d / "check.json"}, "/dev/null"});
  // Last: the report reads every earlier output (and the manifest) of the run folder.
  if (!mesh.empty()) {
    Stage s{"report", "scan2cad-report", {d.string(), "-o", (d / "report.html").string()}, {mesh},
            {d / "report.html", d / "report_files"}, {}};
    if (!o.reference.empty()) {
      s.args.insert(s.args.end(), {"--reference", o.reference.string()});
      s.inputs.push_back(o.reference);
    }
    add(std::move(s));
  }
  final_mesh = mesh;
  return stages;
}

/// Temporary files of writes a killed run never finished (".NAME.tmp-XXXX.EXT", see AtomicFile;
/// ".NAME.tmp-PID" folders of StreamWriter): never valid outputs, removed before a run.
void remove_stale_temporaries(const fs::path& out_dir) {
  for (const fs::path& dir : {out_dir, out_dir / "reports"}) {
    std::error_code ec;
    if (!fs::is_directory(dir, ec)) continue;
    for (const auto& e : fs::directory_iterator(dir, ec)) {
      const std::string name = e.path().filename().string();
      if (name.size() > 1 && name[0] == '.' && name.find(".tmp-") != std::string::npos) fs::remove_all(e.path(), ec);
    }
  }
}

}  // namespace

std::string hash_path(const fs::path& p) {
  if (!fs::is_directory(p)) return sha256_file(p);
  std::vector<std::pair<std::string, std::string>> entries;
  for (const auto& e : fs::recursive_directory_iterator(p))
    if (e.is_regular_file()) entries.emplace_back(fs::relative(e.path(), p).string(), sha256_file(e.path()));
  std::sort(entries.begin(), entries.end());
  std::string listing;
  for (const auto& [rel, h] : entries) listing += rel + "\t" + h + "\n";
  return sha256_bytes(listing);
}

InputKind classify_input(const fs::path& in) {
  if (!fs::exists(in)) throw InvalidInput(fmt::format("{}: no such file or directory", in.string()));
  if (fs::is_directory(in)) {
    if (fs::exists(in / "stream.yaml")) return InputKind::stream;
    throw InvalidInput(fmt::format("{}: a directory without stream.yaml is not a stream (see docs/formats.md)", in.string()));
  }
  std::string ext = in.extension().string();
  std::transform(ext.begin(), ext.end(), ext.begin(), ::tolower);
  if (ext == ".pcd") return InputKind::cloud;
  if (ext == ".ply") return ply_has_faces(in) ? InputKind::mesh : InputKind::cloud;
  if (ext == ".stl" || ext == ".obj" || ext == ".off") return InputKind::mesh;
  throw InvalidInput(fmt::format("{}: not a stream directory, cloud (.ply .pcd) or mesh (.ply .stl .obj .off)", in.string()));
}

RunResult run_pipeline(const RunOptions& o) {
  const InputKind kind = o.acquire.from.empty() ? classify_input(o.input) : InputKind::stream;
  if (!o.edit_script.empty() && !fs::exists(o.edit_script))
    throw InvalidInput(fmt::format("{}: edit script not found", o.edit_script.string()));
  if (!o.reference.empty()) {  // refused now rather than after every other stage has run
    if (!fs::is_regular_file(o.reference)) throw InvalidInput(fmt::format("{}: reference part not found", o.reference.string()));
    mesh_format(o.reference);
    check_mesh_header(o.reference);
  }
  if (fs::exists(o.out_dir) && !fs::is_directory(o.out_dir))
    throw InvalidInput(fmt::format("{}: --out exists and is not a directory", o.out_dir.string()));
  fs::create_directories(o.out_dir / "reports");
  remove_stale_temporaries(o.out_dir);

  const fs::path manifest_path = o.out_dir / "manifest.json";
  json previous = json::object();
  if (fs::exists(manifest_path)) {
    try {
      previous = json::parse(read_file(manifest_path));
    } catch (const json::exception&) {
      spdlog::warn("{}: unreadable manifest; running every stage", manifest_path.string());
    }
  }
  json prev_stages = json::object();
  if (previous.contains("stages") && previous["stages"].is_array())
    for (const auto& s : previous["stages"])
      if (s.is_object() && s.contains("name")) prev_stages[s["name"].get<std::string>()] = s;

  RunResult result;
  std::vector<Stage> stages = plan(o, kind, result.final_mesh);
  json manifest = {{"format", "scan2cad.manifest/1"},
                   {"version", kVersion},
                   {"input", {{"path", o.acquire.from.empty() ? o.input.string() : o.acquire.from},
                              {"sha256", o.acquire.from.empty() ? hash_path(o.input) : std::string()},
                              {"kind", kind == InputKind::stream ? "stream" : kind == InputKind::cloud ? "cloud" : "mesh"}}},
                   {"stages", json::array()}};
  auto save = [&] { write_file_atomic(manifest_path, manifest.dump(2) + "\n"); };

  bool upstream_ran = false;
  std::size_t index = 0;
  const std::vector<Stage>& with_check = stages;
  for (const Stage& s : with_check) {
    ++index;
    const fs::path exe = o.bin_dir / s.executable;
    StageResult sr{s.name, "", 0, 0};
    json entry = {{"name", s.name}, {"executable", s.executable}};
    std::vector<std::string> argv{exe.string()};
    argv.insert(argv.end(), s.args.begin(), s.args.end());
    const json command = s.args;
    entry["command"] = command;
    bool inputs_present = std::all_of(s.inputs.begin(), s.inputs.end(), [](const fs::path& p) { return fs::exists(p); });
    if (!fs::exists(exe) || !inputs_present) {
      sr.status = "unavailable";
      entry["status"] = sr.status;
      entry["reason"] = !fs::exists(exe) ? "not in this build" : "an input was not produced";
      spdlog::info("[{}/{}] {}: skipped ({})", index, with_check.size(), s.name, entry["reason"].get<std::string>());
      manifest["stages"].push_back(entry);
      result.stages.push_back(sr);
      continue;
    }
    const json input_hashes = hashes_of(s.inputs);
    entry["inputs"] = input_hashes;
    const json prev = prev_stages.value(s.name, json());
    if (!o.force && !upstream_ran && up_to_date(prev, s, command, input_hashes)) {
      sr.status = "skipped";
      entry = prev;
      entry["status"] = "ok";
      entry["skipped"] = true;
      spdlog::info("[{}/{}] {}: up to date", index, with_check.size(), s.name);
    } else {
      spdlog::info("[{}/{}] {}: running {}", index, with_check.size(), s.name, s.executable);
      // A stale output must never survive a re-run that fails. (The recording folder is the
      // pipeline's own: the recorder refuses to write into anything but an empty folder.)
      for (const auto& out : s.outputs) fs::remove_all(out);
      const auto t0 = std::chrono::steady_clock::now();
      sr.exit_code = spawn_and_wait(argv, s.stdout_to);
      sr.seconds = seconds_since(t0);
      entry["seconds"] = sr.seconds;
      entry["exit_code"] = sr.exit_code;
      const bool outputs_ok = std::all_of(s.outputs.begin(), s.outputs.end(), [](const fs::path& p) { return fs::exists(p); });
      if (sr.exit_code != 0 || !outputs_ok) {
        sr.status = "failed";
        entry["status"] = sr.status;
        manifest["stages"].push_back(entry);
        result.stages.push_back(sr);
        result.exit_code = sr.exit_code != 0 ? sr.exit_code : kExitFailed;
        save();
        spdlog::error("stage {} failed (exit {}); earlier outputs in {} are kept. See the message above and {}",
                      s.name, sr.exit_code, o.out_dir.string(), (o.out_dir / "reports" / (s.name + ".json")).string());
        return result;
      }
      sr.status = "ok";
      entry["status"] = sr.status;
      entry["outputs"] = hashes_of(s.outputs);
      upstream_ran = true;
    }
    manifest["stages"].push_back(entry);
    result.stages.push_back(sr);
    save();
  }

  if (result.final_mesh.empty() || std::none_of(result.stages.begin(), result.stages.end(),
                                                   [](const StageResult& r) { return r.status == "ok" || r.status == "skipped"; })) {
    save();
    throw ProcessingError(fmt::format("nothing could be run on {}: the stages it needs are not in this build",
                                      o.input.string()));
  }
  const fs::path check_json = o.out_dir / "check.json";
  if (fs::exists(check_json)) {
    try {
      const json c = json::parse(read_file(check_json));
      spdlog::info("final mesh {}: {}", result.final_mesh.string(),
                   c.value("cad_ready", false) ? "CAD-ready" : "not CAD-ready (see check.json 'problems')");
    } catch (const json::exception&) {
    }
  }
  manifest["final_mesh"] = result.final_mesh.string();
  save();
  return result;
}

}  // namespace s2c::app
