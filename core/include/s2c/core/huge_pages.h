#pragma once
// Transparent huge pages for the stages' heaps.

namespace s2c {

/// Adds glibc.malloc.hugetlb=1 to GLIBC_TUNABLES in this process's environment, so that the
/// processes it starts (the stages) ask the kernel for transparent huge pages for their heaps
/// (madvise; this kernel's THP mode is "madvise", so nothing else would). glibc reads its
/// tunables when a process starts: the call cannot change the calling process itself. Left as
/// it is when GLIBC_TUNABLES already names the tunable (glibc.malloc.hugetlb=0 opts out).
///
/// Why: the stages allocate hundreds of MB in many steps (PCL's Poisson octree, point and mesh
/// arrays), and on the benchmark VM every 4 KB page fault is a trip through the hypervisor. With
/// 2 MB pages the same runs take 7-22 % less CPU, with byte-identical outputs and 1-3 % more peak
/// memory (bench/README.md, "Huge pages").
void request_huge_pages_for_children();

}  // namespace s2c
