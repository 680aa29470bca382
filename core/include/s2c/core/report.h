#pragma once
/// \file The `--report FILE` JSON every command writes: parameters used, counts, timings per step.
#include <chrono>
#include <filesystem>
#include <memory>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "s2c/core/clock.h"

namespace s2c {

class Report {
 public:
  /// `command` is the executable name, e.g. "scan2cad-check".
  explicit Report(std::string command);
  ~Report();
  Report(const Report&) = delete;
  Report& operator=(const Report&) = delete;

  /// The whole document: {"command", "version", "parameters": {}, "counts": {}, "timings_s": {}, ...}.
  /// Include <nlohmann/json.hpp> to use it.
  nlohmann::json& json();
  nlohmann::json& parameters();
  nlohmann::json& counts();
  /// Adds `seconds` to the timing of `step`.
  void add_time(const std::string& step, double seconds);
  /// Writes the document atomically (no-op if `path` is empty). \throw IoError
  void write(const std::filesystem::path& path) const;

  /// Times a scope into a step of the report.
  class Step {
   public:
    Step(Report& r, std::string name) : report_(r), name_(std::move(name)), start_(std::chrono::steady_clock::now()) {}
    ~Step() { report_.add_time(name_, seconds_since(start_)); }
    Step(const Step&) = delete;
    Step& operator=(const Step&) = delete;

   private:
    Report& report_;
    std::string name_;
    std::chrono::steady_clock::time_point start_;
  };

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace s2c
