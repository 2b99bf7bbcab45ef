#pragma once
// Makes idle OpenMP threads sleep instead of spinning. The assembly's parallel loops alternate with
// long serial phases (CHOLMOD factorizations, whose BLAS has threads of its own); spinning OpenMP
// threads then compete with them for the cores, which measured 1.5-2x slower whole runs on 2 cores.
// libgomp reads OMP_WAIT_POLICY only when it starts, so when the variable is unset the program sets it
// and re-executes itself once (same process id, same arguments). A user's own setting is kept.
#include <cstdlib>

#include <unistd.h>

namespace snh::cli {

inline void ensure_passive_omp_wait(char** argv) {
  if (std::getenv("OMP_WAIT_POLICY") != nullptr) return;
  ::setenv("OMP_WAIT_POLICY", "PASSIVE", 1);
  ::execv("/proc/self/exe", argv);  // returns only on failure: then run as we are
}

}  // namespace snh::cli
