// scan2cad-run: the whole pipeline in one command.
#include <filesystem>

#include <spdlog/spdlog.h>

#include "s2c/core/cli.h"
#include "s2c/core/errors.h"
#include "src/pipeline.h"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
  CLI::App app{
      "Run every stage that applies to INPUT and leave the results in DIR:\n"
      "  stream dir or cloud → reconstruct → mesh.ply (+ cloud.ply) → repair → repaired.ply\n"
      "  → features → features.json → edit (with --edit) → edited.ply; check.json says if it is CAD-ready;\n"
      "  report.html (+ report_files/) shows every stage; with --reference, the deviation from the true part.\n"
      "manifest.json records each stage's command, input/output hashes, timings and status.\n"
      "Re-running skips stages whose inputs and options are unchanged; a failed stage stops the run\n"
      "and keeps earlier outputs. Stages not in this build are reported and skipped.\n"
      "With --from, a recording is made first (the acquire stage) into DIR/stream.\n"
      "Examples: scan2cad run fixtures/scans/plate --out out --reference fixtures/parts/plate.stl\n"
      "          scan2cad run --from v4l2:/dev/video2 --calibration cam.yaml --frames 300 --out out",
      "scan2cad-run"};
  s2c::CommonOptions common;
  s2c::app::RunOptions o;
  std::string input, out, edit, reference;
  auto* input_opt = app.add_option("INPUT", input, "Stream directory, point cloud (.ply .pcd) or mesh (.ply .stl .obj .off)");
  auto* from_opt = app.add_option("--from", o.acquire.from,
                                  "Record first with `scan2cad acquire` (v4l2:/dev/videoN | usb:VID:PID | replay:DIR) "
                                  "into DIR/stream, then run on the recording")
                       ->excludes(input_opt);
  input_opt->excludes(from_opt);
  app.add_option("--calibration", o.acquire.calibration, "With --from a live device: its calibration (docs/acquire.md)")
      ->needs(from_opt);
  app.add_option("--frames", o.acquire.frames, "With --from: frames to record (0 = until the source ends or Ctrl-C)")
      ->needs(from_opt);
  app.add_option("--out", out, "Output directory (created if missing)")->required();
  app.add_option("--edit", edit, "Edit script (.s2e) to apply to the repaired mesh");
  app.add_option("--reference", reference, "The true part (same coordinates as the scan), for a deviation map in report.html");
  app.add_option("--mesher", o.mesher,
                 "Reconstruction mesher: poisson (PCL's Poisson, trimmed) or imls (implicit moving least squares "
                 "on a sparse grid: 2-4x faster reconstruction, made for scans whose noise is small against the point spacing; README's reconstruct section has the trade-off)")
      ->check(CLI::IsMember({"poisson", "imls"}))->capture_default_str();
  app.add_flag("--force", o.force, "Run every stage even if up to date");
  s2c::add_common_options(app, common);
  if (int rc = s2c::parse_command_line(app, argc, argv); rc >= 0) return rc;
  s2c::init_logging("scan2cad-run", common);
  if (input.empty() && o.acquire.from.empty()) {
    spdlog::error("give INPUT (a stream, cloud or mesh) or --from SOURCE to record one; see --help");
    return s2c::kExitBadInput;
  }

  int stage_rc = 0;
  const int rc = s2c::run_guarded([&] {
    // Absolute paths in the stages' commands: the manifest (and the report, which finds the
    // run's files through it) then means the same files from any working directory.
    auto absolute = [](const std::string& p) { return p.empty() ? fs::path() : fs::absolute(p); };
    o.input = o.acquire.from.empty() ? absolute(input) : absolute(out) / "stream";
    o.out_dir = absolute(out);
    o.edit_script = absolute(edit);
    o.reference = absolute(reference);
    o.quiet = common.quiet;
    std::error_code ec;
    o.bin_dir = fs::read_symlink("/proc/self/exe", ec).parent_path();
    const auto r = s2c::app::run_pipeline(o);
    stage_rc = r.exit_code;
    if (!common.report.empty()) {
      // The manifest is the run's report.
      fs::copy_file(fs::path(out) / "manifest.json", common.report, fs::copy_options::overwrite_existing);
    }
  });
  return rc != 0 ? rc : stage_rc;
}
