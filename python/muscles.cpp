// snh.fibre, snh.Fibre (a fibre energy: ψ, P, ∂P/∂F, its eigensystem), snh.active_strain, snh.ActiveStrain,
// and snh.Muscle (a material with fibres and an active strain: the energy of a muscle cell), docs/math.md §14.
#include <optional>

#include <fmt/format.h>
#include <pybind11/stl.h>

#include "common.hpp"
#include "snh/material/eigensystem.hpp"
#include "snh/material/fibre.hpp"

namespace snh::py {
namespace {

Vec3 direction_of(const pyb::handle& obj) {
  const Doubles d = real_array(obj, "direction", {3});
  const Vec3 a(d.data()[0], d.data()[1], d.data()[2]);
  if (!(a.norm() > 0.0)) value_error("direction: a fibre direction must not be zero");
  return a.normalized();
}

FibreModel model_of(const std::string& name) {
  if (name == "signed_arap") return FibreModel::signed_arap;
  if (name == "quadratic") return FibreModel::quadratic;
  value_error(fmt::format("model: expected signed_arap or quadratic, got '{}'", name));
}

/// ψ_f(F; a) with its direction.
struct PyFibre {
  FibreEnergy energy;
  Vec3 a = Vec3::UnitX();
};

/// A muscle cell's energy: ψ(F A) + ψ_f(F A; a), A the active strain's inverse.
struct PyMuscle {
  AnyMaterial material;
  PyFibre fibre;
  ActiveStrain active;
  [[nodiscard]] double psi(const Mat3& F) const {
    const Mat3 Fe = active.elastic(F);
    return std::visit([&](const auto& m) { return m.psi(Fe); }, material) + fibre.energy.psi(Fe, fibre.a);
  }
  [[nodiscard]] Mat3 pk1(const Mat3& F) const {
    const Mat3 Fe = active.elastic(F);
    return active.pk1(std::visit([&](const auto& m) { return Mat3(m.pk1(Fe)); }, material) + fibre.energy.pk1(Fe, fibre.a));
  }
  /// Each part projected on its own before the pull-back (as the simulation assembles it).
  [[nodiscard]] Mat9 hessian(const Mat3& F, PsdProjection p) const {
    const Mat3 Fe = active.elastic(F);
    const Mat9 H = std::visit([&](const auto& m) { return Mat9(projected_hessian(m, Fe, p)); }, material) +
                   fibre.energy.projected_hessian(Fe, fibre.a, p);
    return active.hessian(H);
  }
};

}  // namespace
}  // namespace snh::py
namespace pybind11::detail {
template <>
struct type_caster<snh::py::PyFibre> : snh::py::checked_caster<snh::py::PyFibre> {};
template <>
struct type_caster<snh::ActiveStrain> : snh::py::checked_caster<snh::ActiveStrain> {};
template <>
struct type_caster<snh::py::PyMuscle> : snh::py::checked_caster<snh::py::PyMuscle> {};
}  // namespace pybind11::detail
namespace snh::py {
namespace {

/// ψ, P and the Hessian of an energy E (PyFibre or PyMuscle) over one F or a batch.
template <class E, class Psi, class P, class H>
void add_energy_methods(pyb::class_<E>& c, Psi psi, P pk1, H hessian) {
  using namespace pyb::literals;
  c.def("psi", [psi](const E& e, const pyb::handle& obj) -> pyb::object {
    const Matrices F = matrices(obj, "F", true);
    Doubles out = output(F, {});
    double* o = out.mutable_data();
    for_each(F, [&](long k) { o[k] = psi(e, F.at(k)); });
    if (F.batch) return out;
    return pyb::float_(o[0]);
  }, "F"_a, "psi(F): one 3x3 F gives a float, a batch (n, 3, 3) an array (n,).");
  c.def("pk1", [pk1](const E& e, const pyb::handle& obj) {
    const Matrices F = matrices(obj, "F", true);
    Doubles out = output(F, {3, 3});
    double* o = out.mutable_data();
    for_each(F, [&](long k) { store(Mat3(pk1(e, F.at(k))), o + 9 * k); });
    return out;
  }, "F"_a, "P = dpsi/dF: (3, 3) or (n, 3, 3).");
  c.def("hessian", [hessian](const E& e, const pyb::handle& obj, const std::string& proj) {
    const PsdProjection p = projection(proj);
    const Matrices F = matrices(obj, "F", true);
    Doubles out = output(F, {9, 9});
    double* o = out.mutable_data();
    for_each(F, [&](long k) { store(Mat9(hessian(e, F.at(k), p)), o + 81 * k); });
    return out;
  }, "F"_a, "projection"_a = "none",
        "dP/dF as a 9x9 matrix over vec(F) column by column: (9, 9) or (n, 9, 9); projection none, clamp or abs.");
}

}  // namespace

void add_muscles(pyb::module_& m) {
  using namespace pyb::literals;
  pyb::class_<PyFibre> fibre(m, "Fibre", "A fibre energy psi(F; a) along a unit rest direction a (made by snh.fibre).");
  fibre.def_property_readonly("direction", [](const PyFibre& f) { return std::vector<double>{f.a[0], f.a[1], f.a[2]}; })
      .def_property_readonly("model", [](const PyFibre& f) { return std::string(to_string(f.energy.model)); })
      .def_property_readonly("stiffness", [](const PyFibre& f) { return f.energy.stiffness; })
      .def("eigensystem", [](const PyFibre& f, const pyb::handle& obj, const std::string& proj) {
        const PsdProjection p = projection(proj);
        const Matrices F = matrices(obj, "F", true);
        Doubles values = output(F, {9}), projected = output(F, {9}), vectors = output(F, {9, 9});
        double *v = values.mutable_data(), *pv = projected.mutable_data(), *q = vectors.mutable_data();
        for_each(F, [&](long k) {
          const Eigensystem9 es = f.energy.eigensystem(F.at(k), f.a);
          for (int i = 0; i < 9; ++i) v[9 * k + i] = es.values[i], pv[9 * k + i] = project_eigenvalue(es.values[i], p);
          store(es.vectors, q + 81 * k);
        });
        pyb::dict d;
        d["values"] = values;
        d["projected"] = projected;
        d["vectors"] = vectors;
        return d;
      }, "F"_a, "projection"_a = "clamp",
           "The closed-form eigensystem of dP/dF: values (9,) or (n, 9) (values[0] on a (x) q, values[1..2] on a (x) q-perp, "
           "the rest 0), projected, and vectors (9, 9) or (n, 9, 9), column c the eigenvector of value c as vec(matrix).")
      .def("__repr__", [](const PyFibre& f) {
        return fmt::format("snh.fibre([{:g}, {:g}, {:g}], model='{}', stiffness={:g})", f.a[0], f.a[1], f.a[2], to_string(f.energy.model),
                           f.energy.stiffness);
      });
  add_energy_methods(
      fibre, [](const PyFibre& f, const Mat3& F) { return f.energy.psi(F, f.a); },
      [](const PyFibre& f, const Mat3& F) { return f.energy.pk1(F, f.a); },
      [](const PyFibre& f, const Mat3& F, PsdProjection p) { return f.energy.projected_hessian(F, f.a, p); });
  m.def("fibre",
        [](const pyb::handle& direction, const std::string& model, double stiffness) {
          if (!std::isfinite(stiffness) || stiffness < 0.0) value_error(fmt::format("stiffness: must be finite and >= 0, got {:g}", stiffness));
          PyFibre f;
          f.a = direction_of(direction);
          f.energy.model = model_of(model);
          f.energy.stiffness = stiffness;
          return f;
        },
        "direction"_a, pyb::kw_only(), "model"_a = "signed_arap", "stiffness"_a = 1.0,
        "A fibre energy along `direction` (normalised): model signed_arap (k/2 (s - 1)^2, s the signed stretch) or "
        "quadratic (k/8 (I4 - 1)^2), stiffness k >= 0 (docs/math.md section 14.1).");

  pyb::class_<ActiveStrain>(m, "ActiveStrain", "A muscle's active strain F_a along its fibres (made by snh.active_strain).")
      .def_property_readonly("alpha", [](const ActiveStrain& s) { return s.alpha; })
      .def_property_readonly("deformation", [](const ActiveStrain& s) {
        Doubles out = new_array({3, 3});
        store(s.deformation(), out.mutable_data());
        return out;
      }, "F_a (3, 3): 1 - alpha along the fibre, (1 - alpha)^(-1/2) across; det 1.")
      .def_property_readonly("inverse", [](const ActiveStrain& s) {
        Doubles out = new_array({3, 3});
        store(s.inverse, out.mutable_data());
        return out;
      }, "A = F_a^-1 (3, 3): a muscle's energies act on F A.");
  m.def("active_strain",
        [](const pyb::handle& direction, double alpha) {
          try {
            return ActiveStrain::along(direction_of(direction), alpha);
          } catch (const std::invalid_argument& e) {
            value_error(e.what());
          }
        },
        "direction"_a, "alpha"_a,
        "The active strain of fibres along `direction` shortened by alpha = contraction x activation, in [0, 1) "
        "(docs/math.md section 14.2).");

  pyb::class_<PyMuscle> muscle(m, "Muscle",
                               "A muscle cell's energy psi(F A) + psi_f(F A; a): a material, a fibre and an active strain (snh.muscle).");
  muscle.def_property_readonly("alpha", [](const PyMuscle& s) { return s.active.alpha; });
  add_energy_methods(
      muscle, [](const PyMuscle& s, const Mat3& F) { return s.psi(F); }, [](const PyMuscle& s, const Mat3& F) { return s.pk1(F); },
      [](const PyMuscle& s, const Mat3& F, PsdProjection p) { return s.hessian(F, p); });
  m.def("muscle",
        [](const pyb::handle& material, const PyFibre& fibre, double alpha) {
          PyMuscle s{any_material(material), fibre, {}};
          try {
            s.active = ActiveStrain::along(fibre.a, alpha);
          } catch (const std::invalid_argument& e) {
            value_error(e.what());
          }
          return s;
        },
        "material"_a, "fibre"_a, pyb::kw_only(), "alpha"_a = 0.0,
        "The energy of a muscle cell as the simulation evaluates it: `material` (snh.material) and `fibre` (snh.fibre) "
        "acting on the elastic part F A of F, A the inverse of the active strain along the fibre for alpha "
        "(docs/math.md section 14.3); its hessian projects each part before the pull-back, as the simulation does.");
}

}  // namespace snh::py
