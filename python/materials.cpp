// snh.material, snh.Material (ψ, P, ∂P/∂F, its eigensystem; one F or a batch, evaluated in parallel),
// snh.svd, snh.stability_table, snh.material_names.
#include <cmath>
#include <optional>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "common.hpp"
#include "snh/material/registry.hpp"
#include "snh/material/stability.hpp"
#include "snh/math/svd.hpp"

namespace snh::py {
namespace {

/// Lamé parameters from μ/λ (defaults 1 and 10, as snh material) or E/ν: the checks of the command line's
/// parameter options (apps/snh/parameter_options.hpp), with the keywords' names.
Lame lame_of(std::optional<double> mu, std::optional<double> lam, std::optional<double> youngs,
             std::optional<double> poisson) {
  if (youngs || poisson) {
    if (mu || lam) throw ParameterError("give mu and lam, or youngs and poisson, not both");
    if (!youngs || !poisson) throw ParameterError("youngs and poisson go together");
    return lame_from_youngs(*youngs, *poisson);
  }
  const Lame p{mu.value_or(1.0), lam.value_or(10.0)};
  validate(p);
  return p;
}

/// An energy with its parameters: AnyMaterial and what it was made from.
struct PyMaterial {
  AnyMaterial m;
  Lame given;
  bool reparametrize = false;
  template <class F>
  decltype(auto) visit(F&& f) const { return std::visit(std::forward<F>(f), m); }
};

}  // namespace
}  // namespace snh::py
namespace pybind11::detail {
template <>
struct type_caster<snh::py::PyMaterial> : snh::py::checked_caster<snh::py::PyMaterial> {};
}  // namespace pybind11::detail
namespace snh::py {
namespace {

pyb::object scalar_or_array(const Matrices& F, Doubles a) {
  if (F.batch) return a;
  return pyb::float_(a.data()[0]);
}

pyb::object psi(const PyMaterial& mat, const pyb::handle& obj) {
  const Matrices F = matrices(obj, "F", true);
  Doubles out = output(F, {});
  double* o = out.mutable_data();
  mat.visit([&](const auto& e) { for_each(F, [&](long k) { o[k] = e.psi(F.at(k)); }); });
  return scalar_or_array(F, std::move(out));
}

Doubles pk1(const PyMaterial& mat, const pyb::handle& obj) {
  const Matrices F = matrices(obj, "F", true);
  Doubles out = output(F, {3, 3});
  double* o = out.mutable_data();
  mat.visit([&](const auto& e) { for_each(F, [&](long k) { store(Mat3(e.pk1(F.at(k))), o + 9 * k); }); });
  return out;
}

Doubles hessian(const PyMaterial& mat, const pyb::handle& obj, const std::string& proj) {
  const PsdProjection p = projection(proj);
  const Matrices F = matrices(obj, "F", true);
  Doubles out = output(F, {9, 9});
  double* o = out.mutable_data();
  mat.visit([&](const auto& e) { for_each(F, [&](long k) { store(Mat9(projected_hessian(e, F.at(k), p)), o + 81 * k); }); });
  return out;
}

pyb::object defined(const PyMaterial& mat, const pyb::handle& obj) {
  const Matrices F = matrices(obj, "F", true);
  pyb::array_t<bool> out(F.batch ? std::vector<pyb::ssize_t>{F.count} : std::vector<pyb::ssize_t>{});
  bool* o = out.mutable_data();
  mat.visit([&](const auto& e) { for_each(F, [&](long k) { o[k] = e.defined(F.at(k)); }); });
  if (F.batch) return out;
  return pyb::bool_(o[0]);
}

pyb::dict eigensystem(const PyMaterial& mat, const pyb::handle& obj, const std::string& proj) {
  const PsdProjection p = projection(proj);
  const Matrices F = matrices(obj, "F", true);
  Doubles values = output(F, {9}), projected = output(F, {9}), vectors = output(F, {9, 9});
  double *v = values.mutable_data(), *pv = projected.mutable_data(), *q = vectors.mutable_data();
  std::vector<std::uint8_t> ok(static_cast<std::size_t>(F.count), 1);
  mat.visit([&](const auto& e) {
    for_each(F, [&](long k) {
      const Mat3 Fk = F.at(k);
      if (!e.defined(Fk)) {
        ok[static_cast<std::size_t>(k)] = 0;
        return;
      }
      const Eigensystem9 es = snh::eigensystem(e, rotation_variant_svd(Fk));
      for (int i = 0; i < 9; ++i) {
        v[9 * k + i] = es.values[i];
        pv[9 * k + i] = project_eigenvalue(es.values[i], p);
      }
      store(es.vectors, q + 81 * k);
    });
  });
  for (pyb::ssize_t k = 0; k < F.count; ++k)
    if (!ok[static_cast<std::size_t>(k)]) {
      const double J = F.at(k).determinant();
      value_error(fmt::format("{} is undefined for J <= 0 (J = {:g}){}: dP/dF has no eigensystem there", name_of(mat.m), J,
                              F.batch ? fmt::format(" at F[{}]", k) : ""));
    }
  pyb::list labels;
  for (auto l : kEigenLabels) labels.append(std::string(l));
  pyb::dict d;
  d["labels"] = labels;
  d["values"] = values;
  d["projected"] = projected;
  d["vectors"] = vectors;
  return d;
}

pyb::tuple svd(const pyb::handle& obj) {
  const Matrices F = matrices(obj, "F", false);
  Doubles U = output(F, {3, 3}), S = output(F, {3}), V = output(F, {3, 3});
  double *u = U.mutable_data(), *s = S.mutable_data(), *w = V.mutable_data();
  for_each(F, [&](long k) {
    const Svd3 d = rotation_variant_svd(F.at(k));
    store(d.U, u + 9 * k);
    store(d.V, w + 9 * k);
    for (int i = 0; i < 3; ++i) s[3 * k + i] = d.sigma[i];
  });
  return pyb::make_tuple(U, S, V);
}

pyb::object finite_or_none(double v) { return std::isfinite(v) ? pyb::object(pyb::float_(v)) : pyb::object(pyb::none()); }

/// The rows of snh material --stability --json, with the same keys.
pyb::list stability_table(std::optional<double> mu, std::optional<double> lam, std::optional<double> youngs,
                          std::optional<double> poisson, bool reparametrize, int samples, unsigned seed) {
  if (samples < 1 || samples > 1000000) value_error(fmt::format("samples must be from 1 to 1000000, got {}", samples));
  const Lame p = lame_of(mu, lam, youngs, poisson);
  StabilityReport rep;
  {
    pyb::gil_scoped_release release;
    rep = measure_stability(p, reparametrize, samples, seed);
  }
  pyb::list rows;
  for (const StabilityRow& r : rep.rows) {
    pyb::list cps;
    for (const CriticalPoint& c : r.critical_points) {
      pyb::dict cp;
      cp["s"] = c.s;
      cp["kind"] = c.minimum ? "min" : "max";
      cps.append(cp);
    }
    pyb::dict inv, refl, rest, collapse, row;
    inv["ok"] = r.inversion_ok;
    inv["samples"] = r.inverted_samples;
    inv["finite"] = r.inverted_finite;
    inv["fd_error"] = finite_or_none(r.inverted_fd_error);
    refl["ok"] = r.reflection_ok;
    refl["max_change"] = finite_or_none(r.reflection_change);
    rest["ok"] = r.rest_ok;
    rest["norm_P"] = r.rest_stress;
    rest["psi"] = r.psi_at_rest;
    collapse["critical_points"] = cps;
    collapse["psi_at_zero"] = finite_or_none(r.psi_at_zero);
    collapse["near_zero"] = r.near_zero;
    row["energy"] = r.name;
    row["reparametrized"] = r.parameters_reparametrized;
    row["inversion"] = inv;
    row["reflection"] = refl;
    row["rest"] = rest;
    row["collapse"] = collapse;
    rows.append(row);
  }
  return rows;
}

}  // namespace

/// The AnyMaterial inside a Python snh.Material (simulation.cpp).
const AnyMaterial& any_material(const pyb::handle& obj) {
  if (!pyb::isinstance<PyMaterial>(obj))
    throw pyb::type_error(fmt::format("material must be an snh.Material (made by snh.material(...)), got {}",
                                      std::string(pyb::str(obj.get_type().attr("__name__")))));
  return obj.cast<const PyMaterial&>().m;
}

void add_materials(pyb::module_& m) {
  using namespace pyb::literals;
  m.def("material_names", [] {
    std::vector<std::string> names;
    for (auto n : material_names()) names.emplace_back(n);
    return names;
  }, "The energies snh.material accepts, in the registry's order.");

  pyb::class_<PyMaterial>(m, "Material", "An energy density with its parameters (made by snh.material).")
      .def_property_readonly("name", [](const PyMaterial& p) { return std::string(name_of(p.m)); })
      .def_property_readonly("formula", [](const PyMaterial& p) {
        return p.visit([](const auto& e) { return std::string(std::decay_t<decltype(e)>::formula); });
      })
      .def_property_readonly("inversion_safe", [](const PyMaterial& p) {
        return p.visit([](const auto& e) { return std::decay_t<decltype(e)>::inversion_safe; });
      }, "False where psi is undefined for J <= 0 (log J or J^(-2/3)).")
      .def_property_readonly("mu", [](const PyMaterial& p) { return p.visit([](const auto& e) { return e.params().mu; }); },
                             "Lame mu as the energy uses it (after reparametrization).")
      .def_property_readonly("lam", [](const PyMaterial& p) { return p.visit([](const auto& e) { return e.params().lambda; }); },
                             "Lame lambda as the energy uses it (after reparametrization).")
      .def_property_readonly("nu", [](const PyMaterial& p) { return poisson_ratio(p.visit([](const auto& e) { return e.params(); })); })
      .def_property_readonly("youngs", [](const PyMaterial& p) { return youngs_modulus(p.visit([](const auto& e) { return e.params(); })); })
      .def_property_readonly("given", [](const PyMaterial& p) { return pyb::make_tuple(p.given.mu, p.given.lambda); },
                             "(mu, lam) as given (before reparametrization).")
      .def_property_readonly("reparametrized", [](const PyMaterial& p) { return p.reparametrize; })
      .def("psi", &psi, "F"_a, "psi(F): one 3x3 F gives a float, a batch (n, 3, 3) an array (n,); +inf where undefined.")
      .def("pk1", &pk1, "F"_a, "P = dpsi/dF: (3, 3) or (n, 3, 3); zero where undefined.")
      .def("hessian", &hessian, "F"_a, "projection"_a = "none",
           "dP/dF as a 9x9 matrix over vec(F) column by column (index i + 3 j for F[i, j]): (9, 9) or (n, 9, 9); "
           "projection none (the true Hessian), clamp or abs; zero where undefined.")
      .def("eigensystem", &eigensystem, "F"_a, "projection"_a = "clamp",
           "The nine eigenvalues of dP/dF and their eigenvectors: a dict with labels (twist_0..2, flip_0..2, "
           "scaling_0..2), values (9,) or (n, 9), projected (the values after the projection) and vectors "
           "(9, 9) or (n, 9, 9), column c the eigenvector of value c as vec(matrix), column by column. ValueError where undefined.")
      .def("defined", &defined, "F"_a, "Whether F is in the energy's domain: bool, or a bool array (n,).")
      .def("__repr__", [](const PyMaterial& p) {
        return fmt::format("snh.material('{}', mu={:g}, lam={:g})", name_of(p.m), p.visit([](const auto& e) { return e.params().mu; }),
                           p.visit([](const auto& e) { return e.params().lambda; }));
      });

  m.def("material",
        [](const std::string& name, std::optional<double> mu, std::optional<double> lam, std::optional<double> youngs,
           std::optional<double> poisson, bool reparametrize) {
          const Lame given = lame_of(mu, lam, youngs, poisson);
          return PyMaterial{make_material(name, given, reparametrize), given, reparametrize};
        },
        "name"_a, pyb::kw_only(), "mu"_a = pyb::none(), "lam"_a = pyb::none(), "youngs"_a = pyb::none(),
        "poisson"_a = pyb::none(), "reparametrize"_a = false,
        "The energy `name` (snh.material_names()) with Lame mu, lam (defaults 1 and 10) or Young's modulus and Poisson's "
        "ratio; reparametrize=True takes them as linear-elastic and maps them (docs/math.md section 2). The ranges of snh "
        "material: mu in [1e-12, 1e12], lam 0 or |lam| in [1e-12, 1e12], -1 < nu < 0.5; else ValueError.");

  m.def("svd", &svd, "F"_a,
        "The rotation-variant SVD: (U, sigma, V) with F = U diag(sigma) V^T, det U = det V = +1, sigma descending in "
        "magnitude, a reflection carried by sigma[2] < 0. One F or a batch (n, 3, 3).");

  m.def("stability_table", &stability_table, pyb::kw_only(), "mu"_a = pyb::none(), "lam"_a = pyb::none(),
        "youngs"_a = pyb::none(), "poisson"_a = pyb::none(), "reparametrize"_a = false, "samples"_a = 200, "seed"_a = 1u,
        "The paper's four stability properties measured for every energy (snh material --stability --json): a list of "
        "dicts with the same keys.");
}

}  // namespace snh::py
