// The multigrid hierarchy's structure (multigrid.hpp): the finest level for a mesh, the coarse levels (from
// the lattice when the preconditioner is made, by smoothed aggregation from each new pattern of A), and for
// each pattern of A the levels' block patterns, the smoother's rows and the coarsest level's scalar matrix.
// Only the values are recomputed for each matrix (preconditioner.cpp).
#include <algorithm>
#include <functional>
#include <stdexcept>
#include <vector>

#include <fmt/format.h>

#include "snh/solve/multigrid/levels.hpp"

namespace snh {
namespace {

/// A level with at most this many free DOFs is solved directly: lattice levels (sparse: 81 blocks per node
/// at most), and aggregation's (whose coarse operators are much denser, their factor nearly full).
constexpr Eigen::Index kCoarsestUnknowns = 3000;
constexpr Eigen::Index kCoarsestAggregationUnknowns = 500;
/// Coarsening stops where it keeps more than this fraction of the unknowns (a lattice too thin to coarsen).
constexpr double kMinReduction = 0.6;
constexpr int kMaxLevels = 16;

}  // namespace

using namespace multigrid;

MultigridPreconditioner::Impl::Impl(const VolumeMesh& mesh, const std::vector<int>& free_index, Coarsening how)
    : coarsening(how) {
  Level L;
  L.nodes = static_cast<int>(mesh.vertex_count());
  if (free_index.size() != 3 * static_cast<std::size_t>(L.nodes))
    throw std::invalid_argument(fmt::format("multigrid: {} DOF indices for {} vertices", free_index.size(), L.nodes));
  L.free.resize(free_index.size());
  int free_count = 0;
  for (std::size_t d = 0; d < free_index.size(); ++d) {
    L.free[d] = free_index[d] >= 0;
    free_count = std::max(free_count, free_index[d] + 1);
  }
  row_dof.assign(free_count, -1);
  for (std::size_t d = 0; d < free_index.size(); ++d)
    if (free_index[d] >= 0) row_dof[free_index[d]] = static_cast<int>(d);
  if (how == Coarsening::aggregation) {
    rigid_body_modes(mesh, L);
    levels.push_back(std::move(L));
    return;  // the levels follow the matrix's pattern (structure())
  }
  // The coordinates stay alive until the levels are grown, as they did before the code was split into files:
  // freed first, they changed how glibc's malloc reuses memory for the coarse levels, and repeated set-ups
  // page-faulted much more (the same allocations, in another order).
  const LatticeCoordinates lattice = lattice_coordinates(mesh);
  lattice_level(mesh, lattice, L);
  levels.push_back(std::move(L));
  grow([this] { coarsen(); });
}

/// Appends levels, each by `coarsen`, until the last has at most kCoarsestUnknowns (aggregation:
/// kCoarsestAggregationUnknowns) free DOFs; a level that keeps more than kMinReduction of the one before (or
/// none) is dropped and ends the hierarchy.
void MultigridPreconditioner::Impl::grow(const std::function<void()>& coarsen) {
  const Eigen::Index coarsest = coarsening == Coarsening::lattice ? kCoarsestUnknowns : kCoarsestAggregationUnknowns;
  while (levels.size() < kMaxLevels && levels.back().unknowns() > coarsest) {
    const Eigen::Index before = levels.back().unknowns();
    coarsen();
    if (levels.back().unknowns() > kMinReduction * static_cast<double>(before) || levels.back().unknowns() == 0) {
      levels.pop_back();
      levels.back().down = Transfer{};
      break;
    }
  }
}

/// The block patterns for A's pattern: level 0 from A, each coarse level's as Wᵀ A W, and the coarsest
/// level's scalar matrix.
void MultigridPreconditioner::Impl::structure(const SparseLower& A) {
  fine_pattern(A);
  if (coarsening == Coarsening::lattice) {
    for (std::size_t l = 0; l + 1 < levels.size(); ++l) coarse_pattern(l);
  } else {
    levels.resize(1);
    levels.front().down = Transfer{};
    grow([this] {
      aggregate();
      coarse_pattern(levels.size() - 2);
    });
  }
  for (Level& l : levels) {
    l.diagonal.resize(l.nodes);
    for (int i = 0; i < l.nodes; ++i) l.diagonal[i] = l.A.find(i, i);
    l.inverse.assign(9 * static_cast<std::size_t>(l.nodes), 0.0);
    l.x.resize(3 * l.nodes);
    l.b.resize(3 * l.nodes);
    l.r.resize(3 * l.nodes);
    sweep_rows(l, !parallel(l));
    product_chunks(l);
  }
  for (std::size_t l = 0; l + 1 < levels.size(); ++l) transpose_transfer(levels[l], levels[l + 1].nodes);
  coarsest_matrix();
}

/// Level 0's block pattern from A's, and where each stored entry of A goes in it (value_slot).
void MultigridPreconditioner::Impl::fine_pattern(const SparseLower& A) {
  Level& L0 = levels.front();
  {
    // Column c of A's lower triangle holds rows r ≥ c: node pairs (i ≥ j), collected per node j.
    std::vector<std::vector<int>> rows(L0.nodes);
    std::vector<int> below;
    for (Eigen::Index c = 0; c < A.outerSize();) {
      const int j = row_dof[c] / 3;
      below.clear();
      for (; c < A.outerSize() && row_dof[c] / 3 == j; ++c)
        for (SparseLower::InnerIterator it(A, c); it; ++it) below.push_back(row_dof[it.row()] / 3);
      sort_unique(below);
      for (int i : below)
        if (i != j) rows[i].push_back(j);  // j ascending: rows stay sorted
    }
    for (int i = 0; i < L0.nodes; ++i) rows[i].push_back(i);
    L0.A.set_pattern(rows);
  }
  {
    // Where each stored entry of A goes. Column c (DOF b of node j) holds entries (i a, j b), i ≥ j: block
    // (i, j)'s entry (a, b). Columns come in increasing j, so each row's cursor only moves forward to (i, j).
    std::vector<int> cursor(L0.A.start.begin(), L0.A.start.end() - 1);
    value_slot.resize(static_cast<std::size_t>(A.nonZeros()));
    for (Eigen::Index c = 0; c < A.outerSize(); ++c) {
      const int dc = row_dof[c], j = dc / 3, b = dc % 3;
      for (int k = A.outerIndexPtr()[c]; k < A.outerIndexPtr()[c + 1]; ++k) {
        const int dr = row_dof[A.innerIndexPtr()[k]], i = dr / 3;
        while (L0.A.col[cursor[i]] < j) ++cursor[i];  // stops at the diagonal block (i ≥ j) at the latest
        if (L0.A.col[cursor[i]] != j) throw std::logic_error("multigrid: the matrix's pattern does not hold its own entries");
        value_slot[static_cast<std::size_t>(k)] = 9 * cursor[i] + 3 * (dr % 3) + b;
      }
    }
  }
}

/// The coarsest level's free DOFs as a lower-triangular scalar matrix for the direct solver (column c: rows
/// r ≥ c in order), and where each of its entries comes from in the level's blocks (coarse_value).
void MultigridPreconditioner::Impl::coarsest_matrix() {
  const Level& K = levels.back();
  std::vector<int> index(3 * static_cast<std::size_t>(K.nodes), -1);
  coarse_dof.clear();
  for (int d = 0; d < 3 * K.nodes; ++d)
    if (K.free[d]) {
      index[d] = static_cast<int>(coarse_dof.size());
      coarse_dof.push_back(d);
    }
  const int n = static_cast<int>(coarse_dof.size());
  struct Entry {
    int c, r, value;
  };
  std::vector<Entry> entries;  // A(i a, j b) = block (i, j)'s entry (a, b), i ≥ j
  for (int i = 0; i < K.nodes; ++i)
    for (int s = K.A.start[i]; s < K.A.start[i + 1]; ++s) {
      const int j = K.A.col[s];
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          const int r = index[3 * i + a], c = index[3 * j + b];
          if (r >= 0 && c >= 0 && r >= c) entries.push_back({c, r, 9 * s + 3 * a + b});
        }
    }
  std::sort(entries.begin(), entries.end(), [](const Entry& x, const Entry& y) { return x.c != y.c ? x.c < y.c : x.r < y.r; });
  std::vector<int> outer(n + 1, 0), inner;
  coarse_value.clear();
  for (const Entry& e : entries) {
    ++outer[e.c + 1];
    inner.push_back(e.r);
    coarse_value.push_back(e.value);
  }
  for (int c = 0; c < n; ++c) outer[c + 1] += outer[c];
  coarse = SparseLower(n, n);
  coarse.resizeNonZeros(static_cast<Eigen::Index>(inner.size()));
  std::copy(outer.begin(), outer.end(), coarse.outerIndexPtr());
  std::copy(inner.begin(), inner.end(), coarse.innerIndexPtr());
  coarse_b.resize(n);
}

}  // namespace snh
