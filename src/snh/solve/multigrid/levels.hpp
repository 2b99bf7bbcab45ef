#pragma once
// Internal to the multigrid V-cycle (snh/solve/multigrid.hpp; only solve/multigrid/*.cpp include this): the
// levels' storage (nodal blocks, transfers, a level), the preconditioner's state (Impl), the small block
// kernels that several files inline, and the steps one file hands another. The files, one concern each:
//   lattice.cpp         lattice coordinates, lattice coarsening and its trilinear transfers (mg)
//   aggregation.cpp     smoothed aggregation: aggregates, the tentative and the smoothed prolongator (amg)
//   galerkin.cpp        the coarse levels' block patterns, Pᵀ's index and the Galerkin products Pᵀ A P
//   colouring.cpp       the smoother's colours and row order, the product's chunks
//   smoother.cpp        the smoother's values, the SIMD Gauss–Seidel sweeps, residual and product A x
//   hierarchy.cpp       the levels for a mesh and for a matrix's pattern, the coarsest level's matrix
//   preconditioner.cpp  each matrix's values, the V-cycle, and MultigridPreconditioner
//   solver.cpp          the registry's "mg" and "amg" (conjugate gradients preconditioned by the V-cycle)
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Core>

#include "snh/solve/direct_solver.hpp"
#include "snh/solve/multigrid.hpp"

