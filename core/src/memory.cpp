#include "s2c/core/memory.h"

#include <malloc.h>
#include <sys/mman.h>
#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>

namespace s2c {

void reuse_freed_memory() {
  // Blocks glibc would map on their own (above 128 KB–32 MB) come from the heap, and the heap's
  // free top is kept: both are then handed out again, already faulted in.
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
}

HeapWarmer::HeapWarmer(std::size_t bytes) {
  // Never more than half the memory now free: warming must not push anything out.
  const long free_pages = sysconf(_SC_AVPHYS_PAGES), page = sysconf(_SC_PAGESIZE);
  if (free_pages > 0 && page > 0) bytes = std::min(bytes, static_cast<std::size_t>(free_pages) * page / 2);
  // Taken on this thread, so from the main heap, where the arrays the caller allocates next come
  // from; only the faulting happens on the other.
  block_ = bytes > 0 ? static_cast<char*>(std::malloc(bytes)) : nullptr;
  if (!block_) return;
  bytes_ = bytes;
  toucher_ = std::thread([this] { warm_chunks(); });
}

void HeapWarmer::warm_chunks() {
  // 16 MB chunks: small enough for the two threads to share out the end of the block evenly,
  // large enough that taking one costs nothing.
  constexpr std::size_t kChunk = std::size_t{16} << 20;
  constexpr std::uintptr_t kPage = 4096;
  for (std::size_t c; (c = next_chunk_.fetch_add(1)) * kChunk < bytes_;) {
    char* chunk = block_ + c * kChunk;
    const std::size_t length = std::min(kChunk, bytes_ - c * kChunk);
    const std::uintptr_t begin = reinterpret_cast<std::uintptr_t>(chunk);
    const std::uintptr_t first = (begin + kPage - 1) / kPage * kPage, last = (begin + length) / kPage * kPage;
    // One call maps all the pages without a fault each (Linux ≥ 5.14; where it fails the writes
    // below fault them as usual). Measured here on 512 MB: 1.55 s of page-by-page first writes,
    // against 0.1 s for the call and 0.7 s for the writes after it, which the hypervisor still
    // sees for the first time.
    if (last > first) madvise(reinterpret_cast<void*>(first), last - first, MADV_POPULATE_WRITE);
    for (std::size_t i = 0; i < length; i += kPage) chunk[i] = 0;
  }
}

HeapWarmer::~HeapWarmer() {
  if (block_) warm_chunks();
  if (toucher_.joinable()) toucher_.join();
  std::free(block_);
}

}  // namespace s2c
