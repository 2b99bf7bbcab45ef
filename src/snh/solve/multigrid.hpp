#pragma once
// Geometric multigrid for hexahedral lattices (DESIGN.md solve/, issue 15): a V-cycle that preconditions
// conjugate gradients, named "mg" in the registry.
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
// Smoother: one forward nodal-block Gauss–Seidel sweep before the coarse correction and one backward sweep
// after it, so the V-cycle is symmetric, and positive definite when A is. Every loop runs in a fixed order
// on one thread: results do not depend on the thread count.
#include <memory>

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

/// The V-cycle as a preconditioner M⁻¹ ≈ A⁻¹ on the free DOFs.
class MultigridPreconditioner final : public Preconditioner {
 public:
  /// mesh: hex8 lattice at rest; free_index: per DOF (3 #V) its row, −1 where kinematic.
  MultigridPreconditioner(const VolumeMesh& mesh, const std::vector<int>& free_index);
  ~MultigridPreconditioner() override;
  MultigridPreconditioner(const MultigridPreconditioner&) = delete;
  MultigridPreconditioner& operator=(const MultigridPreconditioner&) = delete;
  /// Takes the values of A (lower triangle on the free DOFs); the hierarchy's structure is rebuilt only
  /// when A's pattern changes. `shift` ≥ 0 is added to A's diagonal first. False where A (+ shift) is shown
  /// not to be positive definite (a nodal diagonal block or the coarsest operator is not).
  [[nodiscard]] bool compute(const SparseLower& A, double shift = 0.0);
  void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override;
  /// Ap = (A + shift) p for the A and shift of the last compute(), from the nodal blocks (no copy of A is kept).
  void multiply(const Eigen::VectorXd& p, Eigen::VectorXd& Ap) const;
  /// Levels, finest first (1 = the direct solve alone).
  [[nodiscard]] int levels() const;
  /// Free DOFs of level l.
  [[nodiscard]] Eigen::Index unknowns(int level) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// The registry's "mg": conjugate gradients preconditioned by the V-cycle. Throws std::invalid_argument
/// (one line) where the geometry has no mesh, or a mesh that is not a hex lattice.
[[nodiscard]] std::unique_ptr<LinearSolver> make_multigrid_solver(const LinearSolverOptions& options,
                                                                  const SolverGeometry& geometry);

}  // namespace snh
