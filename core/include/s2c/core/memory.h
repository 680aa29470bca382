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
/// file), a chunk at a time; when destroyed, faults in the chunks still left on the caller's
/// thread as well, then frees the block. With reuse_freed_memory() the block stays in malloc's
/// free lists, so the arrays allocated next get pages that are already backed. What a
/// million-vertex mesh's analysis would spend on first touches runs beside the parse of its file
/// instead (bench/README, "features: the file read" and "the binary PLY reader").
class HeapWarmer {
 public:
  explicit HeapWarmer(std::size_t bytes);
  ~HeapWarmer();
  HeapWarmer(const HeapWarmer&) = delete;
  HeapWarmer& operator=(const HeapWarmer&) = delete;

 private:
  /// Faults in chunk after chunk until none is left (the toucher, then the destructor as well).
  void warm_chunks();

  char* block_ = nullptr;
  std::size_t bytes_ = 0;
  std::atomic<std::size_t> next_chunk_{0};
  std::thread toucher_;
};

}  // namespace s2c
