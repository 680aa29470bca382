// Every input a fuzzer ever crashed on (fuzz/regressions/TARGET/) and every seed
// (fuzz/corpus/TARGET/) goes through its target in the ordinary test run: a fixed crash stays fixed.
#include <filesystem>
#include <fstream>
#include <iterator>
#include <ostream>

#include <gtest/gtest.h>

#include "targets.h"

namespace fs = std::filesystem;

namespace s2c::fuzz {
// Test names and failure messages show the target's name, not its bytes.
void PrintTo(const NamedTarget& t, std::ostream* os) { *os << t.name; }
}  // namespace s2c::fuzz

namespace {

class FuzzInputs : public ::testing::TestWithParam<s2c::fuzz::NamedTarget> {};

TEST_P(FuzzInputs, RunWithoutCrashing) {
  const auto& t = GetParam();
  int files = 0;
  for (const char* kind : {"regressions", "corpus"}) {
    const fs::path dir = fs::path(S2C_SOURCE_DIR) / "fuzz" / kind / t.name;
    if (!fs::is_directory(dir)) continue;
    for (const auto& e : fs::directory_iterator(dir)) {
      if (!e.is_regular_file()) continue;
      std::ifstream in(e.path(), std::ios::binary);
      const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      SCOPED_TRACE(e.path().string());
      t.run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
      ++files;
    }
  }
  EXPECT_GT(files, 0) << "no seeds for " << t.name << " in fuzz/corpus";
}

INSTANTIATE_TEST_SUITE_P(AllTargets, FuzzInputs, ::testing::ValuesIn(s2c::fuzz::all_targets()),
                         [](const auto& param_info) { return std::string(param_info.param.name); });

}  // namespace
