#pragma once
// Material parameter options shared by the subcommands: --mu/--lambda or --youngs/--poisson, and
// --reparametrize.
#include <cmath>
#include <string>

#include <CLI/CLI.hpp>

#include "snh/material/lame.hpp"
#include "snh/material/registry.hpp"

namespace snh::cli {

struct ParameterOptions {
  double mu = 1.0, lambda = 10.0;
  double youngs = std::nan(""), poisson = std::nan("");
  bool reparametrize = false;

  /// The Lamé parameters chosen (validated). Throws ParameterError with a one-line message.
  [[nodiscard]] Lame lame() const {
    if (!std::isnan(youngs) || !std::isnan(poisson)) {
      if (std::isnan(youngs) || std::isnan(poisson)) throw ParameterError("--youngs and --poisson go together");
      return lame_from_youngs(youngs, poisson);
    }
    const Lame p{mu, lambda};
    validate(p);
    return p;
  }
};

/// Adds --mu, --lambda, --youngs, --poisson (exclusive with the first two) and --reparametrize. `defaults`:
/// the help's words for what is used when none is given (the paper's example mu 1, lambda 10 by default).
inline void add_parameter_options(CLI::App* cmd, ParameterOptions& o, const std::string& defaults = "") {
  auto* mu = cmd->add_option("--mu", o.mu, defaults.empty() ? "Lame mu (default 1)" : "Lame mu (with --lambda; default: " + defaults + ")");
  auto* lambda = cmd->add_option("--lambda", o.lambda,
                                 defaults.empty() ? "Lame lambda (default 10, the paper's example)" : "Lame lambda (with --mu)");
  auto* E = cmd->add_option("--youngs", o.youngs, "Young's modulus E (with --poisson, instead of --mu/--lambda)");
  auto* nu = cmd->add_option("--poisson", o.poisson, "Poisson's ratio nu, -1 < nu < 0.5");
  E->excludes(mu)->excludes(lambda);
  nu->excludes(mu)->excludes(lambda);
  cmd->add_flag("--reparametrize", o.reparametrize,
                "Take the parameters as linear-elastic mu_L, lambda_L and map them so the energy matches linear "
                "elasticity at rest (docs/math.md section 2); without it they are used as given, as the paper's programs do");
}

/// "stable_neo_hookean, stable_neo_hookean_log, ..." for help texts.
[[nodiscard]] inline std::string material_name_list() {
  std::string names;
  for (auto n : material_names()) names += (names.empty() ? "" : ", ") + std::string(n);
  return names;
}

}  // namespace snh::cli
