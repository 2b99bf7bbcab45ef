// Memory estimate (issue 13): lattice sizes, the estimate against peak memory measured on the 2-core VM
// (docs/results.md, "Memory"), the shortfall against limits, and the refusal.
#include <gtest/gtest.h>

#include <cstdlib>

#include "snh/mesh/box.hpp"
#include "snh/solve/memory_estimate.hpp"

namespace snh {
namespace {

constexpr double kMiB = 1024.0 * 1024.0;

TEST(MemoryEstimate, LatticeSizeMatchesTheBuiltMesh) {
  for (int res : {1, 3, 5}) {
    const ProblemSize tets = lattice_size(res, CellType::tet4), built_tets = problem_size(box_tets(res));
    EXPECT_EQ(tets.vertices, built_tets.vertices);
    EXPECT_EQ(tets.cells, built_tets.cells);
    EXPECT_EQ(tets.nodes_per_cell, 4);
    const ProblemSize hexes = lattice_size(res, CellType::hex8), built_hexes = problem_size(box_hexes(res));
    EXPECT_EQ(hexes.vertices, built_hexes.vertices);
    EXPECT_EQ(hexes.cells, built_hexes.cells);
    EXPECT_EQ(hexes.nodes_per_cell, 8);
  }
  EXPECT_EQ(lattice_size(400, CellType::tet4).cells, 6LL * 400 * 400 * 400);  // no int overflow
}

// Peak resident set (MiB) measured with /usr/bin/time -v, `snh stretch --threads 2` (docs/results.md, "Memory"): the
// estimate is above each, but not by more than 2x.
TEST(MemoryEstimate, BracketsTheMeasuredPeaks) {
  struct Measured {
    int res;
    CellType type;
    const char* solver;
    double rss_mib;
  };
  // Measured again 2026-11-28, once snh kept freed memory in the process (keep_freed_memory; the allowances
  // are those of 2026-11-23, 7 KiB per vertex and 30 bytes per node pair).
  for (const Measured& m : {Measured{10, CellType::tet4, "cholmod", 34}, Measured{10, CellType::hex8, "pcg", 22},
                            Measured{20, CellType::tet4, "cholmod", 212}, Measured{20, CellType::hex8, "cholmod", 240},
                            Measured{20, CellType::tet4, "pcg", 64}, Measured{25, CellType::hex8, "cholmod", 523},
                            Measured{25, CellType::tet4, "pcg", 111}, Measured{30, CellType::tet4, "cholmod", 920},
                            Measured{30, CellType::hex8, "cholmod", 1008}, Measured{30, CellType::hex8, "pcg", 201},
                            Measured{20, CellType::hex8, "mg", 87}, Measured{30, CellType::hex8, "mg", 265},
                            Measured{20, CellType::tet4, "amg", 83}, Measured{30, CellType::tet4, "amg", 253}}) {
    const double e = estimate_memory(lattice_size(m.res, m.type), m.solver).resident_bytes / kMiB;
    EXPECT_GT(e, m.rss_mib) << m.res << " " << m.solver;
    EXPECT_LT(e, 2.0 * m.rss_mib) << m.res << " " << m.solver;
  }
}

// The fist of bench/figure1.sh with the skin's self-contact, mg, 2 threads (docs/results.md, "Memory"): the peak
// resident set (MiB) at each lattice size, 2026-11-28. Without contact the same lattices peak 250–1 822 MiB,
// under the estimate without contact; with it 251–963 MiB more, which the contact allowance covers.
TEST(MemoryEstimate, BracketsTheMeasuredPeaksWithContact) {
  struct Measured {
    std::int64_t vertices, cells;
    double rss_mib, without_contact_mib;
  };
  for (const Measured& m : {Measured{30698, 25347, 501, 250}, Measured{53158, 45274, 712, 413}, Measured{59006, 50536, 824, 482},
                            Measured{114342, 100945, 1530, 943}, Measured{220847, 199754, 2785, 1822}}) {
    ProblemSize size{.vertices = m.vertices, .cells = m.cells, .nodes_per_cell = 8};
    const double without = estimate_memory(size, "mg").resident_bytes / kMiB;
    EXPECT_GT(without, m.without_contact_mib) << m.cells << " hexes without contact";
    EXPECT_LT(without, m.rss_mib) << m.cells << " hexes: the estimate without contact is below the run with it";
    size.contact = true;
    const double e = estimate_memory(size, "mg").resident_bytes / kMiB;
    EXPECT_GT(e, m.rss_mib) << m.cells << " hexes with contact";
    EXPECT_LT(e, 2.0 * m.rss_mib) << m.cells << " hexes with contact";
  }
}

// Peak address space (MiB, VmPeak) of `snh stretch` on one CPU (taskset -c 0, --threads 1) and on two
// (docs/results.md, "Memory"): the estimate for that many threads is above each, by less than half. The allowance
// for threads was calibrated on two only and gave 2.9 times the measurement of PCG on one.
TEST(MemoryEstimate, AddressSpaceBracketsTheMeasuredPeaksOnOneAndTwoCpus) {
  struct Measured {
    int res;
    const char* solver;
    unsigned threads;
    double vmpeak_mib;
  };
  // Measured again 2026-11-28 (VmPeak sampled every 10 ms), once snh kept freed memory in the process.
  for (const Measured& m : {Measured{10, "cholmod", 1, 240}, Measured{10, "pcg", 1, 77}, Measured{20, "cholmod", 1, 414},
                            Measured{20, "pcg", 1, 120}, Measured{10, "cholmod", 2, 375}, Measured{10, "pcg", 2, 221},
                            Measured{20, "cholmod", 2, 550}, Measured{20, "pcg", 2, 264}}) {
    const double e = estimate_memory(lattice_size(m.res, CellType::tet4), m.solver, m.threads).address_space_bytes / kMiB;
    EXPECT_GT(e, m.vmpeak_mib) << "tet " << m.res << " " << m.solver << ", " << m.threads << " threads";
    EXPECT_LT(e, 1.5 * m.vmpeak_mib) << "tet " << m.res << " " << m.solver << ", " << m.threads << " threads";
  }
  // Each further thread adds an OpenBLAS worker's reservation, a direct solver or not.
  const ProblemSize s = lattice_size(10, CellType::tet4);
  EXPECT_GT(estimate_memory(s, "pcg", 16).address_space_bytes - estimate_memory(s, "pcg", 1).address_space_bytes, 15 * 137 * kMiB);
}

TEST(MemoryEstimate, GrowsWithSizeAndADirectSolverNeedsMore) {
  double last = 0.0;
  for (int res : {5, 10, 20, 40, 80}) {
    const ProblemSize s = lattice_size(res, CellType::hex8);
    const MemoryEstimate direct = estimate_memory(s, "cholmod"), pcg = estimate_memory(s, "pcg");
    EXPECT_GT(direct.resident_bytes, last);
    EXPECT_GT(direct.resident_bytes, pcg.resident_bytes);
    EXPECT_GT(direct.address_space_bytes, direct.resident_bytes);
    EXPECT_EQ(estimate_memory(s, "ldlt").resident_bytes, direct.resident_bytes);
    last = direct.resident_bytes;
  }
  // The factor grows faster than linearly: at res 80 it is most of a direct run's memory.
  const ProblemSize big = lattice_size(80, CellType::hex8);
  EXPECT_GT(estimate_memory(big, "cholmod").resident_bytes, 4.0 * estimate_memory(big, "pcg").resident_bytes);
}

TEST(MemoryEstimate, ShortfallNamesTheLimit) {
  const MemoryEstimate e{.resident_bytes = 300 * kMiB, .address_space_bytes = 600 * kMiB};
  EXPECT_EQ(memory_shortfall(e, {}), "");
  EXPECT_EQ(memory_shortfall(e, {.available_bytes = 1024 * kMiB, .address_space_bytes = 700 * kMiB}), "");
  EXPECT_EQ(memory_shortfall(e, {.available_bytes = 200 * kMiB}),
            "needs about 300 MiB of memory, more than the 200 MiB available (MemAvailable)");
  EXPECT_EQ(memory_shortfall(e, {.address_space_bytes = 450 * kMiB}),
            "needs about 600 MiB of address space, more than the limit of 450 MiB (ulimit -v)");
  EXPECT_EQ(format_bytes(1.5 * 1024 * kMiB), "1.5 GiB");
}

TEST(MemoryEstimate, RefusesWhatDoesNotFitUnlessTurnedOff) {
  // Res 400 hexes need terabytes: more than any machine this runs on has available.
  const ProblemSize huge = lattice_size(400, CellType::hex8);
  try {
    check_memory(huge, "cholmod", "hex8 res 400");
    FAIL() << "not refused";
  } catch (const MemoryEstimateError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("not enough memory: hex8 res 400 with cholmod"), std::string::npos) << m;
    EXPECT_NE(m.find("--solver pcg needs less"), std::string::npos) << m;
    EXPECT_EQ(m.find('\n'), std::string::npos) << m;
  }
  EXPECT_NO_THROW(check_memory(lattice_size(5, CellType::hex8), "cholmod", "hex8 res 5"));
  ::setenv("SNH_MEMORY_CHECK", "off", 1);
  EXPECT_NO_THROW(check_memory(huge, "cholmod", "hex8 res 400"));
  ::unsetenv("SNH_MEMORY_CHECK");
}

TEST(MemoryEstimate, OutOfMemoryMessageNamesTheEstimateAndPcg) {
  const std::string m = out_of_memory_message("step 1 (CHOLMOD's factorization)", lattice_size(20, CellType::hex8), "cholmod");
  EXPECT_EQ(m.rfind("out of memory in step 1 (CHOLMOD's factorization): this run needs about ", 0), 0u) << m;
  EXPECT_NE(m.find("--solver pcg needs less"), std::string::npos) << m;
  EXPECT_EQ(out_of_memory_message("step 1", lattice_size(20, CellType::hex8), "pcg").find("--solver pcg"), std::string::npos);
}

}  // namespace
}  // namespace snh
