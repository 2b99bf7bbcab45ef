#pragma once
// The sparse matrix type shared by assembly (fem/) and the linear solvers (solve/).
#include <Eigen/SparseCore>

namespace snh {

/// The lower triangle of a symmetric matrix, column-major (the form CHOLMOD takes); every column starts
/// with its diagonal entry.
using SparseLower = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

}  // namespace snh
