#include "s2c/core/memory.h"

#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>

namespace s2c {

void reuse_freed_memory() {
  // Blocks glibc would map on their own (above 128 KB–32 MB) come from the heap, and the heap's
  // free top is kept: both are then handed out again, already faulted in.
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
}

namespace {

constexpr std::uintptr_t kPage = 4096;
constexpr std::uintptr_t kHugePage = std::uintptr_t{2} << 20;

/// madvise(advice) over the whole pages of size `page` inside [p, p + bytes); false when there
/// are none or the call fails.
bool advise_whole_pages(char* p, std::size_t bytes, std::uintptr_t page, int advice) {
  const std::uintptr_t begin = reinterpret_cast<std::uintptr_t>(p);
  const std::uintptr_t first = (begin + page - 1) / page * page, last = (begin + bytes) / page * page;
  return last > first && madvise(reinterpret_cast<void*>(first), last - first, advice) == 0;
}

}  // namespace

bool transparent_huge_pages() {
  std::ifstream f("/sys/kernel/mm/transparent_hugepage/enabled");
  std::string modes;
  std::getline(f, modes);
  return modes.find("[always]") != std::string::npos || modes.find("[madvise]") != std::string::npos;
}

HeapWarmer::HeapWarmer(std::size_t bytes) {
  // Never more than half the memory now free: warming must not push anything out.
  const long free_pages = sysconf(_SC_AVPHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (free_pages > 0 && page > 0) bytes = std::min(bytes, static_cast<std::size_t>(free_pages) * page / 2);
  if (bytes == 0) return;
  // Measured on this VM, 400 MB: 1.0–1.3 s of first writes to 4 KB pages, 0.06 + 0.47 s when
  // populated first (the hypervisor still sees each page's first write), 0.03 s for 2 MB pages
  // populated from memory a process freed a moment before, 0.4–0.7 s after a few seconds
  // without a run (the host backs them afresh; no slower than 4 KB pages then).
  if (transparent_huge_pages()) {
    // Twice the block asks for 2 MB pages, as address space only: what the caller's heap grows
    // into past the estimate then faults in 2 MB at a time as well (the features stage on the
    // anchor, when this was added: 31 k page faults with the block alone, 11 k so). Populating
    // only maps pages and writes nothing, so malloc may hand the block out at once.
    char* reserve = static_cast<char*>(std::malloc(2 * bytes));
    if (reserve && advise_whole_pages(reserve, 2 * bytes, kHugePage, MADV_HUGEPAGE)) {
      block_ = reserve;
      bytes_ = bytes;
      huge_ = true;
    }
    std::free(reserve);
  }
  if (!huge_) {
    // Taken on this thread, so from the main heap, where the arrays the caller allocates next
    // come from; only the faulting happens on the other.
    block_ = static_cast<char*>(std::malloc(bytes));
    if (!block_) return;
    bytes_ = bytes;
  }
  toucher_ = std::thread([this] { warm_chunks(); });
}

void HeapWarmer::warm_chunks() {
  // 16 MB chunks: small enough for the two threads to share out the end of the block evenly,
  // large enough that taking one costs nothing.
  constexpr std::size_t kChunk = std::size_t{16} << 20;
  for (std::size_t c; (c = next_chunk_.fetch_add(1)) * kChunk < bytes_;) {
    char* chunk = block_ + c * kChunk;
    const std::size_t length = std::min(kChunk, bytes_ - c * kChunk);
    // One call maps all the pages without a fault each (Linux ≥ 5.14; where it fails the writes
    // below fault them as usual). Measured here on 512 MB: 1.55 s of page-by-page first writes,
    // against 0.1 s for the call and 0.7 s for the writes after it, which the hypervisor still
    // sees for the first time.
    advise_whole_pages(chunk, length, kPage, MADV_POPULATE_WRITE);
    if (huge_) continue;  // mapped, and no longer ours to write to
    for (std::size_t i = 0; i < length; i += kPage) chunk[i] = 0;
  }
}

HeapWarmer::~HeapWarmer() {
  if (block_) warm_chunks();
  if (toucher_.joinable()) toucher_.join();
  if (!huge_) std::free(block_);
}

}  // namespace s2c
