#pragma once
/// \file How the mesh stages take memory from the system.
#include <atomic>
#include <cstddef>
#include <thread>

namespace s2c {

/// Keeps the memory the process frees for its own later allocations instead of handing it back
/// to the kernel (glibc: no mmap for large blocks, no trimming of the heap). On the virtual
/// machines this runs on, a page of fresh memory costs 11–15 µs when it is first written (each
/// 4 KB page fault is a trip through the hypervisor; a page written again costs nothing), and a
/// stage frees and takes again hundreds of MB of arrays as it goes: the features stage on a
/// million-vertex mesh took 250 k page faults, 181 k with this (its peak is 169 k pages), the
/// repair of the plate scan 32 k → 23–24 k, for a peak at most 2 % higher. Call it first in main().
/// Not for scan2cad-reconstruct: there the worker threads' blocks all came from the main heap
/// and its peak, which has a target of its own, grew by a tenth.
void reuse_freed_memory();

/// Faults in `bytes` of heap on a second thread while the caller works on one core (reading a
/// file), a chunk at a time. With reuse_freed_memory() the block stays in malloc's free lists, so
/// the arrays allocated next get pages that are already backed. What a million-vertex mesh's
/// analysis would spend on first touches runs beside the parse of its file instead (bench/README,
/// "features: the file read", "the binary PLY reader" and "2 MB pages and 100 MB less").
///
/// Where the kernel offers transparent huge pages (mode `always` or `madvise`), the block is
/// asked for 2 MB pages: one fault per 2 MB instead of 512 (on this VM 30 times cheaper when the
/// runs come one after another, as cheap as 4 KB pages after a pause). Mapping
/// them needs no write to the memory, so the block goes back to malloc at once and the caller's
/// own arrays (the file's) already land in it while the toucher maps it. Otherwise the toucher
/// writes a byte per 4 KB page, and the block is freed in the destructor, which also faults in
/// the chunks still left on the caller's thread.
class HeapWarmer {
 public:
  explicit HeapWarmer(std::size_t bytes);
  ~HeapWarmer();
  HeapWarmer(const HeapWarmer&) = delete;
  HeapWarmer& operator=(const HeapWarmer&) = delete;

  /// True when the block was given 2 MB pages (and handed back to malloc at once).
  bool huge_pages() const { return huge_; }

 private:
  /// Faults in chunk after chunk until none is left (the toucher, then the destructor as well).
  void warm_chunks();

  char* block_ = nullptr;
  std::size_t bytes_ = 0;
  bool huge_ = false;
  std::atomic<std::size_t> next_chunk_{0};
  std::thread toucher_;
};

/// True when the kernel hands out transparent huge pages for memory that asks for them
/// (/sys/kernel/mm/transparent_hugepage/enabled is `always` or `madvise`).
bool transparent_huge_pages();

}  // namespace s2c
