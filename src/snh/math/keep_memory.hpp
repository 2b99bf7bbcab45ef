#pragma once
// Keeps freed memory in the process. glibc hands allocations above its mmap threshold (128 KiB, rising
// to at most 32 MiB as such blocks are freed) to the kernel and back on every free, and trims the heap's
// free top: a Newton iteration on 45k hexes frees and allocates again vectors and matrices of 1 to 100
// MiB, and every page of them was faulted in afresh (13 % of the perf samples of the fist's 20-frame run
// in page faults, memset and memmove). With both thresholds at 1 GiB the memory freed by one iteration
// serves the next; the peak resident set grows by 3-9 % (docs/solvers.md, "Memory"). A user's own MALLOC_*
// or GLIBC_TUNABLES settings are applied by glibc before main and are replaced here only for these two
// parameters.
#include <malloc.h>

namespace snh {

inline void keep_freed_memory() {
  constexpr int kThreshold = 1 << 30;
  ::mallopt(M_MMAP_THRESHOLD, kThreshold);
  ::mallopt(M_TRIM_THRESHOLD, kThreshold);
}

}  // namespace snh
