#include "s2c/core/memory.h"

#include <malloc.h>

namespace s2c {

void reuse_freed_memory() {
  // Blocks glibc would map on their own (above 128 KB–32 MB) come from the heap, and the heap's
  // free top is kept: both are then handed out again, already faulted in.
  mallopt(M_MMAP_MAX, 0);
  mallopt(M_TRIM_THRESHOLD, 1 << 30);
}

}  // namespace s2c
