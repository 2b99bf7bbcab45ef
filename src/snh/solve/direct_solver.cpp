#include "snh/solve/direct_solver.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <new>
#include <stdexcept>
#include <type_traits>

#include <Eigen/CholmodSupport>
#include <Eigen/SparseCholesky>
#include <fmt/format.h>
#include <dlfcn.h>
#include <sys/mman.h>

#include "snh/solve/memory_estimate.hpp"

namespace snh {
namespace {

bool same_pattern(const SparseLower& a, const SparseLower& b) {
  if (a.rows() != b.rows() || a.nonZeros() != b.nonZeros()) return false;
  return std::equal(a.outerIndexPtr(), a.outerIndexPtr() + a.outerSize() + 1, b.outerIndexPtr()) &&
         std::equal(a.innerIndexPtr(), a.innerIndexPtr() + a.nonZeros(), b.innerIndexPtr());
}

/// Adds shift to the diagonal of a lower-triangular CSC matrix whose every column starts at its diagonal.
void add_to_diagonal(SparseLower& A, double shift) {
  for (Eigen::Index c = 0; c < A.outerSize(); ++c) {
    const int first = A.outerIndexPtr()[c];
    if (A.outerIndexPtr()[c + 1] > first && A.innerIndexPtr()[first] == c) A.valuePtr()[first] += shift;
    else throw std::logic_error("add_to_diagonal: missing diagonal entry");
  }
}

Eigen::VectorXd not_a_solution(Eigen::Index n) { return Eigen::VectorXd::Constant(n, std::nan("")); }

/// CHOLMOD's supernodal LLᵀ with access to its symbolic factor.
class Cholmod final : public Eigen::CholmodSupernodalLLT<SparseLower, Eigen::Lower> {
 public:
  /// The analysed (symbolic, or numeric after a factorization) factor; null before the analysis.
  const cholmod_factor* factor() const { return m_cholmodFactor; }
};

/// OpenBLAS's work buffer (BUFFER_SIZE of Debian's build, 128 MiB), mapped at the first BLAS call that
/// needs it; when that mapping fails, its blas_memory_alloc retries forever (a hang, not an error).
constexpr std::size_t kBlasBuffer = std::size_t{128} << 20;

/// Before the first numeric factorization of an analysis: whether the address space has room for the
/// supernodal factor (xsize values), its largest update workspace (maxcsize), the copy of A that CHOLMOD
/// factors (the upper triangle: a lower one is transposed first), 16 MiB for the rest of its workspace and
/// the allocator, and OpenBLAS's buffer. Only reserved, never touched, and released at once; false where a
/// factorization would run out of memory, or hang inside OpenBLAS. (Without the copy and the 16 MiB, a run
/// under a tight ulimit -v passed the check and then hung: the factor had been allocated, OpenBLAS's buffer
/// failed, and OpenBLAS retries that allocation forever.)
bool room_for_first_factorization(const cholmod_factor* L, const SparseLower& A) {
  if (!L || !L->is_super || L->x) return true;  // analysed only: the first factorization still allocates
  const double copy = 12.0 * static_cast<double>(A.nonZeros()) + 8.0 * static_cast<double>(A.cols() + 1);
  const double bytes = 8.0 * (static_cast<double>(L->xsize) + static_cast<double>(L->maxcsize)) + copy +
                       static_cast<double>(std::size_t{16} << 20) + kBlasBuffer;
  if (bytes > 0.9 * static_cast<double>(SIZE_MAX)) return false;
  void* p = ::mmap(nullptr, static_cast<std::size_t>(bytes), PROT_NONE, MAP_PRIVATE | MAP_ANONYMOUS | MAP_NORESERVE, -1, 0);
  if (p == MAP_FAILED) return false;
  ::munmap(p, static_cast<std::size_t>(bytes));
  return true;
}

/// Below this many flops for a factorization (CHOLMOD's estimate after its analysis) the BLAS runs on one
/// thread: on small factorizations OpenBLAS's second thread spends more time waiting (sched_yield) than it
/// saves, while large ones are faster on two (hexcli at res 10 and 20: docs/results.md, "Assembly").
constexpr double kThreadedBlasFlops = 3e9;

/// CHOLMOD and LDLᵀ share the symbolic-reuse and shift logic.
template <class Factor>
class DirectSolver final : public LinearSolver {
 public:
  explicit DirectSolver(std::string_view name) : name_(name) {
    // try_factorize expects indefinite matrices: keep CHOLMOD from printing a warning for each.
    if constexpr (requires(Factor& f) { f.cholmod(); }) factor_.cholmod().print = 0;
  }
  bool try_factorize(const SparseLower& A) override {
    if (!analysed_ || !same_pattern(A, pattern_)) {
      pattern_ = A;
      guarded("symbolic analysis", [&] { factor_.analyzePattern(A); });
      if constexpr (std::is_same_v<Factor, Cholmod>) (void)choose_blas_threads(factor_.cholmod().fl);
      analysed_ = true;
    }
    return numeric(A);
  }
  double factorize(const SparseLower& A) override {
    if (try_factorize(A)) return 0.0;
    // The shared search (linear_solver.hpp): each shift added to the last shifted copy.
    SparseLower shifted = A;
    double applied = 0.0;
    const double shift = search_diagonal_shift(A, [&](double s) {
      add_to_diagonal(shifted, s - applied);
      applied = s;
      return numeric(shifted);
    });
    if (!std::isnan(shift)) return shift;
    throw std::runtime_error(fmt::format("{}: the Newton matrix could not be factorized even with a diagonal shift "
                                         "of {:g} (it has a non-finite entry)",
                                         name_, applied));
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b, double /*enough*/) override { return factor_.solve(b); }
  int factorizations() const override { return factorizations_; }
  std::string_view name() const override { return name_; }