namespace snh {
namespace multigrid {

/// The smoother's stored matrix entries: IEEE half precision (its bits) where the CPU converts it (F16C),
/// single precision otherwise. Both hold the rows scaled (Level::scale), so that every entry is at most 1.
#ifdef __F16C__
using RowValue = std::uint16_t;
#else
using RowValue = float;
#endif

using Block3 = Eigen::Map<Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>;
using ConstBlock3 = Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>;

/// A symmetric matrix in 3×3 nodal blocks, its lower triangle stored: row i's blocks (i, j ≤ i) at
/// start[i] .. start[i+1], columns sorted (the diagonal block last), values row-major (9 per block).
struct Blocks {
  std::vector<int> start{0}, col;
  std::vector<double> val;
  /// The slot of block (i, j); −1 if absent.
  [[nodiscard]] int find(int i, int j) const {
    const auto b = col.begin() + start[i], e = col.begin() + start[i + 1];
    const auto it = std::lower_bound(b, e, j);
    return it != e && *it == j ? static_cast<int>(it - col.begin()) : -1;
  }
  /// Sets the pattern from sorted, duplicate-free rows.
  void set_pattern(const std::vector<std::vector<int>>& rows_) {
    start.assign(1, 0);
    col.clear();
    for (const auto& r : rows_) {
      col.insert(col.end(), r.begin(), r.end());
      start.push_back(static_cast<int>(col.size()));
    }
    val.assign(9 * col.size() + 1, 0.0);  // one more: subtract_product() reads 4 doubles from a block's last row
  }
};

inline void sort_unique(std::vector<int>& v) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
}

/// A prolongation P from a coarse level to a fine one in 3×3 blocks: per fine node, its coarse parents I with
/// the block P_iI (row-major, 9 per entry). The lattice's trilinear weights are multiples of the identity;
/// smoothed aggregation's blocks are full.
struct Transfer {
  std::vector<int> start{0}, node;
  std::vector<double> block;
  std::vector<double> weight;  ///< the lattice's: block = weight·I, the V-cycle's transfers read these (a ninth
                               ///< of the bytes; the same sums: the blocks' zeros add nothing); empty otherwise
  void push(int parent, const double* b) {
    node.push_back(parent);
    block.insert(block.end(), b, b + 9);
  }
};

/// A colour of fewer nodes than this is relaxed by one thread, together with the small colours next to it
/// (Level::colour_phase): a barrier costs more than sharing so few nodes saves.
constexpr int kColourInParallel = 256;

struct Level {
  int nodes = 0;
  std::vector<std::uint8_t> free;       ///< 3 per node
  // The lattice's (geometric coarsening):
  std::vector<Eigen::Vector3i> at;      ///< lattice coordinates
  std::vector<int> piece;               ///< connected piece
  std::vector<std::array<int, 8>> cells;
  // Smoothed aggregation's:
  std::vector<double> near_null;        ///< 18 per node: the rigid-body modes' rows (3×6, row-major)
  std::vector<int> aggregate;           ///< per node, its aggregate (−1: a node with no free DOF)
  std::vector<double> tentative;        ///< 18 per node: its rows of the tentative prolongator (3×6)
  std::vector<int> full_start, full_slot;  ///< per node, every block of its row (both triangles), by slot
  std::vector<int> full_node;           ///< … and the column node (> row: the stored block is (col, row)ᵀ)
  Blocks A;                             ///< masked: rows and columns of DOFs that are not free are zero
  std::vector<int> diagonal;            ///< per node, the slot of its diagonal block
  std::vector<double> inverse;          ///< 9 per node: the inverse of the free part of the diagonal block
  Transfer down;                        ///< P to the next level: the parents of each node
  std::vector<int> up_start, up_entry, up_fine;  ///< Pᵀ: per node of the next level, the entries of `down`
                                                 ///< that reach it and their fine nodes
  // The smoother's colouring and block rows (sweep_rows()): no two coupled nodes share a colour; each node's
  // off-diagonal blocks, both triangles, sorted by (colour, column node), the first `before` of them of
  // lower colours, each a slot of A (to copy its values from) and the column node. A lexicographic level
  // (one that runs on one thread) sorts them by column node alone: the first `before` are those of lower nodes.
  bool lexicographic = false;
  std::vector<int> colour;              ///< per node
  std::vector<int> colour_start, by_colour;  ///< the nodes of each colour, ascending
  /// The sweep's phases, colour_phase[p] .. colour_phase[p + 1] − 1 the colours of phase p: a colour of at
  /// least kColourInParallel nodes is a phase of its own, its nodes shared among the threads; consecutive
  /// smaller ones (a contact pair's few nodes, each clique of them in colours of their own) are one phase that
  /// one thread relaxes colour after colour. Each phase ends at a barrier: one for the run of small colours
  /// instead of one for each. The same updates in the same order either way (a colour's nodes are not coupled).
  std::vector<int> colour_phase;
  /// Whether colour c has fewer than kColourInParallel nodes; a phase whose first colour is small is a run of them.
  [[nodiscard]] bool small_colour(int c) const { return colour_start[c + 1] - colour_start[c] < kColourInParallel; }
  std::vector<int> row_start, row_end;   ///< per node, its blocks' range; rows lie in sweep order (by colour,
                                         ///< or by node on a lexicographic level) so that a sweep streams them
  std::vector<int> row_slot, row_node, before;
  std::vector<RowValue> row_val;        ///< the scaled blocks σ_i A_ik σ_k of those rows, 9 each by columns
                                        ///< (column-major), as the rows lie, in half precision (a quarter of the
                                        ///< doubles' memory traffic; the smoother's alone), and 3 more values
                                        ///< (read, never used: subtract_row)
  std::vector<double> scale;            ///< per node, σ_i: the largest power of two at most 1/√ of its largest
                                        ///< free diagonal entry (prepare_smoother()), so that every scaled entry
                                        ///< of a positive definite A is at most 1 in magnitude
  // The product A x by a fixed number of row chunks (not the thread count): each chunk's rows i sum their
  // blocks (i, k ≤ i) and spill the transposed ones into the chunk's own buffer, rows chunk_low .. its end.
  std::vector<int> chunk_start, chunk_low;
  std::vector<std::size_t> chunk_offset;  ///< each chunk's buffer in `spill` (3 per node)
  std::vector<double> spill;
  Eigen::VectorXd x, b, r;              ///< work vectors (3 per node)
  Eigen::VectorXd power;                ///< aggregation: the last power iteration's vector for ρ(D⁻¹ A)
  [[nodiscard]] Eigen::Index unknowns() const { return std::count(free.begin(), free.end(), std::uint8_t{1}); }
  [[nodiscard]] bool has_free(int i) const { return free[3 * i] || free[3 * i + 1] || free[3 * i + 2]; }
};

/// y −= a x for a row-major 3×3 block a; yt −= aᵀ x.
template <class T>
inline void subtract(const T* a, const double* x, double* y) {
  y[0] -= a[0] * x[0] + a[1] * x[1] + a[2] * x[2];
  y[1] -= a[3] * x[0] + a[4] * x[1] + a[5] * x[2];
  y[2] -= a[6] * x[0] + a[7] * x[1] + a[8] * x[2];
}
inline void subtract_transposed(const double* a, const double* x, double* y) {
  y[0] -= a[0] * x[0] + a[3] * x[1] + a[6] * x[2];
  y[1] -= a[1] * x[0] + a[4] * x[1] + a[7] * x[2];
  y[2] -= a[2] * x[0] + a[5] * x[1] + a[8] * x[2];
}

/// x_i = D_i⁻¹ s for node i.
inline void solve_diagonal(const Level& L, int i, const double* s, double* x) {
  const double* d = &L.inverse[9 * static_cast<std::size_t>(i)];
  x[0] = d[0] * s[0] + d[1] * s[1] + d[2] * s[2];
  x[1] = d[3] * s[0] + d[4] * s[1] + d[5] * s[2];
  x[2] = d[6] * s[0] + d[7] * s[1] + d[8] * s[2];
}

// Steps one file hands another (see each definition).
void sweep_rows(Level& L, bool lexicographic);                   // colouring.cpp
void product_chunks(Level& L);                                   // colouring.cpp
void transpose_transfer(Level& F, int coarse_nodes);             // galerkin.cpp
void forward_sweep_in_order(Level& L);                           // smoother.cpp
void backward_sweep_in_order(Level& L);                          // smoother.cpp
void forward_sweep(Level& L, bool parallel);                     // smoother.cpp
void backward_sweep(Level& L, bool parallel);                    // smoother.cpp
void forward_residual(Level& L, bool parallel);                  // smoother.cpp
void scale_right_side(Level& L, bool parallel);                  // smoother.cpp
void unscale_solution(Level& L, bool parallel);                  // smoother.cpp
void subtract_product(Level& L, const double* x, double* y, bool parallel);  // smoother.cpp
void rigid_body_modes(const VolumeMesh& mesh, Level& L);         // aggregation.cpp
void lattice_level(const VolumeMesh& mesh, const LatticeCoordinates& lattice, Level& L);  // lattice.cpp

}  // namespace multigrid

