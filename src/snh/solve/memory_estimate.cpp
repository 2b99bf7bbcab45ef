#include "snh/solve/memory_estimate.hpp"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <fstream>
#include <string>
#include <thread>

#include <fmt/format.h>
#include <sys/resource.h>

namespace snh {
namespace {

constexpr double kMiB = 1024.0 * 1024.0;

// Calibration: peak resident set and peak address space of `snh stretch` at resolutions 5-30, tets and
// hexes, CHOLMOD and PCG, 2 threads (the measurements: docs/results.md, "Memory"); each coefficient rounded up.
constexpr double kBaseResident = 16.0 * kMiB;     // the program, its libraries, a tiny mesh
constexpr double kPerVertex = 7.0 * 1024.0;       // positions, DOF vectors, the PCG matrix, frames, stats (bytes)
constexpr double kPerCellNodePair = 30.0;         // per cell and (node, node) pair: the scatter map (6 ints per pair)
constexpr double kFactorPerN43 = 260.0;           // CHOLMOD's L and workspace, bytes per n^{4/3}
// Address space reserved beyond the resident set (VmPeak minus the peak resident set of `snh stretch`,
// measured on one and two CPUs: docs/results.md, "Memory"): a fixed part; per CPU after the first, an
// OpenBLAS worker thread, which reserves its 128 MiB buffer and an 8 MiB stack when the library starts, with
// PCG too; with a direct solver, the main thread's OpenBLAS buffer in the factorization. Rounded up.
constexpr double kReservedFixed = 60.0 * kMiB;
constexpr double kReservedPerExtraThread = 150.0 * kMiB;
constexpr double kReservedDirect = 170.0 * kMiB;

// Multigrid (mg): the Newton matrix in 3×3 nodal blocks, both triangles (27 blocks of 72 bytes per
// lattice vertex), and the coarse levels (an eighth more each). Algebraic multigrid (amg) holds the same
// blocks (15 per vertex on tets) and its prolongator (about 16 blocks per vertex): less than mg's in the
// measurements (docs/results.md, "Multigrid"), so the same allowance covers it.
constexpr double kMultigridPerVertex = 3.0 * 1024.0;

// Contact (calibration: the fist of bench/figure1.sh with and without the skin's self-contact, mg, 25k to 200k
// hexes: 251, 299, 342, 587 and 963 MiB more at 30.7k, 53.2k, 59.0k, 114k and 221k vertices, 8.4 to 4.5 KiB
// per vertex; docs/results.md, "Memory"). The largest per vertex, rounded up: a fixed part fitted to these
// runs would make a small scene with contact look hundreds of MiB larger than it is.
constexpr double kContactPerVertex = 8.5 * 1024.0;

bool is_direct(std::string_view solver) { return solver != "pcg" && solver != "mg" && solver != "amg"; }

}  // namespace

ProblemSize problem_size(const VolumeMesh& mesh) {
  return {.vertices = mesh.vertex_count(), .cells = mesh.cell_count(), .nodes_per_cell = nodes_per_cell(mesh.type)};
}

ProblemSize lattice_size(int resolution, CellType type) {
  const std::int64_t r = std::max(resolution, 0), cells = r * r * r;
  return {.vertices = (r + 1) * (r + 1) * (r + 1),
          .cells = type == CellType::tet4 ? 6 * cells : cells,
          .nodes_per_cell = nodes_per_cell(type)};
}

MemoryEstimate estimate_memory(const ProblemSize& size, std::string_view solver, unsigned threads) {
  const double v = static_cast<double>(size.vertices), c = static_cast<double>(size.cells);
  const double npc = size.nodes_per_cell;
  double resident = kBaseResident + kPerVertex * v + kPerCellNodePair * c * npc * npc;
  if (is_direct(solver)) resident += kFactorPerN43 * std::pow(3.0 * v, 4.0 / 3.0);
  if (solver == "mg" || solver == "amg") resident += kMultigridPerVertex * v;
  if (size.contact) resident += kContactPerVertex * v;
  const double t = std::max(1u, threads ? threads : std::thread::hardware_concurrency());
  const double reserved = kReservedFixed + (t - 1.0) * kReservedPerExtraThread + (is_direct(solver) ? kReservedDirect : 0.0);
  return {.resident_bytes = resident, .address_space_bytes = resident + reserved};
}

MemoryLimits memory_limits() {
  MemoryLimits limits;
  std::ifstream in("/proc/meminfo");
  for (std::string line; std::getline(in, line);)
    if (line.rfind("MemAvailable:", 0) == 0) limits.available_bytes = std::stod(line.substr(13)) * 1024.0;  // kB
  rlimit rl{};
  if (getrlimit(RLIMIT_AS, &rl) == 0 && rl.rlim_cur != RLIM_INFINITY)
    limits.address_space_bytes = static_cast<double>(rl.rlim_cur);
  return limits;
}

std::string format_bytes(double bytes) {
  if (bytes >= 1024.0 * kMiB) return fmt::format("{:.1f} GiB", bytes / (1024.0 * kMiB));
  return fmt::format("{:.0f} MiB", std::ceil(bytes / kMiB));
}

std::string memory_shortfall(const MemoryEstimate& estimate, const MemoryLimits& limits) {
  if (limits.address_space_bytes && estimate.address_space_bytes > *limits.address_space_bytes)
    return fmt::format("needs about {} of address space, more than the limit of {} (ulimit -v)",
                       format_bytes(estimate.address_space_bytes), format_bytes(*limits.address_space_bytes));
  if (limits.available_bytes && estimate.resident_bytes > *limits.available_bytes)
    return fmt::format("needs about {} of memory, more than the {} available (MemAvailable)",
                       format_bytes(estimate.resident_bytes), format_bytes(*limits.available_bytes));
  return "";
}

namespace {
/// ", PCG (--solver pcg) about …" where the solver is a direct one.
std::string pcg_alternative(const ProblemSize& size, std::string_view solver, const MemoryLimits& limits) {
  if (!is_direct(solver)) return "";
  const MemoryEstimate pcg = estimate_memory(size, "pcg");
  const bool fits = memory_shortfall(pcg, limits).empty();
  return fmt::format("; --solver pcg needs less: about {} ({} address space){}", format_bytes(pcg.resident_bytes),
                     format_bytes(pcg.address_space_bytes), fits ? ", which fits" : ", which does not fit either");
}
}  // namespace

void check_memory(const ProblemSize& size, std::string_view solver, std::string_view what) {
  if (const char* env = std::getenv("SNH_MEMORY_CHECK"); env && std::string_view(env) == "off") return;
  const MemoryLimits limits = memory_limits();
  const std::string shortfall = memory_shortfall(estimate_memory(size, solver), limits);
  if (shortfall.empty()) return;
  throw MemoryEstimateError(fmt::format("not enough memory: {} with {} ({} vertices, {} cells{}) {}{} "
                                        "(SNH_MEMORY_CHECK=off runs it anyway)",
                                        what, solver, size.vertices, size.cells, size.contact ? ", contact" : "", shortfall,
                                        pcg_alternative(size, solver, limits)));
}

std::string out_of_memory_message(std::string_view what, const ProblemSize& size, std::string_view solver) {
  const MemoryLimits limits = memory_limits();
  const MemoryEstimate e = estimate_memory(size, solver);
  std::string limit;
  if (limits.address_space_bytes) limit = fmt::format(", limit {} (ulimit -v)", format_bytes(*limits.address_space_bytes));
  else if (limits.available_bytes) limit = fmt::format(", {} available", format_bytes(*limits.available_bytes));
  return fmt::format("out of memory in {}: this run needs about {} ({} address space) with {}{}{}", what,
                     format_bytes(e.resident_bytes), format_bytes(e.address_space_bytes), solver, limit,
                     pcg_alternative(size, solver, limits));
}

}  // namespace snh