 private:
  /// Factorizes A (pattern analysed); true if it succeeded and (for LDLᵀ) every pivot is positive.
  bool numeric(const SparseLower& A) {
    ++factorizations_;
    guarded("factorization", [&] {
      if constexpr (std::is_same_v<Factor, Cholmod>)
        if (!room_for_first_factorization(factor_.factor(), A)) throw std::bad_alloc();
      factor_.factorize(A);
    });
    return factor_.info() == Eigen::Success && positive_pivots();
  }
  /// Runs a step of the factorization; a failed allocation (CHOLMOD's status, or std::bad_alloc) throws
  /// OutOfMemoryError instead of passing for a matrix that is not positive definite.
  template <class Step>
  void guarded(const char* what, Step step) {
    const auto oom = [&] {
      return OutOfMemoryError(fmt::format("{}'s {} ({} unknowns)", name_ == "cholmod" ? "CHOLMOD" : "LDLT", what,
                                          pattern_.rows()));
    };
    if constexpr (requires(Factor& f) { f.cholmod(); }) factor_.cholmod().status = CHOLMOD_OK;
    try {
      step();
    } catch (const std::bad_alloc&) {
      throw oom();
    }
    if constexpr (requires(Factor& f) { f.cholmod(); })
      if (factor_.cholmod().status == CHOLMOD_OUT_OF_MEMORY || factor_.cholmod().status == CHOLMOD_TOO_LARGE) throw oom();
  }
  bool positive_pivots() const {
    if constexpr (requires(const Factor& f) { f.vectorD(); }) return (factor_.vectorD().array() > 0.0).all();
    else return true;  // LLᵀ fails by itself when not positive definite
  }
  std::string_view name_;
  Factor factor_;
  SparseLower pattern_;
  bool analysed_ = false;
  int factorizations_ = 0;
};

/// The last factor of a direct solver as a preconditioner.
class FactorPreconditioner final : public Preconditioner {
 public:
  explicit FactorPreconditioner(LinearSolver& direct) : direct_(direct) {}
  void apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const override { z = direct_.solve(r); }

