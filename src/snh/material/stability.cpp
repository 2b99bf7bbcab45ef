#include "snh/material/stability.hpp"

#include <algorithm>
#include <cmath>
#include <random>

#include "snh/material/registry.hpp"
#include "snh/math/finite_difference.hpp"
#include "snh/math/random.hpp"

namespace snh {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

/// dψ(sI)/ds = P(sI) : I.
template <class M>
double path_slope(const M& m, double s) {
  return m.pk1(s * Mat3::Identity()).trace();
}

template <class M>
void measure_inversion(const M& m, const std::vector<Mat3>& samples, StabilityRow& row) {
  row.inverted_samples = static_cast<int>(samples.size());
  row.inverted_finite = 0;
  row.inverted_fd_error = 0.0;
  for (const Mat3& F : samples) {
    const double psi = m.psi(F);
    const Mat3 P = m.pk1(F);
    const Mat9 H = projected_hessian(m, F, PsdProjection::clamp);
    const bool finite = std::isfinite(psi) && P.allFinite() && H.allFinite();
    if (!finite) continue;
    ++row.inverted_finite;
    const double err = best_relative_error(
        P, [&](double eps) { return fd_gradient([&](const Mat3& G) { return m.psi(G); }, F, eps); });
    row.inverted_fd_error = std::max(row.inverted_fd_error, err);
  }
  if (row.inverted_finite == 0) row.inverted_fd_error = std::nan("");
  row.inversion_ok = row.inverted_finite == row.inverted_samples && row.inverted_fd_error <= 1e-6;
}

double relative_change(double a, double b) { return std::abs(a - b) / std::max(1.0, std::abs(a)); }
template <class T>
double relative_change(const T& a, const T& b) {
  return (a - b).norm() / std::max(1.0, a.norm());
}

template <class M>
void measure_reflection(const M& m, const std::vector<Mat3>& inverted, StabilityRow& row) {
  double worst = 0.0;
  bool any = false;
  for (const Mat3& F : inverted) {
    if (F.determinant() >= 0.0) continue;  // the degenerate samples have no sign to move
    const Svd3 base = rotation_variant_svd(F);
    if (!std::isfinite(psi(m, base))) continue;
    any = true;
    const double psi0 = psi(m, base);
    const Mat3 P0 = pk1(m, base);
    const Mat9 H0 = projected_hessian(m, base, PsdProjection::clamp);
    for (int k = 0; k < 2; ++k) {
      const Svd3 moved = move_reflection(base, k);
      worst = std::max({worst, relative_change(psi0, psi(m, moved)), relative_change(P0, pk1(m, moved)),
                        relative_change(H0, projected_hessian(m, moved, PsdProjection::clamp))});
    }
  }
  row.reflection_change = any ? worst : std::nan("");
  row.reflection_ok = any && worst <= 1e-9;
}

template <class M>
void measure_collapse(const M& m, StabilityRow& row) {
  constexpr int kGrid = 20000;
  constexpr double kRestGap = 1e-6;  // the rest state s = 1 itself is not reported
  row.critical_points.clear();
  double s_prev = 1.0 / kGrid;
  double d_prev = path_slope(m, s_prev);
  for (int i = 2; i < kGrid; ++i) {
    const double s = static_cast<double>(i) / kGrid;
    const double d = path_slope(m, s);
    if ((d_prev < 0.0) != (d < 0.0) && std::isfinite(d) && std::isfinite(d_prev)) {
      double lo = s_prev, hi = s;  // bisection on the sign change
      const bool rising = d > 0.0;
      for (int it = 0; it < 80; ++it) {
        const double mid = 0.5 * (lo + hi);
        if ((path_slope(m, mid) > 0.0) == rising) hi = mid;
        else lo = mid;
      }
      const double root = 0.5 * (lo + hi);
      if (root < 1.0 - kRestGap) row.critical_points.push_back({root, rising});
    }
    s_prev = s;
    d_prev = d;
  }
  row.psi_at_zero = m.psi(Mat3::Zero());
  const double slope0 = path_slope(m, 1.0 / kGrid);
  if (!std::isfinite(row.psi_at_zero) || !std::isfinite(slope0)) row.near_zero = "psi->inf";
  else if (slope0 > 0.0) row.near_zero = "trap (F=0 local min)";
  else row.near_zero = "escapes (F=0 a max)";
  row.psi_at_rest = m.psi(Mat3::Identity());
}

}  // namespace

StabilityReport measure_stability(const Lame& p, bool reparametrize, int samples, unsigned seed) {
  validate(p);
  StabilityReport report;
  report.given = p;
  report.reparametrize = reparametrize;
  report.samples = samples;

  // Inverted samples: random rotations with one negative singular value of random size (and a few
  // with all three negative), plus degenerate ones with a zero singular value.
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> mag(0.05, 2.0);
  std::vector<Mat3> inverted;
  for (int i = 0; i < samples; ++i) {
    Vec3 sigma(mag(rng), mag(rng), mag(rng));
    if (i % 10 == 9) {  // J = 0 exactly: R diag(σ0, 0, σ2) has an exactly zero middle column
      sigma[1] = 0.0;
      inverted.push_back(random_rotation(rng) * sigma.asDiagonal());
      continue;
    }
    if (i % 10 == 8) sigma = -sigma;  // all three negative
    else sigma[i % 3] = -sigma[i % 3];  // one negative
    inverted.push_back(random_matrix_with_sigma(rng, sigma));
  }

  for (std::string_view name : material_names()) {
    StabilityRow row;
    row.name = std::string(name);
    AnyMaterial material = make_material(name, p, false);
    if (reparametrize) {
      try {
        material = make_material(name, p, true);
        row.parameters_reparametrized = true;
      } catch (const ParameterError&) {
        // psi_d and arap have no reparametrization: measured with p as given.
      }
    }
    std::visit(
        [&](const auto& m) {
          measure_inversion(m, inverted, row);
          measure_reflection(m, inverted, row);
          row.rest_stress = m.pk1(Mat3::Identity()).norm();
          const Lame q = m.params();
          row.rest_ok = row.rest_stress <= 1e-12 * (q.mu + std::abs(q.lambda));
          measure_collapse(m, row);
        },
        material);
    report.rows.push_back(std::move(row));
  }
  return report;
}

}  // namespace snh
