#pragma once
// The `scan2cad run` driver: plans the stages that apply to an input, runs each as a child
// process, and keeps manifest.json so that re-runs skip stages whose inputs, options and
// outputs are unchanged.
#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace s2c::app {

enum class InputKind { stream, cloud, mesh };

/// `--from SPEC`: record first (the acquire stage, into OUT/stream), then run on the recording.
struct AcquireStage {
  std::string from;                   // v4l2:/dev/videoN | usb:VID:PID | replay:DIR; empty: no acquire stage
  std::filesystem::path calibration;  // live devices
  std::uint64_t frames = 0;           // 0: until the source ends (replay) or Ctrl-C
};

struct RunOptions {
  std::filesystem::path input, out_dir;  // input is OUT/stream when acquire.from is set
  AcquireStage acquire;
  std::filesystem::path edit_script;  // empty: no edit stage
  std::filesystem::path reference;    // empty: no deviation map
  std::filesystem::path bin_dir;      // where the scan2cad-* executables are
  std::string mesher = "poisson";      // reconstruct --method: poisson | imls
  bool force = false;
  bool quiet = false;
};

struct StageResult {
  std::string name, status;  // ok | skipped (up to date) | unavailable | failed
  int exit_code = 0;
  double seconds = 0;
};

struct RunResult {
  std::vector<StageResult> stages;
  int exit_code = 0;  // the failed stage's exit code, else 0
  std::filesystem::path final_mesh;
};

/// What an input is: a stream directory, a point cloud (.pcd, or .ply without faces) or a mesh.
/// \throw InvalidInput naming the path when it is none of these.
InputKind classify_input(const std::filesystem::path& input);

/// Runs the pipeline. \throw InvalidInput for a bad input or out dir, IoError for manifest I/O.
RunResult run_pipeline(const RunOptions& options);

/// SHA-256 of a file, or of a directory as the hash of its sorted (relative path, file hash) list.
std::string hash_path(const std::filesystem::path& path);

}  // namespace s2c::app
