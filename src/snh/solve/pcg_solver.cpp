#include "snh/solve/pcg_solver.hpp"

#include <algorithm>
#include <cmath>

namespace snh {
namespace {

class PcgSolver final : public LinearSolver {
 public:
  explicit PcgSolver(double tolerance) : tolerance_(tolerance) {}
  bool try_factorize(const SparseLower& A) override {
    prepare(A);
    return true;
  }
  double factorize(const SparseLower& A) override {
    prepare(A);
    return 0.0;
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b, double enough) override {
    const int max_iterations = static_cast<int>(std::max<Eigen::Index>(1000, 2 * b.size()));
    Eigen::VectorXd x;
    const CgResult r = conjugate_gradients(A_, b, jacobi_, std::max(tolerance_ * b.norm(), enough), max_iterations, x);
    iterations_ = r.iterations;
    return r.status == CgStatus::converged ? x : Eigen::VectorXd::Constant(b.size(), std::nan(""));
  }
  int last_iterations() const override { return iterations_; }
  std::string_view name() const override { return "pcg"; }

 private:
  void prepare(const SparseLower& A) {
    A_ = A;
    jacobi_.compute(A);
  }
  double tolerance_;
  SparseLower A_;
  JacobiPreconditioner jacobi_;
  int iterations_ = 0;
};

}  // namespace

std::unique_ptr<LinearSolver> make_pcg_solver(double tolerance) { return std::make_unique<PcgSolver>(tolerance); }

}  // namespace snh
