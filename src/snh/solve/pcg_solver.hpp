#pragma once
// Conjugate gradients with a Jacobi preconditioner as a linear solver (docs/design.md), named "pcg".
#include <memory>

#include "snh/solve/linear_solver.hpp"

namespace snh {

/// Gives up (non-finite result) after max(1000, 2 n) iterations or at a direction of non-positive curvature.
///   tolerance  relative residual at which it stops
[[nodiscard]] std::unique_ptr<LinearSolver> make_pcg_solver(double tolerance);

}  // namespace snh
