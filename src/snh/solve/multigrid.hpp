#pragma once
// Multigrid V-cycles that precondition conjugate gradients (docs/design.md solve/, issue 15): geometric for
// hexahedral lattices, named "mg" in the registry, and algebraic (smoothed aggregation) for any mesh, "amg".
// Both share the V-cycle below; only the prolongation P differs. The implementation is in solve/multigrid/,
// one concern a file (its levels.hpp lists them).
//
// Levels: the simulated hex mesh, then lattices of twice the cell size, each cube of a coarse level the
// union of the (up to 8) fine cubes inside it, until a level has few enough unknowns for a direct solve
// (Eigen's LDLT: small, so no BLAS). Lattice coordinates come from the cells' corner order (VolumeMesh:
// c1 = c0 + x̂, c2 = c0 + ŷ, c4 = c0 + ẑ), walked from cell to cell, not from positions: any mesh whose hexes
// fit together as a lattice (the stretch box, `snh flesh`'s partial lattices, a structured mesh file) has
// them exactly; a mesh whose cells contradict one another is refused. Prolongation: trilinear
// interpolation of the coarse nodes, the same for x, y and z, restricted to the free DOFs on both sides (a
// coarse DOF is dropped where the fine vertex at its place is kinematic, or where it reaches no free fine
// DOF). Coarse operators: Galerkin, A_c = Pᵀ A P, in 3×3 nodal blocks (lower triangle); the block patterns
// and the transfer operators are built once and only the values are recomputed for each Newton matrix.
// Smoother: one forward multi-colour nodal-block Gauss–Seidel sweep before the coarse correction and one
// backward sweep (the colours in reverse order) after it, so the V-cycle is symmetric, and positive definite
// when A is. Colours come from the matrix, never from the thread count: lattice levels the parity of the
// lattice coordinates (8 colours), except a node coupled to a lower node of its own parity (contact couples
// nodes across the lattice), which takes a colour from 8 on greedily; aggregation levels a greedy colouring in
// node order. The nodes of one colour (a run of colours of few nodes: one thread, in turn), the rows of A x, of the restriction Pᵀ r
// and of the prolongation P e run in parallel (OpenMP; levels of at least set_parallel_nodes() nodes, smaller
// ones on one thread with a lexicographic sweep), each row's sum in a fixed order: results are bit-identical
// for any thread count.
//
// Smoothed aggregation (amg): levels from the matrix's nodal block graph, not from positions. Greedy
// aggregation of the nodes with a free DOF (every block of the pattern a connection); a tentative
// prolongator per aggregate from the 6 rigid-body modes (3 translations, 3 rotations of the rest
// positions), orthonormalized on the aggregate's free DOFs by a QR with column pivoting (rank r ≤ 6: an
// aggregate becomes two coarse nodes of 3 DOFs, those from r on not free; the coarse level's rigid-body
// modes are Qᵀ B, so coarser levels aggregate the same way); then one damped block-Jacobi step,
// P = (I − ω D⁻¹ A) P_tent with ω = 4 / (3 ρ(D⁻¹ A)), recomputed with the Galerkin products for each
// Newton matrix (aggregates and patterns: once per pattern).
#include <memory>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "snh/solve/linear_solver.hpp"

namespace snh {

/// Integer lattice coordinates of a hex mesh's vertices (see above), each connected piece of the mesh
/// shifted to start at 0.
struct LatticeCoordinates {
  Eigen::Matrix3Xi coordinates;  ///< 3 by #V
  std::vector<int> piece;        ///< per vertex, its connected piece (vertices of no cell: a piece each)
};

/// Throws std::invalid_argument (one line naming the cell) where the mesh is not hex8 or two cells give a
/// vertex different coordinates.
[[nodiscard]] LatticeCoordinates lattice_coordinates(const VolumeMesh& mesh);

/// How the levels are made: from the hex lattice (trilinear P) or by smoothed aggregation.
enum class Coarsening { lattice, aggregation };

/// The V-cycle as a preconditioner M⁻¹ ≈ A⁻¹ on the free DOFs.
class MultigridPreconditioner final : public Preconditioner {
 public:
  /// mesh: at rest (a hex8 lattice for Coarsening::lattice, any cells for aggregation); free_index: per DOF
  /// (3 #V) its row, −1 where kinematic.
  MultigridPreconditioner(const VolumeMesh& mesh, const std::vector<int>& free_index,
                          Coarsening how = Coarsening::lattice);
  ~MultigridPreconditioner() override;
  MultigridPreconditioner(const MultigridPreconditioner&) = delete;
  MultigridPreconditioner& operator=(const MultigridPreconditioner&) = delete;
  /// Takes the values of A (lower triangle on the free DOFs); the hierarchy's structure is rebuilt only
  /// when A's pattern changes. `shift` ≥ 0 is added to A's diagonal first. False where A (+ shift) is shown
  /// not to be positive definite (a nodal diagonal block or the coarsest operator is not).
  /// coarse = false keeps the coarse levels of the last compute() (same pattern), refreshing only the finest
  /// level: the V-cycle stays symmetric positive definite (its coarse correction uses an older positive
  /// definite Pᵀ A P), just weaker as A drifts from that matrix.
  [[nodiscard]] bool compute(const SparseLower& A, double shift = 0.0, bool coarse = true);
  void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override;
  /// Ap = (A + shift) p for the A and shift of the last compute(), from the nodal blocks (no copy of A is kept).
  void multiply(const Eigen::VectorXd& p, Eigen::VectorXd& Ap) const;
  /// Levels, finest first (1 = the direct solve alone).
  [[nodiscard]] int levels() const;
  /// Free DOFs of level l.
  [[nodiscard]] Eigen::Index unknowns(int level) const;
  /// The smoother's colour of each node of level l, and the node pairs (i, j < i) that level l's matrix
  /// couples (after compute(); for tests: no pair shares a colour).
  [[nodiscard]] const std::vector<int>& colours(int level) const;
  [[nodiscard]] std::vector<std::pair<int, int>> couplings(int level) const;
  /// Level l's matrix, both triangles, on all its 3 × nodes DOFs, and the prolongation from level l + 1 to
  /// level l (after compute(); for tests).
  [[nodiscard]] Eigen::SparseMatrix<double> level_matrix(int level) const;
  [[nodiscard]] Eigen::SparseMatrix<double> prolongation(int level) const;
  /// Levels of fewer nodes than this run on one thread with a lexicographic Gauss–Seidel smoother, larger
  /// ones in parallel with the multi-colour smoother (default 4 096; tests set 1 to run every level so).
  void set_parallel_nodes(int nodes);

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The registry's "mg": conjugate gradients preconditioned by the V-cycle. Throws std::invalid_argument
/// (one line) where the geometry has no mesh, or a mesh that is not a hex lattice.
[[nodiscard]] std::unique_ptr<LinearSolver> make_multigrid_solver(const LinearSolverOptions& options,
                                                                  const SolverGeometry& geometry);

/// True where "amg" can be made for this geometry: a mesh (any cell type) and a DOF index for each of its
/// vertices' DOFs (for an automatic choice of solver).
[[nodiscard]] bool amg_applicable(const SolverGeometry& geometry);

/// The registry's "amg": conjugate gradients preconditioned by the smoothed-aggregation V-cycle. Throws
/// std::invalid_argument (one line) where !amg_applicable(geometry).
[[nodiscard]] std::unique_ptr<LinearSolver> make_amg_solver(const LinearSolverOptions& options,
                                                            const SolverGeometry& geometry);

}  // namespace snh
