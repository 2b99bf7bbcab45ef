#pragma once
// Measures, for every energy, the paper's four stability properties (docs/math.md §5): inversion,
// reflection, rest, and behaviour under collapse along F = sI.
#include <string>
#include <vector>

#include "snh/material/lame.hpp"

namespace snh {

/// A point 0 < s < 1 where dψ(sI)/ds = 0.
struct CriticalPoint {
  double s = 0.0;
  bool minimum = false;  ///< a local minimum along the path (else a maximum, a barrier)
};

struct StabilityRow {
  std::string name;
  bool parameters_reparametrized = false;  ///< false also when the energy has no reparametrization
  // 1. Inversion: sampled F with J < 0 and J = 0.
  int inverted_samples = 0;
  int inverted_finite = 0;            ///< samples with ψ, P and the projected Hessian all finite
  double inverted_fd_error = 0.0;     ///< worst (over samples) best-ε relative error of P against ψ
  bool inversion_ok = false;          ///< all finite and all FD errors ≤ 1e-6
  // 2. Reflection: the sign moved to each σ of the same F.
  double reflection_change = 0.0;     ///< max relative change of ψ, P, projected ∂P/∂F (NaN if undefined)
  bool reflection_ok = false;         ///< change ≤ 1e-9
  // 3. Rest.
  double rest_stress = 0.0;           ///< ‖P(I)‖
  bool rest_ok = false;               ///< ‖P(I)‖ ≤ 1e-12 (μ + |λ|)
  // 4. Collapse along F = sI, 0 < s < 1.
  std::vector<CriticalPoint> critical_points;
  double psi_at_zero = 0.0;           ///< ψ(0) (+∞ when undefined there)
  std::string near_zero;              ///< "psi->inf", "trap (local min at F=0)" or "escapes (F=0 is a max)"
  double psi_at_rest = 0.0;           ///< ψ(I)
};

struct StabilityReport {
  Lame given;
  bool reparametrize = false;
  int samples = 0;
  std::vector<StabilityRow> rows;
};

/// Runs the measurements for every registered energy.
///   p              Lamé parameters as given to make_material
///   reparametrize  map p through each energy's Lamé reparametrization where it has one
///   samples        number of random inverted F (J < 0) and degenerate F (J = 0) to test
///   seed           seed of the random samples
[[nodiscard]] StabilityReport measure_stability(const Lame& p, bool reparametrize, int samples = 200,
                                                unsigned seed = 1);

}  // namespace snh
