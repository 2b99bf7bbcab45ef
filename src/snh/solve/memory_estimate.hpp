#pragma once
// How much memory a run needs, estimated before it starts, and what this process may use (issue 13).
//
// The model (calibrated by the peak resident set and peak address space of `snh stretch` runs at
// resolutions 5 to 30 on a 2-core VM; docs/results.md, "Memory", has the figures):
//   resident  = base + per_vertex · #V + per_cell · #C (nodes_per_cell² scaled) + 8 · 2 · nnz(H)
//               + for a direct solver, the factor: fill · n^{4/3} nonzeros of L (n = 3 #V, the 3D
//                 nested-dissection growth) at 8 bytes each, times the factorization's workspace ratio
//               + with contact, a part per vertex (the fist with self-contact at 25k–200k hexes against the
//                 same runs without: docs/results.md, "Memory")
//   address space = resident + the libraries' reserved but untouched space: a fixed part, per hardware
//               thread after the first an OpenBLAS worker (its 128 MiB buffer and its stack, reserved when
//               the library starts, whatever the solver) and an OpenMP worker's stack, and with a direct
//               solver the main thread's OpenBLAS buffer (measured with 1 and 2 threads).
// Conservative: a run needing more than the estimate has not been measured; the demos need a few tenths.
//
// A run is refused before any work when its estimate exceeds the limit: MemAvailable from /proc/meminfo
// against the resident estimate, and RLIMIT_AS (ulimit -v) against the address-space estimate.
// SNH_MEMORY_CHECK=off in the environment skips the refusal (to try a run the estimate refuses anyway).
#include <cstdint>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>

#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// A run that ran out of memory (a failed allocation in the linear solver, or anywhere in a frame). The
/// message is one line: what failed, the estimate, what is kept and what needs less.
class OutOfMemoryError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A run refused before any work because its estimate exceeds what this process may use.
class MemoryEstimateError : public std::invalid_argument {
 public:
  using std::invalid_argument::invalid_argument;
};

/// What the estimate needs to know about a problem.
struct ProblemSize {
  std::int64_t vertices = 0;
  std::int64_t cells = 0;
  int nodes_per_cell = 4;  ///< 4 (tet4) or 8 (hex8)
  bool contact = false;    ///< contact terms (self-contact, colliders, planes): their pairs, and a Newton matrix
                           ///< of a new pattern made beside the old one as pairs come and go
};

/// The size of a mesh.
[[nodiscard]] ProblemSize problem_size(const VolumeMesh& mesh);
/// The size of the stretch test's lattice with res³ cells (6 tets each, or one hex), without building it.
[[nodiscard]] ProblemSize lattice_size(int resolution, CellType type);

struct MemoryEstimate {
  double resident_bytes = 0.0;       ///< peak resident set
  double address_space_bytes = 0.0;  ///< peak address space (what ulimit -v bounds)
};

/// The estimated peak memory of a run of `size` with the linear solver `solver` (cholmod, ldlt: a factor;
/// pcg: none; mg: the matrix in nodal blocks and its coarse levels) on a machine of `threads` hardware
/// threads (0: this one's).
[[nodiscard]] MemoryEstimate estimate_memory(const ProblemSize& size, std::string_view solver, unsigned threads = 0);

/// What this process may still use: the smaller of MemAvailable (against resident memory) and RLIMIT_AS
/// (against address space) where set. Absent fields: no such limit known.
struct MemoryLimits {
  std::optional<double> available_bytes;      ///< MemAvailable, /proc/meminfo
  std::optional<double> address_space_bytes;  ///< RLIMIT_AS (soft), when not unlimited
};
[[nodiscard]] MemoryLimits memory_limits();

/// Why `estimate` does not fit `limits`, e.g. "needs about 1.2 GiB of address space, more than the
/// ulimit -v of 439 MiB"; empty when it fits.
[[nodiscard]] std::string memory_shortfall(const MemoryEstimate& estimate, const MemoryLimits& limits);

/// "12 MiB", "1.2 GiB".
[[nodiscard]] std::string format_bytes(double bytes);

/// Throws MemoryEstimateError (one line, naming the estimate, the limit, and what PCG would need when
/// the solver is a direct one) when the run of `size` does not fit this process' limits. Does nothing
/// when SNH_MEMORY_CHECK=off.
///   what  the run, for the message ("hex res 400")
void check_memory(const ProblemSize& size, std::string_view solver, std::string_view what);

/// The message of an out-of-memory failure: `what` failed (e.g. "step 3: CHOLMOD's factorization"), the
/// estimate for `size` with `solver` and with PCG, and the limits.
[[nodiscard]] std::string out_of_memory_message(std::string_view what, const ProblemSize& size, std::string_view solver);

}  // namespace snh
