// Galerkin coarse operators A_c = Pᵀ A P (multigrid.hpp): the coarse levels' block patterns, the index of Pᵀ
// that the products and the V-cycle's restriction read, and the products themselves in 3×3 nodal blocks.
#include <algorithm>
#include <stdexcept>
#include <vector>

#include "snh/solve/multigrid/levels.hpp"

namespace snh {
namespace multigrid {

/// Pᵀ's index: per coarse node, the entries of `down` that reach it, in fine-node order.
void transpose_transfer(Level& F, int coarse_nodes) {
  F.up_start.assign(coarse_nodes + 1, 0);
  for (int I : F.down.node) ++F.up_start[I + 1];
  for (int I = 0; I < coarse_nodes; ++I) F.up_start[I + 1] += F.up_start[I];
  F.up_entry.resize(F.down.node.size());
  F.up_fine.resize(F.down.node.size());
  std::vector<int> next(F.up_start.begin(), F.up_start.end() - 1);
  for (int i = 0; i < F.nodes; ++i)
    for (int p = F.down.start[i]; p < F.down.start[i + 1]; ++p) {
      F.up_fine[next[F.down.node[p]]] = i;
      F.up_entry[next[F.down.node[p]]++] = p;
    }
}

namespace {

/// R += Wᵀ a for 3×3 row-major blocks; W diagonal (the lattice's transfers: trilinear weights times the
/// identity, masked to the free DOFs) needs a third of the products.
template <bool kDiagonal>
inline void add_transposed_product(const double* w, const double* a, bool transpose_a, double* R) {
  const auto at = [&](int r, int c) { return transpose_a ? a[3 * c + r] : a[3 * r + c]; };
  for (int r = 0; r < 3; ++r)
    for (int c = 0; c < 3; ++c) {
      if constexpr (kDiagonal) R[3 * r + c] += w[4 * r] * at(r, c);
      else R[3 * r + c] += w[r] * at(0, c) + w[3 + r] * at(1, c) + w[6 + r] * at(2, c);
    }
}

/// Y += r W for 3×3 row-major blocks (W diagonal as above where kDiagonal).
template <bool kDiagonal>
inline void add_product(const double* r, const double* w, double* Y) {
  for (int i = 0; i < 3; ++i)
    for (int c = 0; c < 3; ++c) {
      if constexpr (kDiagonal) Y[3 * i + c] += r[3 * i + c] * w[4 * c];
      else Y[3 * i + c] += r[3 * i] * w[c] + r[3 * i + 1] * w[3 + c] + r[3 * i + 2] * w[6 + c];
    }
}

/// The next level's A from this one's, Pᵀ A P, one coarse block row I at a time, rows in parallel: first
/// R_k = Σ_i P_iIᵀ A_ik over I's fine nodes i and every block of their rows (both triangles), then
/// C_IK = Σ_k R_k P_kK for the coarse K ≤ I (the diagonal block made symmetric); then the coarse DOFs that are
/// not free masked out. Each row's sums run in an order fixed by the structure alone, so the result does not
/// depend on the thread count. By coarse rows rather than by scattering each fine row's products into the
/// coarse blocks (a serial loop): no two threads write one block, so the rows run in parallel without locks.
template <bool kDiagonal>
void galerkin_rows(const Level& F, Level& C, bool in_parallel) {
  int outside = 0;  // coarse blocks reached outside C's pattern (none: the structure made it from the same P)
#pragma omp parallel if (in_parallel) reduction(+ : outside)
  {
    std::vector<double> R(9 * static_cast<std::size_t>(F.nodes), 0.0), Y(9 * static_cast<std::size_t>(C.nodes), 0.0);
    std::vector<int> reached, reached_coarse;
    std::vector<char> seen(F.nodes, 0), seen_coarse(C.nodes, 0);
    const double* val = F.A.val.data();
#pragma omp for schedule(dynamic, 64)
    for (int I = 0; I < C.nodes; ++I) {
      for (int q = F.up_start[I]; q < F.up_start[I + 1]; ++q) {
        const int i = F.up_fine[q];
        const double* w = &F.down.block[9 * static_cast<std::size_t>(F.up_entry[q])];
        const auto add = [&](int k, std::size_t slot, bool transpose) {
          if (!seen[k]) {
            seen[k] = 1;
            reached.push_back(k);
          }
          add_transposed_product<kDiagonal>(w, val + 9 * slot, transpose, &R[9 * static_cast<std::size_t>(k)]);
        };
        add(i, F.diagonal[i], false);
        for (int e = F.row_start[i]; e < F.row_end[i]; ++e) add(F.row_node[e], F.row_slot[e], F.row_node[e] > i);
      }
      for (int k : reached) {
        const double* r = &R[9 * static_cast<std::size_t>(k)];
        for (int p = F.down.start[k]; p < F.down.start[k + 1]; ++p) {
          const int K = F.down.node[p];
          if (K > I) continue;
          if (!seen_coarse[K]) {
            seen_coarse[K] = 1;
            reached_coarse.push_back(K);
          }
          add_product<kDiagonal>(r, &F.down.block[9 * static_cast<std::size_t>(p)], &Y[9 * static_cast<std::size_t>(K)]);
        }
        std::fill_n(&R[9 * static_cast<std::size_t>(k)], 9, 0.0);
        seen[k] = 0;
      }
      reached.clear();
      // Row I of C: every stored block is written (zero where nothing reached it), its DOFs that are not free
      // masked out.
      for (int s = C.A.start[I]; s < C.A.start[I + 1]; ++s) {
        const int K = C.A.col[s];
        Block3 c(&C.A.val[9 * static_cast<std::size_t>(s)]);
        if (seen_coarse[K]) {
          const ConstBlock3 y(&Y[9 * static_cast<std::size_t>(K)]);
          if (K < I) c = y;
          else c = 0.5 * (y + y.transpose());
          std::fill_n(&Y[9 * static_cast<std::size_t>(K)], 9, 0.0);
          seen_coarse[K] = 0;
        } else {
          c.setZero();
        }
        for (int a = 0; a < 3; ++a)
          for (int b = 0; b < 3; ++b)
            if (!C.free[3 * I + a] || !C.free[3 * K + b]) c(a, b) = 0.0;
      }
      for (int K : reached_coarse)
        if (seen_coarse[K]) {
          ++outside;
          std::fill_n(&Y[9 * static_cast<std::size_t>(K)], 9, 0.0);
          seen_coarse[K] = 0;
        }
      reached_coarse.clear();
    }
  }
  if (outside > 0) throw std::logic_error("multigrid: Galerkin product reached blocks outside the coarse pattern");
}

}  // namespace
}  // namespace multigrid

using namespace multigrid;

/// Level l + 1's block pattern, Pᵀ A P's, from level l's and P's.
void MultigridPreconditioner::Impl::coarse_pattern(std::size_t l) {
  Level &F = levels[l], &C = levels[l + 1];
  // Block (i, k ≤ i) reaches the coarse pairs (I, K), I a parent of i and K of k, stored at (max, min).
  std::vector<std::vector<int>> coarse_rows(C.nodes);
  std::vector<int> reach;
  for (int i = 0; i < F.nodes; ++i) {
    reach.clear();
    for (int s = F.A.start[i]; s < F.A.start[i + 1]; ++s) {
      const int k = F.A.col[s];
      reach.insert(reach.end(), F.down.node.begin() + F.down.start[k], F.down.node.begin() + F.down.start[k + 1]);
    }
    sort_unique(reach);
    for (int p = F.down.start[i]; p < F.down.start[i + 1]; ++p) {
      const int I = F.down.node[p];
      for (int K : reach) coarse_rows[std::max(I, K)].push_back(std::min(I, K));
    }
  }
  for (int I = 0; I < C.nodes; ++I) {
    coarse_rows[I].push_back(I);
    sort_unique(coarse_rows[I]);
  }
  C.A.set_pattern(coarse_rows);
}

void MultigridPreconditioner::Impl::galerkin(Level& F, Level& C) {
  // The lattice's transfers are diagonal blocks (tests/solve/test_multigrid.cpp checks the products against
  // the explicit Pᵀ A P); smoothed aggregation's are full.
  if (coarsening == Coarsening::lattice) galerkin_rows<true>(F, C, parallel(F));
  else galerkin_rows<false>(F, C, parallel(F));
}

}  // namespace snh