 private:
  LinearSolver& direct_;
};

/// A direct solver whose last factor preconditions conjugate gradients on later matrices of the same
/// pattern, refactorizing only when that stops paying (see linear_solver.hpp).
class FactorReuse final : public LinearSolver {
 public:
  FactorReuse(std::unique_ptr<LinearSolver> direct, double tolerance, int max_iterations)
      : direct_(std::move(direct)), preconditioner_(*direct_), tolerance_(tolerance), max_iterations_(max_iterations) {}
  bool try_factorize(const SparseLower& A) override { return prepare(A, Mode::reuse_try) || fresh(Mode::direct_try); }
  double factorize(const SparseLower& A) override {
    if (prepare(A, Mode::reuse_must)) return 0.0;
    fresh(Mode::direct_must);
    return shift_;
  }
  Eigen::VectorXd solve(const Eigen::VectorXd& b, double enough) override {
    iterations_ = 0;
    if (mode_ == Mode::direct_try || mode_ == Mode::direct_must) return direct_->solve(b);
    Eigen::VectorXd x;
    const CgResult r =
        conjugate_gradients(A_, b, preconditioner_, std::max(tolerance_ * b.norm(), enough), max_iterations_, x);
    iterations_ = r.iterations;
    if (r.status == CgStatus::converged) {
      stale_ = 2 * iterations_ > max_iterations_;  // the factor is drifting away: refresh it next time
      return x;
    }
    // A proven indefinite after try_factorize: report it (the factor stays a good preconditioner).
    if (r.status == CgStatus::indefinite && mode_ == Mode::reuse_try) return not_a_solution(b.size());
    // Too slow, or indefinite where a solution is required: factorize this matrix.
    if (!fresh(mode_ == Mode::reuse_try ? Mode::direct_try : Mode::direct_must)) return not_a_solution(b.size());
    return direct_->solve(b);
  }
  int last_iterations() const override { return iterations_; }
  int factorizations() const override { return direct_->factorizations(); }
  std::string_view name() const override { return direct_->name(); }

 private:
  enum class Mode { direct_try, direct_must, reuse_try, reuse_must };
  /// Takes A; true if the held factor can precondition it (then mode becomes `reuse`).
  bool prepare(const SparseLower& A, Mode reuse) {
    const bool reusable = have_factor_ && !stale_ && same_pattern(A, A_);
    if (reusable) std::copy(A.valuePtr(), A.valuePtr() + A.nonZeros(), A_.valuePtr());
    else A_ = A;
    mode_ = reuse;
    return reusable;
  }
  /// Factorizes A_ (shifted if `direct_must`); false if A_ is not positive definite (`direct_try`).
  bool fresh(Mode direct) {
    mode_ = direct;
    stale_ = false;
    shift_ = 0.0;
    if (direct == Mode::direct_must) {
      shift_ = direct_->factorize(A_);
      have_factor_ = true;
    } else {
      have_factor_ = direct_->try_factorize(A_);
    }
    return have_factor_;
  }
  std::unique_ptr<LinearSolver> direct_;
  FactorPreconditioner preconditioner_;
  double tolerance_;
  int max_iterations_;
  SparseLower A_;
  Mode mode_ = Mode::direct_try;
  bool have_factor_ = false, stale_ = false;
  double shift_ = 0.0;
  int iterations_ = 0;
};

}  // namespace

int choose_blas_threads(double flops) {
  // OpenBLAS's functions, looked up at run time so that any other BLAS is left as it is.
  using Set = void (*)(int);
  using Get = int (*)();
  static const Set set = reinterpret_cast<Set>(::dlsym(RTLD_DEFAULT, "openblas_set_num_threads"));
  static const Get get = reinterpret_cast<Get>(::dlsym(RTLD_DEFAULT, "openblas_get_num_threads"));
  static const int initial = get ? get() : 0;
  if (!set || !get) return 0;
  set(flops < kThreadedBlasFlops ? 1 : initial);
  return get();
}

std::unique_ptr<LinearSolver> make_cholmod_solver() {
  return std::make_unique<DirectSolver<Cholmod>>("cholmod");
}

std::unique_ptr<LinearSolver> make_ldlt_solver() {
  return std::make_unique<DirectSolver<Eigen::SimplicialLDLT<SparseLower, Eigen::Lower>>>("ldlt");
}

std::unique_ptr<LinearSolver> with_factor_reuse(std::unique_ptr<LinearSolver> direct, double tolerance, int max_iterations) {
  return std::make_unique<FactorReuse>(std::move(direct), tolerance, max_iterations);
}

}  // namespace snh
