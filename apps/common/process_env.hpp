#pragma once
// Settings that glibc and libgomp read only when a process starts: the program sets those the user left
// unset and re-executes itself once (same process id, same arguments). A user's own settings are kept.
// - OMP_WAIT_POLICY=PASSIVE: idle OpenMP threads sleep instead of spinning. The assembly's parallel loops
//   alternate with long serial phases (CHOLMOD factorizations, whose BLAS has threads of its own); spinning
//   OpenMP threads then compete with them for the cores, which measured 1.5-2x slower whole runs on 2 cores.
// - GOMP_SPINCOUNT=10000 with it (unless set): a thread that finds no work spins that long (libgomp counts
//   about 100 000 spins a millisecond: 0.1 ms) before it sleeps. A V-cycle of the multigrid is a few
//   milliseconds of many short parallel phases, and waking a sleeping thread for each cost Figure 1 a tenth
//   of its time (whole runs 0.89 of the time without contact, 0.93 with; CHOLMOD runs unchanged:
//   docs/results.md). libgomp's own default spins 3 ms.
// - glibc.malloc.hugetlb=1 in GLIBC_TUNABLES: malloc asks for transparent huge pages (madvise) for the
//   memory it takes from the kernel. A Newton iteration's matrices and vectors are tens of MiB each, and a
//   first touch of 4 KiB pages cost a fault each (the first frame of Figure 1 at 45k hexes 1.8 s, 1.4 s with
//   huge pages; whole runs 0.95 of the time: docs/results.md). Where the kernel gives none (transparent huge
//   pages off), nothing changes. GLIBC_TUNABLES=glibc.malloc.hugetlb=0 turns it off.
#include <cstdlib>
#include <string>

#include <unistd.h>

namespace snh::cli {

inline void ensure_process_settings(char** argv) {
  // Re-executed only where every setting it lacked could be set: after it, none is lacking (no loop).
  bool changed = false, failed = false;
  if (std::getenv("OMP_WAIT_POLICY") == nullptr) {
    changed = true;
    failed = ::setenv("OMP_WAIT_POLICY", "PASSIVE", 1) != 0;
    if (!failed && std::getenv("GOMP_SPINCOUNT") == nullptr) failed = ::setenv("GOMP_SPINCOUNT", "10000", 1) != 0;
  }
  const char* tunables = std::getenv("GLIBC_TUNABLES");
  const std::string given = tunables ? tunables : "";
  if (!failed && given.find("glibc.malloc.hugetlb") == std::string::npos) {
    const std::string with = given.empty() ? "glibc.malloc.hugetlb=1" : given + ":glibc.malloc.hugetlb=1";
    changed = true;
    failed = ::setenv("GLIBC_TUNABLES", with.c_str(), 1) != 0;
  }
  if (changed && !failed) ::execv("/proc/self/exe", argv);  // returns only on failure: then run as we are
}

}  // namespace snh::cli
