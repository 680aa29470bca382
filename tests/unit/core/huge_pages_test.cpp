// request_huge_pages_for_children: what the stages started by `scan2cad` and `scan2cad run` see.
#include <cstdlib>
#include <optional>
#include <string>

#include <gtest/gtest.h>

#include "s2c/core/huge_pages.h"

namespace {

// Sets GLIBC_TUNABLES for one test and restores the caller's value afterwards.
class TunablesGuard {
 public:
  explicit TunablesGuard(const char* value) {
    if (const char* old = std::getenv("GLIBC_TUNABLES")) saved_ = old;
    if (value) ::setenv("GLIBC_TUNABLES", value, 1);
    else ::unsetenv("GLIBC_TUNABLES");
  }
  ~TunablesGuard() {
    if (saved_) ::setenv("GLIBC_TUNABLES", saved_->c_str(), 1);
    else ::unsetenv("GLIBC_TUNABLES");
  }
  static std::string now() {
    const char* v = std::getenv("GLIBC_TUNABLES");
    return v ? v : "<unset>";
  }

 private:
  std::optional<std::string> saved_;
};

}  // namespace

TEST(HugePages, SetsTheTunableWhenTheVariableIsUnset) {
  TunablesGuard guard(nullptr);
  s2c::request_huge_pages_for_children();
  EXPECT_EQ(TunablesGuard::now(), "glibc.malloc.hugetlb=1");
}

TEST(HugePages, KeepsTheUsersOtherTunables) {
  TunablesGuard guard("glibc.malloc.arena_max=2");
  s2c::request_huge_pages_for_children();
  EXPECT_EQ(TunablesGuard::now(), "glibc.malloc.arena_max=2:glibc.malloc.hugetlb=1");
}

TEST(HugePages, LeavesAnExplicitChoiceAlone) {
  TunablesGuard guard("glibc.malloc.hugetlb=0");
  s2c::request_huge_pages_for_children();
  EXPECT_EQ(TunablesGuard::now(), "glibc.malloc.hugetlb=0");
  s2c::request_huge_pages_for_children();  // and calling it twice adds nothing
  EXPECT_EQ(TunablesGuard::now(), "glibc.malloc.hugetlb=0");
}
