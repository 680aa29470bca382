#include "s2c/core/cli.h"

#include <new>

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>

#include "s2c/core/errors.h"
#include "s2c/core/progress.h"
#include "s2c/core/version.h"

namespace s2c {

void add_common_options(CLI::App& app, CommonOptions& o) {
  app.add_option("--report", o.report, "Write a JSON report (parameters, counts, timings per step) to FILE")
      ->type_name("FILE");
  app.add_flag("-q,--quiet", o.quiet, "Print errors only; no progress bars");
  app.add_flag("-v,--verbose", o.verbose, "Print debug messages");
  app.set_version_flag("--version", std::string("scan2cad ") + kVersion);
  app.get_formatter()->column_width(34);
}

int parse_command_line(CLI::App& app, int argc, char** argv) {
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    std::fprintf(stderr, "%s: error: %s\nRun '%s --help' for usage.\n", app.get_name().c_str(), e.what(),
                 app.get_name().c_str());
    return kExitBadInput;
  }
  return -1;
}

void init_logging(const std::string& command, const CommonOptions& o) {
  auto logger = spdlog::stderr_color_mt(command);
  logger->set_pattern(command + ": %^%l%$: %v");
  logger->set_level(o.quiet ? spdlog::level::err : o.verbose ? spdlog::level::debug : spdlog::level::info);
  spdlog::set_default_logger(logger);
  Progress::set_enabled(!o.quiet);
}

int run_guarded(const std::function<void()>& body) {
  try {
    body();
    return kExitOk;
  } catch (const InvalidInput& e) {
    spdlog::error("{}", e.what());
    return kExitBadInput;
  } catch (const ProcessingError& e) {
    spdlog::error("{}", e.what());
    return kExitFailed;
  } catch (const IoError& e) {
    spdlog::error("{}", e.what());
    return kExitDevice;
  } catch (const DeviceError& e) {
    spdlog::error("{}", e.what());
    return kExitDevice;
  } catch (const std::bad_alloc&) {
    spdlog::error("out of memory; try a coarser resolution or a smaller input");
    return kExitFailed;
  } catch (const std::exception& e) {
    spdlog::error("internal error: {}", e.what());
    return kExitFailed;
  }
}

}  // namespace s2c
