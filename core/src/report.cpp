#include "s2c/core/report.h"

#include <nlohmann/json.hpp>

#include "s2c/core/files.h"
#include "s2c/core/version.h"

namespace s2c {

struct Report::Impl {
  nlohmann::json doc;
};

Report::Report(std::string command) : impl_(std::make_unique<Impl>()) {
  impl_->doc = {{"command", std::move(command)},
                {"version", kVersion},
                {"parameters", nlohmann::json::object()},
                {"counts", nlohmann::json::object()},
                {"timings_s", nlohmann::json::object()}};
}
Report::~Report() = default;

nlohmann::json& Report::json() { return impl_->doc; }
nlohmann::json& Report::parameters() { return impl_->doc["parameters"]; }
nlohmann::json& Report::counts() { return impl_->doc["counts"]; }

void Report::add_time(const std::string& step, double seconds) {
  auto& t = impl_->doc["timings_s"];
  t[step] = t.value(step, 0.0) + seconds;
}

void Report::write(const std::filesystem::path& path) const {
  if (path.empty()) return;
  write_file_atomic(path, impl_->doc.dump(2) + "\n");
}

}  // namespace s2c
