// The multigrid preconditioner (multigrid.hpp): each matrix's values on every level (the smoother's, the
// Galerkin products, the coarsest factorization), the V-cycle, and MultigridPreconditioner's interface. The
// levels' structure is made by hierarchy.cpp, once per pattern of A.
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

#include <fmt/format.h>

#include "snh/solve/multigrid/levels.hpp"

namespace snh {
namespace {

/// A fingerprint of a sparse matrix's pattern (its size and index arrays, FNV-1a), to tell a new pattern from
/// the last without keeping a copy (a collision, at odds of about 2⁻⁶⁴, is caught only where the entry count
/// differs: values() then finds value_slot the wrong length). The index arrays go through four interleaved
/// FNV-1a streams, combined at the end: one stream is a chain of dependent multiplications, whose latency would
/// bound the hash of a large matrix; four independent chains overlap.
std::uint64_t pattern_hash(const SparseLower& A) {
  constexpr std::uint64_t kBasis = 1469598103934665603ull, kPrime = 1099511628211ull;
  std::uint64_t h[4] = {kBasis, kBasis ^ 1, kBasis ^ 2, kBasis ^ 3};
  const auto mix = [](std::uint64_t& to, std::uint64_t v) { to = (to ^ v) * kPrime; };
  const auto stream = [&](const int* p, Eigen::Index n) {
    Eigen::Index k = 0;
    for (; k + 4 <= n; k += 4)
      for (int s = 0; s < 4; ++s) mix(h[s], static_cast<std::uint32_t>(p[k + s]));
    for (; k < n; ++k) mix(h[0], static_cast<std::uint32_t>(p[k]));
  };
  mix(h[0], static_cast<std::uint64_t>(A.rows()));
  mix(h[1], static_cast<std::uint64_t>(A.nonZeros()));
  stream(A.outerIndexPtr(), A.outerSize() + 1);
  stream(A.innerIndexPtr(), A.nonZeros());
  std::uint64_t out = kBasis;
  for (const std::uint64_t v : h) mix(out, v);
  return out;
}

}  // namespace

using namespace multigrid;

bool MultigridPreconditioner::Impl::values(const SparseLower& A, double shift, bool refresh) {
  Level& L0 = levels.front();
  // A's entries into their blocks by value_slot, a map made once per pattern, rather than a walk with a cursor
  // per row for each matrix: each entry goes to its own slot, so they go in parallel (compute() rebuilt the
  // structure, and with it value_slot, for a new pattern).
  if (value_slot.size() != static_cast<std::size_t>(A.nonZeros())) throw std::logic_error("multigrid: the matrix's pattern changed unnoticed");
  const double* v = A.valuePtr();
  double* to = L0.A.val.data();
  const int* slot = value_slot.data();
  const Eigen::Index entries = A.nonZeros();
#pragma omp parallel for schedule(static) if (parallel(L0))
  for (Eigen::Index k = 0; k < entries; ++k) to[slot[k]] = v[k];
  // The upper halves of the diagonal blocks by symmetry, and the shift.
#pragma omp parallel for schedule(static) if (parallel(L0))
  for (int i = 0; i < L0.nodes; ++i) {
    double* d = &L0.A.val[9 * static_cast<std::size_t>(L0.diagonal[i])];
    for (int a = 0; a < 3; ++a)
      for (int b = a + 1; b < 3; ++b) d[3 * a + b] = d[3 * b + a];
    for (int a = 0; a < 3; ++a)
      if (L0.free[3 * i + a]) d[4 * a] += shift;
  }
  if (!refresh && coarse_current && levels.size() > 1) return prepare_smoother(L0);
  coarse_current = false;
  for (std::size_t l = 0; l + 1 < levels.size(); ++l) {
    if (!prepare_smoother(levels[l])) return false;
    if (coarsening == Coarsening::aggregation) smooth_prolongator(l);
    galerkin(levels[l], levels[l + 1]);
  }
  const Level& K = levels.back();
  for (std::size_t e = 0; e < coarse_value.size(); ++e) coarse.valuePtr()[e] = K.A.val[coarse_value[e]];
  coarse_current = coarse.rows() == 0 || direct->try_factorize(coarse);
  return coarse_current;
}

void MultigridPreconditioner::Impl::vcycle(std::size_t l) {
  Level& L = levels[l];
  if (l + 1 == levels.size()) {
    for (std::size_t k = 0; k < coarse_dof.size(); ++k) coarse_b[static_cast<Eigen::Index>(k)] = L.b[coarse_dof[k]];
    L.x.setZero();
    if (coarse_b.size() == 0) return;
    const Eigen::VectorXd y = direct->solve(coarse_b);
    for (std::size_t k = 0; k < coarse_dof.size(); ++k) L.x[coarse_dof[k]] = y[static_cast<Eigen::Index>(k)];
    return;
  }
  Level& C = levels[l + 1];
  // The sweeps run in the scaled unknowns (prepare_smoother()): b̂ = σ b in, x = σ x̂ out; the residual and the
  // coarse correction pass between the two.
  scale_right_side(L, parallel(L));
  if (L.lexicographic) forward_sweep_in_order(L);
  else forward_sweep(L, parallel_sweep(L));
  forward_residual(L, parallel(L));
  // Restriction Pᵀ r on the coarse free DOFs (by coarse rows), prolongation P e on the fine ones.
#pragma omp parallel for schedule(static) if (parallel(C))
  for (int I = 0; I < C.nodes; ++I) {
    double e[3] = {0.0, 0.0, 0.0};
    if (L.down.weight.empty()) {
      for (int q = L.up_start[I]; q < L.up_start[I + 1]; ++q)
        subtract_transposed(&L.down.block[9 * static_cast<std::size_t>(L.up_entry[q])], L.r.data() + 3 * L.up_fine[q], e);
    } else {
      for (int q = L.up_start[I]; q < L.up_start[I + 1]; ++q) {
        const double w = L.down.weight[static_cast<std::size_t>(L.up_entry[q])], *r = L.r.data() + 3 * L.up_fine[q];
        for (int a = 0; a < 3; ++a) e[a] -= w * r[a];
      }
    }
    for (int a = 0; a < 3; ++a) C.b[3 * I + a] = C.free[3 * I + a] ? -e[a] : 0.0;
  }
  vcycle(l + 1);
#pragma omp parallel for schedule(static) if (parallel(L))
  for (int i = 0; i < L.nodes; ++i) {
    double e[3] = {0.0, 0.0, 0.0};
    if (L.down.weight.empty()) {
      for (int p = L.down.start[i]; p < L.down.start[i + 1]; ++p)
        subtract(&L.down.block[9 * static_cast<std::size_t>(p)], C.x.data() + 3 * L.down.node[p], e);
    } else {
      for (int p = L.down.start[i]; p < L.down.start[i + 1]; ++p) {
        const double w = L.down.weight[static_cast<std::size_t>(p)], *x = C.x.data() + 3 * L.down.node[p];
        for (int a = 0; a < 3; ++a) e[a] -= w * x[a];
      }
    }
    const double to_scaled = 1.0 / L.scale[static_cast<std::size_t>(i)];
    for (int a = 0; a < 3; ++a)
      if (L.free[3 * i + a]) L.x[3 * i + a] -= e[a] * to_scaled;
  }
  if (L.lexicographic) backward_sweep_in_order(L);
  else backward_sweep(L, parallel_sweep(L));
  unscale_solution(L, parallel(L));
}

MultigridPreconditioner::MultigridPreconditioner(const VolumeMesh& mesh, const std::vector<int>& free_index, Coarsening how)
    : impl_(std::make_unique<Impl>(mesh, free_index, how)) {}

MultigridPreconditioner::~MultigridPreconditioner() = default;

bool MultigridPreconditioner::compute(const SparseLower& A, double shift, bool coarse) {
  if (A.rows() != static_cast<Eigen::Index>(impl_->row_dof.size()) || A.cols() != A.rows())
    throw std::invalid_argument(fmt::format("multigrid: a {}x{} matrix for {} free DOFs", A.rows(), A.cols(), impl_->row_dof.size()));
  const std::uint64_t pattern = pattern_hash(A);
  if (!impl_->have_structure || pattern != impl_->pattern) {
    impl_->structure(A);
    impl_->coarse_current = false;
    impl_->pattern = pattern;
    impl_->have_structure = true;
  }
  return impl_->values(A, shift, coarse);
}

void MultigridPreconditioner::multiply(const Eigen::VectorXd& p, Eigen::VectorXd& Ap) const { impl_->product(p, Ap); }

void MultigridPreconditioner::Impl::product(const Eigen::VectorXd& p, Eigen::VectorXd& Ap) {
  Level& L0 = levels.front();
  product_in.setZero(3 * L0.nodes);
  for (std::size_t k = 0; k < row_dof.size(); ++k) product_in[row_dof[k]] = p[static_cast<Eigen::Index>(k)];
  product_out.resize(3 * L0.nodes);
  subtract_product(L0, product_in.data(), product_out.data(), parallel(L0));
  Ap.resize(p.size());
  for (std::size_t k = 0; k < row_dof.size(); ++k) Ap[static_cast<Eigen::Index>(k)] = -product_out[row_dof[k]];
}

void MultigridPreconditioner::apply(const Eigen::VectorXd& r, Eigen::VectorXd& z) const {
  Level& L0 = impl_->levels.front();
  L0.b.setZero();
  const auto& rows = impl_->row_dof;
  for (std::size_t k = 0; k < rows.size(); ++k) L0.b[rows[k]] = r[static_cast<Eigen::Index>(k)];
  impl_->vcycle(0);
  z.resize(r.size());
  for (std::size_t k = 0; k < rows.size(); ++k) z[static_cast<Eigen::Index>(k)] = L0.x[rows[k]];
}

int MultigridPreconditioner::levels() const { return static_cast<int>(impl_->levels.size()); }

Eigen::Index MultigridPreconditioner::unknowns(int level) const { return impl_->levels.at(level).unknowns(); }

const std::vector<int>& MultigridPreconditioner::colours(int level) const { return impl_->levels.at(level).colour; }

std::vector<std::pair<int, int>> MultigridPreconditioner::couplings(int level) const {
  const Blocks& A = impl_->levels.at(level).A;
  std::vector<std::pair<int, int>> out;
  for (std::size_t i = 0; i + 1 < A.start.size(); ++i)
    for (int s = A.start[i]; s < A.start[i + 1]; ++s)
      if (A.col[s] != static_cast<int>(i)) out.emplace_back(static_cast<int>(i), A.col[s]);
  return out;
}

Eigen::SparseMatrix<double> MultigridPreconditioner::level_matrix(int level) const {
  const Level& L = impl_->levels.at(level);
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < L.nodes; ++i)
    for (int s = L.A.start[i]; s < L.A.start[i + 1]; ++s) {
      const int j = L.A.col[s];
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) {
          const double v = L.A.val[9 * static_cast<std::size_t>(s) + 3 * a + b];
          entries.emplace_back(3 * i + a, 3 * j + b, v);
          if (j != i) entries.emplace_back(3 * j + b, 3 * i + a, v);
        }
    }
  Eigen::SparseMatrix<double> M(3 * L.nodes, 3 * L.nodes);
  M.setFromTriplets(entries.begin(), entries.end());
  return M;
}

Eigen::SparseMatrix<double> MultigridPreconditioner::prolongation(int level) const {
  const Level& F = impl_->levels.at(level);
  const Level& C = impl_->levels.at(level + 1);
  std::vector<Eigen::Triplet<double>> entries;
  for (int i = 0; i < F.nodes; ++i)
    for (int p = F.down.start[i]; p < F.down.start[i + 1]; ++p)
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b)
          entries.emplace_back(3 * i + a, 3 * F.down.node[p] + b, F.down.block[9 * static_cast<std::size_t>(p) + 3 * a + b]);
  Eigen::SparseMatrix<double> P(3 * F.nodes, 3 * C.nodes);
  P.setFromTriplets(entries.begin(), entries.end());
  return P;
}

void MultigridPreconditioner::set_parallel_nodes(int nodes) { impl_->parallel_nodes = nodes; }

}  // namespace snh
