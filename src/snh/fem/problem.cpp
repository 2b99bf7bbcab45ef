#include "snh/fem/problem.hpp"

#include <algorithm>
#include <cmath>
#include <optional>

namespace snh {

void Problem::add(Term& term) {
  terms_.push_back(&term);
  have_layout_ = false;
}

double Problem::energy(const Eigen::VectorXd& x) const {
  double total = 0.0;
  for (const Term* t : terms_) {
    const double e = t->energy(x);
    if (!std::isfinite(e)) return e;
    total += e;
  }
  return total;
}

void Problem::update_layout(const Eigen::VectorXd& x) {
  bool rebuild = !have_layout_;
  if (rebuild) {
    fixed_.assign(terms_.size(), Stencil{});
    varying_.assign(terms_.size(), Stencil{});
    for (std::size_t i = 0; i < terms_.size(); ++i)
      if (!terms_[i]->stencil_varies()) terms_[i]->stencil(x, fixed_[i]);
  }
  for (std::size_t i = 0; i < terms_.size(); ++i)
    if (terms_[i]->stencil_varies()) {
      Stencil s;
      terms_[i]->stencil(x, s);
      if (!rebuild && !layout_.covers(s)) rebuild = true;
      varying_[i] = std::move(s);
    }
  if (!rebuild) return;
  // A layout that no longer covers: the varying stencils ahead of x (Term::stencil_ahead), so that the new one
  // covers the next iterates too. The first layout is built for x alone: a scene that starts out of contact
  // may never need more.
  if (have_layout_)
    for (std::size_t i = 0; i < terms_.size(); ++i)
      if (terms_[i]->stencil_varies()) terms_[i]->stencil_ahead(x, varying_[i]);
  std::vector<const Stencil*> all;
  for (const auto* list : {&fixed_, &varying_})
    for (const Stencil& s : *list)
      if (s.groups() > 0) all.push_back(&s);
  // The old layout goes first, so that the new one takes its memory (kept in the process: keep_freed_memory)
  // rather than fresh pages; it is not needed while the new one is built. Should building fail (memory), the
  // next call builds it all again.
  have_layout_ = false;
  layout_ = HessianLayout();
  layout_ = HessianLayout(dofs_.free_index(), static_cast<int>(dofs_.free_count()), all);
  have_layout_ = true;
  ++layouts_built_;
  for (Term* t : terms_) t->bind(layout_);
}

double Problem::sum_terms(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, HessianMatrix* hessian,
                          PsdProjection projection) {
  std::optional<HessianValues> values;
  if (hessian) {  // only a Hessian needs the layout (and the varying stencils at x)
    update_layout(x);
    if (hessian->layout != layout_.id()) {
      hessian->matrix = layout_.pattern();
      hessian->layout = layout_.id();
    }
    // Zeroed in parallel above a million entries: at Figure 1's size, zeroing on one thread is a visible share
    // of every Hessian.
    double* v = hessian->matrix.valuePtr();
    const Eigen::Index n = hessian->matrix.nonZeros(), chunk = Eigen::Index{1} << 16;
#pragma omp parallel for schedule(static) if (n >= (Eigen::Index{1} << 20))
    for (Eigen::Index begin = 0; begin < n; begin += chunk) std::fill(v + begin, v + std::min(n, begin + chunk), 0.0);
    values.emplace(layout_, hessian->matrix.valuePtr());
  }
  double total = 0.0;
  for (const Term* t : terms_) {
    const double e = t->evaluate(x, gradient, values ? &*values : nullptr, projection);
    if (!std::isfinite(e)) return e;
    total += e;
  }
  return total;
}

double Problem::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd& gradient, HessianMatrix* hessian,
                         PsdProjection projection) {
  Eigen::VectorXd full = Eigen::VectorXd::Zero(x.size());
  const double total = sum_terms(x, &full, hessian, projection);
  gradient = dofs_.gather_free(full);
  return total;
}

void Problem::hessian(const Eigen::VectorXd& x, HessianMatrix& hessian, PsdProjection projection) {
  (void)sum_terms(x, nullptr, &hessian, projection);
}

double Problem::max_step(const Eigen::VectorXd& x, const Eigen::VectorXd& dx_free) const {
  double alpha = 1.0;
  Eigen::VectorXd dx;
  for (const Term* t : terms_) {
    if (dx.size() == 0) dx = dofs_.expand(dx_free);
    alpha = std::min(alpha, t->max_step(x, dx));
  }
  return alpha;
}

void Problem::on_accepted(const Eigen::VectorXd& x) {
  for (Term* t : terms_) t->on_accepted(x);
}

void Problem::at_time(double t) {
  for (Term* term : terms_) term->at_time(t);
}

}  // namespace snh
