#pragma once
// Direct solvers for the Newton step (docs/design.md): CHOLMOD's supernodal LLᵀ and Eigen's simplicial
// LDLᵀ, with the symbolic analysis reused while the pattern is unchanged and a doubling diagonal shift for
// a matrix that is not positive definite; and factor reuse, which preconditions conjugate gradients on
// later matrices with the last factor (linear_solver.hpp). Made through the registry in linear_solver.hpp.
#include <memory>

#include "snh/solve/linear_solver.hpp"

namespace snh {

/// CHOLMOD supernodal Cholesky, named "cholmod".
[[nodiscard]] std::unique_ptr<LinearSolver> make_cholmod_solver();
/// Eigen's simplicial LDLᵀ (positive pivots required), named "ldlt".
[[nodiscard]] std::unique_ptr<LinearSolver> make_ldlt_solver();
/// Wraps a direct solver: its last factor preconditions conjugate gradients on later matrices of the same
/// pattern until they stop converging within max_iterations (or needed more than half of them last time).
///   direct          the direct solver (owned)
///   tolerance       relative residual at which conjugate gradients stop
///   max_iterations  iterations allowed with a reused factor before refactorizing
[[nodiscard]] std::unique_ptr<LinearSolver> with_factor_reuse(std::unique_ptr<LinearSolver> direct, double tolerance,
                                                              int max_iterations);

/// The BLAS threads for a factorization of `flops` (CHOLMOD's estimate, made by each new analysis): one
/// below 3e9 flops, where OpenBLAS's idle threads cost more than they save, else OpenBLAS's own count. Sets
/// them where the BLAS is OpenBLAS (found at run time) and returns the count set; 0 for any other BLAS.
int choose_blas_threads(double flops);

}  // namespace snh
