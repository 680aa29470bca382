#pragma once
/// \file What every scan2cad executable shares: common options, logging, and the mapping of
/// exceptions to the exit codes of DESIGN.md. Included by main.cpp files only (CLI11 is header-only).
#include <functional>
#include <string>

#include <CLI/CLI.hpp>

namespace s2c {

struct CommonOptions {
  std::string report;   ///< --report FILE
  bool quiet = false;   ///< --quiet: only errors
  bool verbose = false; ///< --verbose: debug messages
};

/// Adds --report, --quiet, --verbose and --version to `app`.
void add_common_options(CLI::App& app, CommonOptions& options);

/// Parses the command line; prints help (exit 0) or the usage error (exit 2).
/// Returns -1 when the command should go on, else the exit code to return.
int parse_command_line(CLI::App& app, int argc, char** argv);

/// Configures logging ("scan2cad-X: level: message" on stderr) and progress bars.
void init_logging(const std::string& command, const CommonOptions& options);

/// Runs `body`, mapping InvalidInput→2, ProcessingError→3, IoError/DeviceError→4 (and any other
/// exception or out-of-memory→3), with the message on stderr. Returns the exit code.
int run_guarded(const std::function<void()>& body);

}  // namespace s2c