/// The V-cycle's state: the levels, finest first, and the coarsest level's direct solve. Its steps are defined
/// in the files of their concern (see the list above).
struct MultigridPreconditioner::Impl {
  using Level = multigrid::Level;
  using Transfer = multigrid::Transfer;
  std::vector<Level> levels;
  std::vector<int> row_dof;  ///< free row → DOF of level 0 (3 v + axis)
  bool have_structure = false;
  std::uint64_t pattern = 0;  ///< pattern_hash of the A the structure was built for
  std::vector<int> value_slot;  ///< per stored entry of A, its index in level 0's A.val (values() copies by it)
  // The coarsest level as a scalar matrix for the direct solver.
  std::vector<int> coarse_dof;    ///< its free DOFs (3 node + axis)
  std::vector<int> coarse_value;  ///< per stored entry of `coarse`, its index in the last level's A.val
  SparseLower coarse;
  std::unique_ptr<LinearSolver> direct = make_ldlt_solver();  // small: no BLAS (its buffers and threads) needed
  Eigen::VectorXd coarse_b;
  std::vector<double> row;  ///< work: one block row of A T (smooth_prolongator(): 9 per coarse node)

  Coarsening coarsening;

  Impl(const VolumeMesh& mesh, const std::vector<int>& free_index, Coarsening how);  // hierarchy.cpp
  void grow(const std::function<void()>& coarsen);                                     // hierarchy.cpp
  void coarsen();                                                                      // lattice.cpp
  void aggregate();                                                                    // aggregation.cpp
  void coarse_pattern(std::size_t l);                                                  // galerkin.cpp
  void structure(const SparseLower& A);                                                // hierarchy.cpp
  void fine_pattern(const SparseLower& A);                                             // hierarchy.cpp
  void coarsest_matrix();                                                              // hierarchy.cpp
  bool values(const SparseLower& A, double shift, bool refresh);                       // preconditioner.cpp
  bool coarse_current = false;  ///< the coarse levels were made from a matrix of the current structure
  bool prepare_smoother(Level& L);                                                     // smoother.cpp
  void smooth_prolongator(std::size_t l);                                              // aggregation.cpp
  void galerkin(Level& fine, Level& coarse_level);                                     // galerkin.cpp
  void vcycle(std::size_t l);                                                          // preconditioner.cpp
  void product(const Eigen::VectorXd& p, Eigen::VectorXd& Ap);                         // preconditioner.cpp
  Eigen::VectorXd product_in, product_out;
  /// A level of fewer nodes runs on one thread (a parallel region costs more than it saves) and smooths by
  /// lexicographic Gauss–Seidel (x read in node order); larger ones by the multi-colour sweep in parallel.
  /// Chosen by size when the structure is made (Level::lexicographic), never by the thread count, so results
  /// stay the same for any thread count. 4096: on Figure 1 (levels of 53 158, 8 778, 1 690 and 392 nodes)
  /// level 1 in parallel took 0.90 of the wall time without contact and the same with it (docs/results.md).
  int parallel_nodes = 4096;
  [[nodiscard]] bool parallel(const Level& L) const { return L.nodes >= parallel_nodes; }
  /// The sweeps: also at least parallel_nodes / 8 nodes per phase on average (a barrier after each phase).
  [[nodiscard]] bool parallel_sweep(const Level& L) const {
    return parallel(L) && L.nodes >= parallel_nodes / 8 * (static_cast<int>(L.colour_phase.size()) - 1);
  }
};

}  // namespace snh
