#include "targets.h"

#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <optional>

#include "s2c/acquire/decode.h"
#include "s2c/core/errors.h"
#include "s2c/core/io.h"
#include "s2c/core/stream.h"
#include "s2c/edit/editor.h"
#include "s2c/edit/interpreter.h"
#include "s2c/edit/script.h"
#include "s2c/features/analyze.h"
#include "s2c/features/feature_set.h"
#include "s2c/reconstruct/views.h"

namespace fs = std::filesystem;

namespace s2c::fuzz {
namespace {

/// A private scratch folder per process (fuzzers may run in parallel).
const fs::path& scratch() {
  static const fs::path dir = [] {
    fs::path d = fs::temp_directory_path() / ("s2c-fuzz-" + std::to_string(::getpid()));
    fs::create_directories(d);
    return d;
  }();
  return dir;
}

void write(const fs::path& p, const std::uint8_t* data, std::size_t size) {
  std::ofstream f(p, std::ios::binary | std::ios::trunc);
  f.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
}

/// Runs `f`, swallowing the errors bad input is allowed to raise.
template <class F>
void tolerate_bad_input(F&& f) {
  try {
    f();
  } catch (const InvalidInput&) {
  } catch (const IoError&) {
  }
}

std::vector<std::string> split(const std::string& s, const std::string& sep, std::size_t parts) {
  std::vector<std::string> out;
  std::size_t at = 0;
  while (out.size() + 1 < parts) {
    const std::size_t next = s.find(sep, at);
    if (next == std::string::npos) break;
    out.push_back(s.substr(at, next - at));
    at = next + sep.size();
  }
  out.push_back(s.substr(at));
  return out;
}

}  // namespace

void mesh(const std::uint8_t* data, std::size_t size) {
  if (size < 1) return;
  static const char* kExt[] = {".ply", ".stl", ".obj", ".off", ".vtk"};
  const fs::path p = scratch() / (std::string("m") + kExt[data[0] % 5]);
  write(p, data + 1, size - 1);
  tolerate_bad_input([&] {
    TriangleSoup s = read_soup(p, true);
    Mesh m;
    (void)soup_to_mesh(s, m);  // what every stage does next
  });
}

void pcd(const std::uint8_t* data, std::size_t size) {
  const fs::path p = scratch() / "c.pcd";
  write(p, data, size);
  tolerate_bad_input([&] { (void)load_views({p}, InputOptions{}); });
}

void stream(const std::uint8_t* data, std::size_t size) {
  const std::vector<std::string> part = split(std::string(reinterpret_cast<const char*>(data), size), "\n%%\n", 4);
  const fs::path dir = scratch() / "s";
  fs::remove_all(dir);
  fs::create_directories(dir / "depth");
  const char* names[] = {"stream.yaml", "depth.txt", "poses.txt", "depth/000000.png"};
  for (std::size_t i = 0; i < part.size(); ++i)
    write(dir / names[i], reinterpret_cast<const std::uint8_t*>(part[i].data()), part[i].size());
  tolerate_bad_input([&] {
    const Stream s = read_stream(dir);
    for (std::size_t i = 0; i < s.frames.size() && i < 2; ++i) {
      if (s.frames[i].file != "depth/000000.png") continue;
      const DepthImage d = read_frame(s, i);
      (void)s.pose_of(i);
      (void)deproject(s, i, d);
    }
  });
}

void features_json(const std::uint8_t* data, std::size_t size) {
  tolerate_bad_input([&] {
    const features::FeatureSet f = features::from_json_text(std::string(reinterpret_cast<const char*>(data), size), "f.json");
    (void)features::to_json_text(f);
  });
}

void edit_script(const std::uint8_t* data, std::size_t size) {
  // A plate with holes, analysed once: every input runs on a fresh copy of its editor.
  static const std::optional<std::pair<Mesh, features::FeatureSet>> plate = []() -> std::optional<std::pair<Mesh, features::FeatureSet>> {
    const char* src = std::getenv("S2C_FUZZ_PLATE");
    const fs::path path = src ? fs::path(src) : fs::path(S2C_SOURCE_DIR) / "fixtures/parts/plate.stl";
    if (!fs::exists(path)) return std::nullopt;
    Mesh m = read_mesh(path);
    features::Analysis a = features::analyze(m, {});
    return std::make_pair(std::move(m), std::move(a.features));
  }();
  const std::string text(reinterpret_cast<const char*>(data), size);
  try {
    const edit::Script script = edit::parse_script(text, "fuzz.s2e");
    if (!plate) return;
    edit::Editor editor(plate->first, plate->second);
    (void)edit::run_script(script, editor);
  } catch (const InvalidInput&) {
  } catch (const ProcessingError&) {  // a failed assert or an unsatisfiable edit: a valid outcome
  }
}

void usb_profile(const std::uint8_t* data, std::size_t size) {
  const std::optional<Profile> p = decode_profile(data, size);
  if (p) {
    StreamInfo info;
    info.sensor = Sensor::laser;
    info.width = 64;
    info.depth_unit_mm = 0.01;
    info.camera_matrix << 50, 0, 31.5, 0, 50, 0, 0, 0, 1;
    info.profile_step_mm = 0.1;
    SweepAssembler a(info, 4);
    for (int i = 0; i < 5; ++i) {
      Profile q = *p;
      q.sequence += static_cast<std::uint32_t>(i * (1 + (size % 3)));
      (void)a.add(q);
    }
    (void)a.flush();
  }
  if (size >= 2) {
    const int w = 1 + data[0] % 32, h = 1 + data[1] % 32;
    (void)decode_z16(data + 2, size - 2, w, h, 2 * w + (data[0] >> 5) * 2);
  }
}

const std::vector<NamedTarget>& all_targets() {
  static const std::vector<NamedTarget> t = {{"mesh", &mesh},
                                             {"pcd", &pcd},
                                             {"stream", &stream},
                                             {"features_json", &features_json},
                                             {"edit_script", &edit_script},
                                             {"usb_profile", &usb_profile}};
  return t;
}

}  // namespace s2c::fuzz
