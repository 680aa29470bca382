#pragma once
/// \file Exception types shared by every stage and the exit codes they map to (DESIGN.md).
#include <stdexcept>
#include <string>

namespace s2c {

/// Process exit codes of every scan2cad executable.
enum ExitCode : int {
  kExitOk = 0,
  kExitBadInput = 2,   ///< bad usage or bad input (the message names the file and what is wrong)
  kExitFailed = 3,     ///< processing failed (e.g. a failed assert, an unsatisfiable edit)
  kExitDevice = 4,     ///< device or I/O failure
};

/// The input (a file, an option, a script) is malformed or unusable. Exit code 2.
struct InvalidInput : std::runtime_error {
  using std::runtime_error::runtime_error;
};
/// Reading or writing a file failed for reasons outside the content (permissions, disk full). Exit code 4.
struct IoError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
/// An algorithm could not produce a valid result from valid input. Exit code 3.
struct ProcessingError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
/// A capture device failed (vanished, wrong format, timeout). Exit code 4.
struct DeviceError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

}  // namespace s2c
