// scan2cad: git-style dispatcher. `scan2cad STAGE args…` runs `scan2cad-STAGE args…` from the
// folder this executable lives in.
#include <unistd.h>

#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include "s2c/core/errors.h"
#include "s2c/core/version.h"

namespace fs = std::filesystem;

namespace {

struct StageInfo {
  const char* name;
  const char* summary;
};

const StageInfo kStages[] = {
    {"run", "the whole pipeline on a stream, cloud or mesh: INPUT --out DIR"},
    {"simulate", "scan a part with a virtual depth camera or laser scanner → stream"},
    {"acquire", "record a stream from a V4L2 depth camera, a USB laser scanner or a replay"},
    {"reconstruct", "stream or cloud → fused cloud and mesh (PCL)"},
    {"repair", "holes, gaps, defects and volumetric repair → CAD-ready mesh"},
    {"features", "feature lines, patches, fitted shapes and constraints → features.json"},
    {"edit", "apply an edit script (.s2e) to a mesh and its features"},
    {"check", "is a mesh CAD-ready? one JSON object on stdout"},
    {"render", "a shaded picture of a mesh or cloud (PNG); features or deviation colours"},
    {"report", "report.html of a run folder: pictures of every stage, tables, deviation map"},
};

fs::path self_dir() {
  std::error_code ec;
  fs::path p = fs::read_symlink("/proc/self/exe", ec);
  return ec ? fs::path(".") : p.parent_path();
}

void usage(FILE* out) {
  std::fprintf(out,
               "scan2cad %s: scan-to-CAD pipeline\n\n"
               "Usage: scan2cad STAGE [options]    (scan2cad STAGE --help for a stage's options)\n\n"
               "Stages:\n",
               s2c::kVersion);
  const fs::path dir = self_dir();
  for (const auto& s : kStages) {
    const bool present = fs::exists(dir / (std::string("scan2cad-") + s.name));
    std::fprintf(out, "  %-12s %s%s\n", s.name, s.summary, present ? "" : "  [not in this build]");
  }
  std::fprintf(out,
               "\nExit codes: 0 success, 2 bad usage or bad input, 3 processing failed, 4 device or I/O failure.\n"
               "Quick start: scan2cad run fixtures/scans/plate --out out\n");
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 2 || !std::strcmp(argv[1], "--help") || !std::strcmp(argv[1], "-h") || !std::strcmp(argv[1], "help")) {
    usage(stdout);
    return argc < 2 ? s2c::kExitBadInput : s2c::kExitOk;
  }
  if (!std::strcmp(argv[1], "--version")) {
    std::printf("scan2cad %s\n", s2c::kVersion);
    return 0;
  }
  const std::string stage = argv[1];
  const fs::path exe = self_dir() / ("scan2cad-" + stage);
  if (stage.find('/') != std::string::npos || !fs::exists(exe)) {
    std::fprintf(stderr, "scan2cad: error: '%s' is not a stage%s. Run 'scan2cad --help' for the list.\n",
                 stage.c_str(), fs::exists(exe) ? "" : " of this build");
    return s2c::kExitBadInput;
  }
  std::vector<char*> args;
  std::string name = exe.string();
  args.push_back(name.data());
  for (int i = 2; i < argc; ++i) args.push_back(argv[i]);
  args.push_back(nullptr);
  ::execv(exe.c_str(), args.data());
  std::fprintf(stderr, "scan2cad: error: cannot run %s: %s\n", exe.c_str(), std::strerror(errno));
  return s2c::kExitDevice;
}
