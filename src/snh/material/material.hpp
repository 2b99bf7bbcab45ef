#pragma once
// The material concept and the operations every energy supports, dispatched at compile time
// (no virtual call; the runtime choice is one std::visit outside any element loop, see registry.hpp).
#include <concepts>
#include <limits>
#include <string_view>

#include "snh/material/eigensystem.hpp"
#include "snh/material/lame.hpp"
#include "snh/material/psd_projection.hpp"
#include "snh/math/svd.hpp"
#include "snh/math/types.hpp"

namespace snh {

/// An energy whose Hessian's eigensystem comes from its signed singular values (docs/math.md §4): ψ̂(σ), ∇ψ̂(σ)
/// and the σ-frame eigenvalues, assembled with the SVD's rotations.
template <class M>
concept SigmaEigensystem = requires(const M m, const Vec3& s) {
  { m.defined_sigma(s) } -> std::same_as<bool>;
  { m.psi_sigma(s) } -> std::same_as<double>;
  { m.grad_sigma(s) } -> std::same_as<Vec3>;
  { m.sigma_eigenvalues(s) } -> std::same_as<SigmaEigenvalues>;
};

/// An energy that gives its Hessian's eigensystem directly (a quadratic energy: the same at every F).
template <class M>
concept OwnEigensystem = requires(const M m) {
  { m.eigensystem() } -> std::same_as<Eigensystem9>;
};

/// An energy density: ψ(F), P(F) = ∂ψ/∂F, ∂P/∂F (9x9, column-major vec), whether F is in its domain, and
/// one of the two routes to its Hessian's eigensystem (needed by the PSD projection).
template <class M>
concept Material = requires(const M m, const Mat3& F, const Lame& p) {
  { M::name } -> std::convertible_to<std::string_view>;
  { M::formula } -> std::convertible_to<std::string_view>;
  { M::inversion_safe } -> std::convertible_to<bool>;
  { M::from_linear(p) } -> std::same_as<Lame>;
  { m.params() } -> std::same_as<Lame>;
  { m.defined(F) } -> std::same_as<bool>;
  { m.psi(F) } -> std::same_as<double>;
  { m.pk1(F) } -> std::same_as<Mat3>;
  { m.hessian(F) } -> std::same_as<Mat9>;
} && (SigmaEigensystem<M> || OwnEigensystem<M>);

/// An isotropic energy: also ψ̂(σ), ∇ψ̂(σ) and the σ-frame eigenvalues at signed singular values.
template <class M>
concept IsotropicMaterial = Material<M> && SigmaEigensystem<M>;

/// The 9x9 eigensystem of ∂P/∂F at the F whose SVD is given (docs/math.md §4).
template <Material M>
[[nodiscard]] Eigensystem9 eigensystem(const M& m, const Svd3& svd) {
  if constexpr (IsotropicMaterial<M>) {
    return assemble_eigensystem(svd, m.sigma_eigenvalues(svd.sigma));
  } else {
    return m.eigensystem();
  }
}

/// ψ evaluated from a precomputed SVD: ψ̂(σ) for isotropic energies.
template <Material M>
[[nodiscard]] double psi(const M& m, const Svd3& svd) {
  if constexpr (IsotropicMaterial<M>) return m.psi_sigma(svd.sigma);
  else return m.psi(svd.reconstruct());
}

/// P evaluated from a precomputed SVD: U diag(∇ψ̂(σ)) Vᵀ for isotropic energies.
template <Material M>
[[nodiscard]] Mat3 pk1(const M& m, const Svd3& svd) {
  if constexpr (IsotropicMaterial<M>) return svd.U * m.grad_sigma(svd.sigma).asDiagonal() * svd.V.transpose();
  else return m.pk1(svd.reconstruct());
}

/// The PSD-projected ∂P/∂F from a precomputed SVD. Zero where the energy is undefined.
template <Material M>
[[nodiscard]] Mat9 projected_hessian(const M& m, const Svd3& svd, PsdProjection p) {
  if constexpr (IsotropicMaterial<M>) {
    if (!m.defined_sigma(svd.sigma)) return Mat9::Zero();
    return projected_from_sigma(svd, m.sigma_eigenvalues(svd.sigma), p);
  } else {
    return rebuild(eigensystem(m, svd), p);
  }
}

/// The PSD-projected ∂P/∂F (docs/math.md §4). PsdProjection::none returns the analytic Hessian.
/// Zero where the energy is undefined.
template <Material M>
[[nodiscard]] Mat9 projected_hessian(const M& m, const Mat3& F, PsdProjection p) {
  if (p == PsdProjection::none) return m.hessian(F);
  if constexpr (IsotropicMaterial<M>) {
    return projected_hessian(m, rotation_variant_svd(F), p);
  } else {
    return rebuild(m.eigensystem(), p);
  }
}

/// ψ, P and the (projected) ∂P/∂F at one F, as the element loop needs them. P and H hold values only where
/// point_terms() was asked for them (want_P, want_H), and are left unset otherwise: zeroing the 81 doubles of
/// H for every point of every energy and gradient evaluation was a large share of point_terms()'s time.
struct PointTerms {
  double psi = 0.0;
  Mat3 P;
  Mat9 H;
};

/// ψ(F), and when asked P(F) and projected_hessian(m, F, p), with the SVD of F computed at most once: for an
/// energy of I1 (corotated, ARAP) ψ, P and ∂P/∂F all come from one SVD; otherwise only the projection
/// needs it. The values are those of m.psi(F), m.pk1(F) and projected_hessian(m, F, p), bit for bit.
template <Material M>
[[nodiscard]] PointTerms point_terms(const M& m, const Mat3& F, bool want_P, bool want_H, PsdProjection p) {
  PointTerms out;
  if constexpr (requires { M::uses_I1; }) {
    if constexpr (M::uses_I1) {
      const Svd3 svd = rotation_variant_svd(F);
      out.psi = m.psi_sigma(svd.sigma);
      if (want_P) {
        // Constructed, as pk1(F) returns it: Eigen evaluates a product assigned to an existing matrix in
        // another order (the last bits differ).
        const Mat3 P = svd.U * m.grad_sigma(svd.sigma).asDiagonal() * svd.V.transpose();
        out.P = P;
      }
      if (want_H) {
        if (p == PsdProjection::none)
          out.H = rebuild(assemble_eigensystem(svd, m.sigma_eigenvalues(svd.sigma)), PsdProjection::none);
        else out.H = projected_hessian(m, svd, p);
      }
      return out;
    }
  }
  out.psi = m.psi(F);
  if (want_P) out.P = m.pk1(F);
  if (want_H) out.H = projected_hessian(m, F, p);
  return out;
}

/// Everything about one F, with an explicit domain status.
struct Evaluation {
  bool defined = true;  ///< false where the energy is undefined (log J or J^(−2/3) at J ≤ 0)
  double psi = 0.0;     ///< +∞ where undefined
  Mat3 P = Mat3::Zero();
  Mat9 H = Mat9::Zero();  ///< projected as asked
};

template <Material M>
[[nodiscard]] Evaluation evaluate(const M& m, const Mat3& F, PsdProjection p) {
  Evaluation e;
  e.defined = m.defined(F);
  if (!e.defined) {
    e.psi = std::numeric_limits<double>::infinity();
    return e;
  }
  e.psi = m.psi(F);
  e.P = m.pk1(F);
  e.H = projected_hessian(m, F, p);
  return e;
}

}  // namespace snh
