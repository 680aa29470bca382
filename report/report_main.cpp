// scan2cad-report: report.html of a `scan2cad run` folder (the run's last stage; also stand-alone).
#include <nlohmann/json.hpp>
#include <spdlog/spdlog.h>

#include "s2c/core/cli.h"
#include "s2c/core/errors.h"
#include "s2c/core/report.h"
#include "s2c/report/run_report.h"

int main(int argc, char** argv) {
  CLI::App app{
      "Write report.html for a scan2cad run folder: pictures of the scan cloud, the raw mesh, the repaired\n"
      "mesh (added surface in orange), the features (patches by type, feature lines) and the edited\n"
      "result, ray traced on the CPU; tables of stage timings, defects before and after repair, features\n"
      "with their fitted parameters and constraints, and the CAD-ready check. With --reference, a\n"
      "deviation colour map of the final mesh against the true part, with legend, histogram and\n"
      "max/mean/RMS. The page and its pictures (REPORT_files/) open offline in any browser.\n"
      "scan2cad run does this as its last stage.\n"
      "Example: scan2cad report out -o out/report.html --reference part.stl",
      "scan2cad-report"};
  s2c::CommonOptions common;
  s2c::report::RunReportOptions o;
  std::string run_dir, output, reference, views;
  app.add_option("RUN_DIR", run_dir, "Folder of a scan2cad run (with manifest.json)")->required();
  app.add_option("-o,--output", output, "HTML file to write (default: RUN_DIR/report.html)");
  app.add_option("--reference", reference, "True part (.stl .ply .obj .off), in the scan's coordinates");
  app.add_option("--range", o.range, "Deviation colour range ±mm (default: from the data)")->check(CLI::PositiveNumber);
  app.add_option("--width", o.render.width, "Picture width, pixels")->check(CLI::Range(64, 4096))->capture_default_str();
  app.add_option("--height", o.render.height, "Picture height, pixels")->check(CLI::Range(64, 4096))->capture_default_str();
  s2c::add_common_options(app, common);
  if (int rc = s2c::parse_command_line(app, argc, argv); rc >= 0) return rc;
  s2c::init_logging("scan2cad-report", common);

  return s2c::run_guarded([&] {
    o.run_dir = run_dir;
    o.output = output.empty() ? o.run_dir / "report.html" : std::filesystem::path(output);
    o.reference = reference;
    s2c::Report report("scan2cad-report");
    report.parameters() = {{"run_dir", run_dir}, {"output", o.output.string()}, {"reference", reference},
                           {"width", o.render.width}, {"height", o.render.height}, {"range_mm", o.range}};
    s2c::report::RunReportResult r;
    {
      s2c::Report::Step t(report, "report");
      r = s2c::report::write_run_report(o, &report.counts());
    }
    spdlog::info("{}: {} pictures in {}", o.output.string(), r.pictures, r.pictures_dir.string());
    if (r.deviation)
      spdlog::info("deviation from {}: RMS {:.4f} mm, mean {:+.4f} mm, max |d| {:.4f} mm", reference, r.deviation->rms,
                   r.deviation->mean, r.deviation->max_abs);
    report.write(common.report);
  });
}
