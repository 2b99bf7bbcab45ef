#include "material_command.hpp"

#include <array>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>
#include <string>
#include <string_view>
#include <vector>

#include <fmt/format.h>
#include <nlohmann/json.hpp>

#include "../common/out_option.hpp"
#include "parameter_options.hpp"
#include "snh/material/fibre.hpp"
#include "snh/material/printable.hpp"
#include "snh/material/registry.hpp"
#include "snh/material/stability.hpp"
#include "snh/math/svd.hpp"

namespace snh::cli {
namespace {

using nlohmann::json;

struct MaterialOptions {
  std::string name;
  ParameterOptions params;
  std::string F_text;
  std::vector<double> stretch;
  std::string projection = "clamp";
  bool json = false, stability = false, list = false;
  int samples = 200;
  unsigned seed = 1;
  std::vector<double> fibre;  ///< a fibre direction (3 numbers): the fibre and muscle sections are printed
  std::string fibre_model = "signed_arap";
  double fibre_stiffness = std::numeric_limits<double>::quiet_NaN();  ///< unset: the material's mu
  double contraction = 0.0;  ///< active strain alpha in [0, 1)
};

/// The fibre, its energy and the active strain given by --fibre, --fibre-model, --fibre-stiffness and
/// --contraction (none without --fibre).
struct FibreSetup {
  Vec3 a;
  FibreEnergy energy;
  ActiveStrain active;
};
std::optional<FibreSetup> fibre_setup(const MaterialOptions& o, double mu) {
  if (o.fibre.empty()) {
    if (o.contraction != 0.0 || !std::isnan(o.fibre_stiffness) || o.fibre_model != "signed_arap")
      throw std::invalid_argument("--fibre-model, --fibre-stiffness and --contraction need --fibre X Y Z");
    return std::nullopt;
  }
  FibreSetup f;
  const Vec3 a(o.fibre[0], o.fibre[1], o.fibre[2]);
  if (!(a.norm() > 0.0)) throw std::invalid_argument("--fibre: the direction (0, 0, 0) has no length");
  f.a = a.normalized();
  if (o.fibre_model == "quadratic") f.energy.model = FibreModel::quadratic;
  else if (o.fibre_model == "signed_arap") f.energy.model = FibreModel::signed_arap;
  else throw std::invalid_argument(fmt::format("--fibre-model must be quadratic or signed_arap, got '{}'", printable(o.fibre_model)));
  f.energy.stiffness = std::isnan(o.fibre_stiffness) ? mu : o.fibre_stiffness;
  if (!(o.contraction >= 0.0 && o.contraction < 1.0))
    throw std::invalid_argument(fmt::format("--contraction must be in [0, 1), got {:g}", o.contraction));
  f.active = ActiveStrain::along(f.a, o.contraction);
  return f;
}

/// Nine finite numbers separated by spaces or commas: vec(F), column by column.
Mat3 parse_F(const std::string& text) {
  std::string cleaned = text;
  for (char& c : cleaned)
    if (c == ',') c = ' ';
  std::istringstream in(cleaned);
  std::vector<double> values;
  std::string token;
  while (in >> token) {
    char* end = nullptr;
    const double v = std::strtod(token.c_str(), &end);
    if (end == token.c_str() || *end != '\0' || !std::isfinite(v))
      throw std::invalid_argument(
          fmt::format("--F entry {} is not a finite number: '{}'", values.size(), token));
    values.push_back(v);
  }
  if (values.size() != 9)
    throw std::invalid_argument(fmt::format("--F needs 9 numbers (vec(F), column by column), got {}", values.size()));
  Mat3 F;
  for (int k = 0; k < 9; ++k) F.data()[k] = values[k];
  return F;
}

/// The supported magnitudes of the entries of F: 0 or |f| in [1e-20, 1e20]. Within them every energy's
/// psi, P and dP/dF stay finite for mu, |lambda| <= 1e12 (J <= 6e60); beyond them they overflow to
/// inf/nan, so such an F is refused before any work, naming the entry.
constexpr double kMinEntry = 1e-20, kMaxEntry = 1e20;

void check_F_range(const Mat3& F, bool from_stretch) {
  for (int k = 0; k < 9; ++k) {
    const double f = F.data()[k];
    if (f == 0.0 || (std::abs(f) >= kMinEntry && std::abs(f) <= kMaxEntry)) continue;
    const std::string which = from_stretch ? fmt::format("--stretch value {}", k / 4) : fmt::format("--F entry {}", k);
    throw std::invalid_argument(fmt::format("{} = {:g} is outside the supported range (0 or |f| in [{:g}, {:g}])",
                                            which, f, kMinEntry, kMaxEntry));
  }
}

json matrix_json(const Mat3& A) {
  json rows = json::array();
  for (int i = 0; i < 3; ++i) rows.push_back({A(i, 0), A(i, 1), A(i, 2)});
  return rows;
}

std::string matrix_text(const Mat3& A, const std::string& indent) {
  std::string out;
  for (int i = 0; i < 3; ++i)
    out += fmt::format("{}[{:>13.6g} {:>13.6g} {:>13.6g} ]\n", indent, A(i, 0), A(i, 1), A(i, 2));
  return out;
}

/// The fibre and muscle sections: the base material and the fibre on the elastic part F_e = F F_a⁻¹, their
/// sum, and the muscle's P = (P + P_fibre)(F_e) F_a⁻¹.
template <class M>
int run_muscle(const MaterialOptions& o, const M& m, const Mat3& F, const FibreSetup& f, PsdProjection projection) {
  const Mat3 E = f.active.elastic(F);
  const bool defined = m.defined(E);
  const double sign = fibre_sign(E, f.a), I4 = (E * f.a).squaredNorm();
  const Eigensystem9 es = f.energy.eigensystem(E, f.a);
  const double psi_fibre = f.energy.psi(E, f.a);
  const Mat3 P_fibre = f.energy.pk1(E, f.a);
  constexpr std::array<std::string_view, 3> labels = {"along the fibre", "across the fibre", "across the fibre"};
  if (o.json) {
    json j;
    j["material"] = std::string(M::name);
    j["mu"] = m.params().mu;
    j["lambda"] = m.params().lambda;
    j["F"] = matrix_json(F);
    j["fibre"] = {{"direction", {f.a[0], f.a[1], f.a[2]}}, {"model", std::string(to_string(f.energy.model))},
                  {"stiffness", f.energy.stiffness}, {"contraction", o.contraction}, {"F_a", matrix_json(f.active.deformation())},
                  {"F_e", matrix_json(E)}, {"I4", I4}, {"sign", sign}, {"psi", psi_fibre}, {"P", matrix_json(P_fibre)}};
    json eig = json::array();
    for (int i = 0; i < 9; ++i)
      eig.push_back({{"label", i < 3 ? std::string(labels[static_cast<std::size_t>(i)]) : std::string("cross-section")},
                     {"value", es.values[static_cast<std::size_t>(i)]},
                     {"projected", project_eigenvalue(es.values[static_cast<std::size_t>(i)], projection)}});
    j["fibre"]["eigenvalues"] = eig;
    j["defined"] = defined;
    j["projection"] = o.projection;
    if (defined) {
      j["psi_material"] = m.psi(E);
      j["psi"] = m.psi(E) + psi_fibre;
      j["P"] = matrix_json(f.active.pk1(m.pk1(E) + P_fibre));
    } else {
      j["psi"] = nullptr;
      j["reason"] = fmt::format("{} is undefined for J <= 0 (J = {:g})", M::name, E.determinant());
    }
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  std::cout << fmt::format("material   {}: psi = {}\n", M::name, M::formula);
  std::cout << fmt::format("parameters {}\n", describe(m.params()));
  std::cout << fmt::format("fibre      {} along a = ({:.6g}, {:.6g}, {:.6g}), stiffness k = {:g}\n", to_string(f.energy.model), f.a[0],
                           f.a[1], f.a[2], f.energy.stiffness);
  std::cout << "F\n" << matrix_text(F, "  ");
  if (o.contraction > 0.0) {
    std::cout << fmt::format("active strain, contraction {:g}: the fibre's rest length is {:g}; the energies act on F_e = F F_a^-1\n",
                             o.contraction, 1.0 - o.contraction);
    std::cout << "F_a\n" << matrix_text(f.active.deformation(), "  ") << "F_e\n" << matrix_text(E, "  ");
  }
  std::cout << fmt::format("I4 = |F_e a|^2 = {:.10g}   sign(a^T S a) = {:+g}   psi_fibre = {:.12g}\n", I4, sign, psi_fibre);
  std::cout << "P_fibre = dpsi_fibre/dF_e\n" << matrix_text(P_fibre, "  ");
  std::cout << fmt::format("eigenvalues of dP_fibre/dF_e   {:>16} {:>16}\n", "value", "projected(" + o.projection + ")");
  for (int i = 0; i < 3; ++i)
    std::cout << fmt::format("  {:<28} {:>16.9g} {:>16.9g}\n", labels[static_cast<std::size_t>(i)], es.values[static_cast<std::size_t>(i)],
                             project_eigenvalue(es.values[static_cast<std::size_t>(i)], projection));
  std::cout << fmt::format("  {:<28} {:>16} {:>16}\n", "cross-section (six)", 0, 0);
  if (!defined) {
    std::cout << fmt::format("psi = +inf: {} is undefined for J <= 0 (J = {:g})\n", M::name, E.determinant());
    return 0;
  }
  std::cout << fmt::format("psi = psi_material + psi_fibre = {:.12g} + {:.12g} = {:.12g}\n", m.psi(E), psi_fibre, m.psi(E) + psi_fibre);
  std::cout << "P = dpsi/dF\n" << matrix_text(f.active.pk1(m.pk1(E) + P_fibre), "  ");
  return 0;
}

int run_inspect(const MaterialOptions& o) {
  if (o.name.empty()) throw std::invalid_argument("give a material NAME (see --list), or --stability");
  if (o.F_text.empty() == o.stretch.empty())
    throw std::invalid_argument("give exactly one of --F \"f0 ... f8\" or --stretch sx sy sz");
  const auto projection = parse_projection(o.projection);
  if (!projection) throw std::invalid_argument(fmt::format("--projection must be none, clamp or abs, got '{}'", printable(o.projection)));
  Mat3 F;
  if (!o.F_text.empty()) {
    F = parse_F(o.F_text);
  } else {  // nan and inf were refused with the options (refuse_non_finite_numbers)
    F = Vec3(o.stretch[0], o.stretch[1], o.stretch[2]).asDiagonal();
  }
  check_F_range(F, o.F_text.empty());
  const Lame given = o.params.lame();
  const AnyMaterial material = make_material(o.name, given, o.params.reparametrize);

  return std::visit(
      [&](const auto& m) {
        using M = std::decay_t<decltype(m)>;
        const Lame used = m.params();
        if (const std::optional<FibreSetup> fibre = fibre_setup(o, used.mu)) return run_muscle(o, m, F, *fibre, *projection);
        const Svd3 svd = rotation_variant_svd(F);
        const bool defined = m.defined(F);
        Eigensystem9 es;
        if (defined) es = eigensystem(m, svd);
        const double J = F.determinant();
        if (o.json) {
          json j;
          j["material"] = std::string(M::name);
          j["formula"] = std::string(M::formula);
          j["mu"] = used.mu;
          j["lambda"] = used.lambda;
          j["nu"] = poisson_ratio(used);
          j["reparametrized"] = o.params.reparametrize;
          if (o.params.reparametrize) j["linear"] = {{"mu", given.mu}, {"lambda", given.lambda}};
          j["F"] = matrix_json(F);
          j["J"] = J;
          j["I_C"] = F.squaredNorm();
          j["sigma"] = {svd.sigma[0], svd.sigma[1], svd.sigma[2]};
          j["defined"] = defined;
          j["projection"] = o.projection;
          if (defined) {
            j["psi"] = m.psi(F);
            j["P"] = matrix_json(m.pk1(F));
            json eig = json::array();
            for (int i = 0; i < 9; ++i)
              eig.push_back({{"label", std::string(kEigenLabels[i])},
                             {"value", es.values[i]},
                             {"projected", project_eigenvalue(es.values[i], *projection)}});
            j["eigenvalues"] = eig;
          } else {
            j["psi"] = nullptr;
            j["reason"] = fmt::format("{} is undefined for J <= 0 (J = {:g})", M::name, J);
          }
          std::cout << j.dump(2) << "\n";
          return 0;
        }
        std::cout << fmt::format("material   {}: psi = {}\n", M::name, M::formula);
        std::cout << fmt::format("parameters {}{}\n", describe(used),
                                 o.params.reparametrize ? fmt::format("  (reparametrized from linear {})", describe(given)) : "");
        std::cout << "F\n" << matrix_text(F, "  ");
        std::cout << fmt::format("J = {:.10g}   I_C = {:.10g}   sigma = ({:.10g}, {:.10g}, {:.10g})\n", J,
                                 F.squaredNorm(), svd.sigma[0], svd.sigma[1], svd.sigma[2]);
        if (!defined) {
          std::cout << fmt::format("psi = +inf: {} is undefined for J <= 0 (J = {:g}); P and dP/dF do not exist here\n",
                                   M::name, J);
          return 0;
        }
        std::cout << fmt::format("psi = {:.12g}\n", m.psi(F));
        std::cout << "P = dpsi/dF\n" << matrix_text(m.pk1(F), "  ");
        std::cout << fmt::format("eigenvalues of dP/dF   {:>16} {:>16}\n", "value", "projected(" + o.projection + ")");
        for (int i = 0; i < 9; ++i)
          std::cout << fmt::format("  {:<20} {:>16.9g} {:>16.9g}\n", kEigenLabels[i], es.values[i],
                                   project_eigenvalue(es.values[i], *projection));
        return 0;
      },
      material);
}

std::string points_text(const StabilityRow& r) {
  if (r.critical_points.empty()) return "none";
  std::string out;
  for (const auto& c : r.critical_points)
    out += fmt::format("{}{} {:.4f}", out.empty() ? "" : ", ", c.minimum ? "min" : "max", c.s);
  return out;
}

int run_stability(const MaterialOptions& o) {
  const Lame p = o.params.lame();
  const StabilityReport rep = measure_stability(p, o.params.reparametrize, o.samples, o.seed);
  if (o.json) {
    json j;
    j["mu"] = p.mu;
    j["lambda"] = p.lambda;
    j["nu"] = poisson_ratio(p);
    j["reparametrize"] = o.params.reparametrize;
    j["samples"] = rep.samples;
    j["seed"] = o.seed;
    json rows = json::array();
    for (const auto& r : rep.rows) {
      json cps = json::array();
      for (const auto& c : r.critical_points) cps.push_back({{"s", c.s}, {"kind", c.minimum ? "min" : "max"}});
      auto num = [](double v) { return std::isfinite(v) ? json(v) : json(nullptr); };
      rows.push_back({{"energy", r.name},
                      {"reparametrized", r.parameters_reparametrized},
                      {"inversion", {{"ok", r.inversion_ok}, {"samples", r.inverted_samples},
                                     {"finite", r.inverted_finite}, {"fd_error", num(r.inverted_fd_error)}}},
                      {"reflection", {{"ok", r.reflection_ok}, {"max_change", num(r.reflection_change)}}},
                      {"rest", {{"ok", r.rest_ok}, {"norm_P", r.rest_stress}, {"psi", r.psi_at_rest}}},
                      {"collapse", {{"critical_points", cps}, {"psi_at_zero", num(r.psi_at_zero)},
                                    {"near_zero", r.near_zero}}}});
    }
    j["rows"] = rows;
    std::cout << j.dump(2) << "\n";
    return 0;
  }
  std::cout << fmt::format("Stability of every energy, measured: {}{}; {} sampled F with J <= 0 (seed {})\n\n",
                           describe(p), o.params.reparametrize ? ", reparametrized where possible" : ", used as given",
                           rep.samples, o.seed);
  std::cout << fmt::format("{:<23} {:<24} {:<16} {:<15} {}\n", "energy", "1 inverted F (J<=0)", "2 reflection",
                           "3 rest |P(I)|", "4 collapse F=sI: critical points in (0,1); F->0");
  for (const auto& r : rep.rows) {
    const std::string inv = r.inverted_finite == 0
                                ? fmt::format("no: undefined {}/{}", r.inverted_samples - r.inverted_finite, r.inverted_samples)
                                : fmt::format("{} {}/{} fd {:.0e}", r.inversion_ok ? "ok" : "NO", r.inverted_finite,
                                              r.inverted_samples, r.inverted_fd_error);
    const std::string refl = std::isnan(r.reflection_change)
                                 ? "n/a (undefined)"
                                 : fmt::format("{} {:.0e}", r.reflection_ok ? "ok" : "NO", r.reflection_change);
    const std::string rest = fmt::format("{} {:.1e}", r.rest_ok ? "ok" : "NO", r.rest_stress);
    std::cout << fmt::format("{:<23} {:<24} {:<16} {:<15} {}; {}\n",
                             r.name + (o.params.reparametrize && !r.parameters_reparametrized ? "*" : ""), inv, refl, rest,
                             points_text(r), r.near_zero);
  }
  std::cout << "\n1: psi, P and the clamped dP/dF finite at every sample, P matching finite differences of psi (<= 1e-6)\n"
               "2: largest relative change of psi, P, clamped dP/dF when the SVD puts the reflection on another sigma (<= 1e-9)\n"
               "3: rest stable when |P(I)| <= 1e-12 (mu + |lambda|)\n"
               "4: s where d psi(sI)/ds = 0 (max = barrier, min = resting point), and whether F = 0 traps (local min)\n";
  if (o.params.reparametrize) std::cout << "*: no Lame reparametrization exists; measured with the parameters as given\n";
  return 0;
}

}  // namespace

void add_material_command(CLI::App& app, int& exit_code) {
  auto opts = std::make_shared<MaterialOptions>();
  CLI::App* cmd = app.add_subcommand(
      "material",
      "Inspect an energy at one deformation gradient F: psi, P = dpsi/dF and the nine eigenvalues of dP/dF "
      "(twist, flip, scaling) before and after PSD projection; or measure the stability table of every energy.");
  cmd->add_option("name", opts->name, "Energy: " + material_name_list());
  add_parameter_options(cmd, opts->params);
  auto* Fopt = cmd->add_option("--F", opts->F_text, "Deformation gradient: 9 numbers, vec(F) column by column");
  auto* st = cmd->add_option("--stretch", opts->stretch, "Deformation gradient diag(sx, sy, sz)")->expected(3);
  Fopt->excludes(st);
  cmd->add_option("--projection", opts->projection, "PSD projection of dP/dF: none, clamp (default) or abs");
  auto* fib = cmd->add_option("--fibre", opts->fibre,
                              "A fibre direction a (3 numbers, normalised): adds a fibre energy along a to the material, a muscle")
                  ->expected(3);
  cmd->add_option("--fibre-model", opts->fibre_model, "Fibre energy: signed_arap (default: (k/2)(s - 1)^2, s the signed stretch) or quadratic ((k/8)(I4 - 1)^2)");
  cmd->add_option("--fibre-stiffness", opts->fibre_stiffness, "Fibre stiffness k (default: the material's mu)")
      ->check(finite_number(Sign::non_negative));
  cmd->add_option("--contraction", opts->contraction,
                  "Active strain: the fibre's rest length shortened to 1 - c, c in [0, 1) (default 0); the energies act on F F_a^-1")
      ->check(finite_number(Sign::non_negative));
  cmd->add_flag("--json", opts->json, "Machine-readable JSON output");
  cmd->add_flag("--list", opts->list, "List the energies and their formulas");
  auto* stability = cmd->add_flag("--stability", opts->stability,
                "Measure, for every energy, the paper's four stability properties (inversion, reflection, rest, "
                "collapse along F = sI)");
  // --stability measures every energy on its own sampled F: a given energy or F was silently ignored.
  stability->excludes(Fopt)->excludes(st)->excludes(fib);
  cmd->add_option("--samples", opts->samples, "Number of sampled F with J <= 0 for --stability (default 200)")
      ->check(CLI::Range(1, 1000000));
  cmd->add_option("--seed", opts->seed, "Seed of the samples for --stability (default 1)");
  cmd->callback([opts, &exit_code]() {
    const MaterialOptions& o = *opts;
    if (o.list) {
      for (auto n : material_names()) {
        std::visit([&](const auto& m) {
          using M = std::decay_t<decltype(m)>;
          std::cout << fmt::format("{:<24} {}{}\n", M::name, M::formula, M::inversion_safe ? "" : "   [undefined for J <= 0]");
        }, make_material(n, Lame{}, false));
      }
      exit_code = 0;
      return;
    }
    if (o.stability && !o.name.empty())
      throw std::invalid_argument(fmt::format("--stability measures every energy: drop the energy name '{}'",
                                              printable(o.name)));
    exit_code = o.stability ? run_stability(o) : run_inspect(o);
  });
}

}  // namespace snh::cli
