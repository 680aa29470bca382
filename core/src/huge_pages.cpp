#include "s2c/core/huge_pages.h"

#include <cstdlib>
#include <string>

namespace s2c {

void request_huge_pages_for_children() {
  const char* current = std::getenv("GLIBC_TUNABLES");
  std::string value = current ? current : "";
  if (value.find("glibc.malloc.hugetlb") != std::string::npos) return;
  if (!value.empty()) value += ':';
  value += "glibc.malloc.hugetlb=1";
  ::setenv("GLIBC_TUNABLES", value.c_str(), 1);
}

}  // namespace s2c
