#include <gtest/gtest.h>

#include <malloc.h>
#include <sys/resource.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

#include "s2c/core/memory.h"

namespace {

long minor_page_faults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

/// Page faults taken while a block of `bytes` is allocated, written and freed.
long faults_to_fill(std::size_t bytes) {
  const long before = minor_page_faults();
  char* block = static_cast<char*>(std::malloc(bytes));
  if (!block) return -1;
  std::memset(block, 1, bytes);
  asm volatile("" : : "r"(block) : "memory");  // the block is used: no malloc/free pair to drop
  std::free(block);
  return minor_page_faults() - before;
}

}  // namespace

// Under AddressSanitizer malloc is ASan's own, which keeps freed blocks in a quarantine and takes
// no mallopt: there is nothing of glibc's to test.
#if defined(__SANITIZE_ADDRESS__)
#define S2C_OWN_MALLOC 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define S2C_OWN_MALLOC 1
#endif
#endif

TEST(Memory, FreedBlocksComeBackWithoutPageFaults) {
#ifdef S2C_OWN_MALLOC
  GTEST_SKIP() << "malloc is AddressSanitizer's";
#endif
  constexpr std::size_t kBytes = 64u << 20;  // 16,384 pages, above glibc's largest mmap threshold
  constexpr long kPages = kBytes / 4096;
  // glibc's default: a block this large is mapped afresh each time, every page faulted in again.
  faults_to_fill(kBytes);
  EXPECT_GT(faults_to_fill(kBytes), kPages / 2);
  s2c::reuse_freed_memory();
  faults_to_fill(kBytes);  // the heap grows once
  EXPECT_LT(faults_to_fill(kBytes), kPages / 20);
}

// The warmer faults a block in on its own thread and hands it back to malloc: the next blocks
// of the main thread come without faults, beyond what the heap held before.
TEST(Memory, HeapWarmerLeavesTheHeapFaultedIn) {
#ifdef S2C_OWN_MALLOC
  GTEST_SKIP() << "malloc is AddressSanitizer's";
#endif
  constexpr std::size_t kBytes = 96u << 20;
  constexpr long kPages = kBytes / 4096;
  s2c::reuse_freed_memory();
  faults_to_fill(kBytes);  // whatever the heap held before, it now holds this much
  EXPECT_LT(faults_to_fill(kBytes), kPages / 20);
  EXPECT_GT(faults_to_fill(2 * kBytes), kPages / 2);  // beyond it: fresh pages
  { s2c::HeapWarmer warm(4 * kBytes); }
  const long faults = faults_to_fill(3 * kBytes);
  EXPECT_LT(faults, kPages / 20);
}

namespace {

/// kB of anonymous memory of this process on 2 MB pages (/proc/self/smaps_rollup).
long anon_huge_kb() {
  FILE* f = std::fopen("/proc/self/smaps_rollup", "r");
  if (!f) return -1;
  char line[256];
  long kb = -1;
  while (std::fgets(line, sizeof line, f))
    if (std::sscanf(line, "AnonHugePages: %ld kB", &kb) == 1) break;
  std::fclose(f);
  return kb;
}

}  // namespace

// Where the kernel offers transparent huge pages, the warmer's block is on 2 MB pages: the
// block's worth of them appears in the process, and filling it afterwards takes almost no faults
// (one per 2 MB at most where the kernel had none to give).
TEST(Memory, HeapWarmerUsesHugePagesWhereTheKernelHasThem) {
#ifdef S2C_OWN_MALLOC
  GTEST_SKIP() << "malloc is AddressSanitizer's";
#endif
  if (!s2c::transparent_huge_pages()) GTEST_SKIP() << "transparent huge pages are off on this machine";
  constexpr std::size_t kBytes = 128u << 20;
  s2c::reuse_freed_memory();
  malloc_trim(0);  // what earlier tests left faulted in goes back: the block is fresh memory
  const long before = anon_huge_kb();
  ASSERT_GE(before, 0) << "no AnonHugePages line in /proc/self/smaps_rollup";
  bool huge = false;
  {
    s2c::HeapWarmer warm(kBytes);
    huge = warm.huge_pages();
  }
  ASSERT_TRUE(huge);
  // At least an eighth of it: the kernel may be short of free 2 MB blocks (without the advice
  // there are none at all in `madvise` mode).
  EXPECT_GT(anon_huge_kb() - before, static_cast<long>(kBytes / 1024 / 8));
  EXPECT_LT(faults_to_fill(kBytes / 2), static_cast<long>(kBytes / 4096 / 20));
}
