#pragma once
// What the binding files share: NumPy arrays in and out with their checks (shape, dtype, finite values),
// each failure one line raised as ValueError; and the functions that add each part to the module.
#include <string>
#include <string_view>

#include <Eigen/Core>
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include "snh/material/psd_projection.hpp"
#include "snh/material/registry.hpp"
#include "snh/math/types.hpp"
#include "snh/mesh/volume_mesh.hpp"

namespace snh::py {

namespace pyb = pybind11;

/// The caster of a bound class T that refuses an instance whose C++ object was never made: one that
/// T.__new__(T) gave without __init__ (pybind11 would hand the methods uninitialized memory). Raises
/// TypeError naming the class and how to make one. Each binding file specializes pybind11's caster for its
/// class with it (type_caster<PyMaterial>, type_caster<PySimulation>), right after the class, before any use.
template <class T>
struct checked_caster : pyb::detail::type_caster_base<T> {
  bool load(pyb::handle src, bool convert) {
    if (src && pyb::detail::get_type_info(typeid(T)) && pyb::isinstance<T>(src)) {
      auto* inst = reinterpret_cast<pyb::detail::instance*>(src.ptr());
      if (!inst->get_value_and_holder().holder_constructed())
        throw pyb::type_error("snh." + std::string(pyb::str(pyb::type::handle_of(src).attr("__qualname__"))) +
                              ": this object was made by __new__ without __init__ (make one with snh.material(...) "
                              "or snh.Simulation(...))");
    }
    return pyb::detail::type_caster_base<T>::load(src, convert);
  }
};

/// A C-contiguous float64 array.
using Doubles = pyb::array_t<double, pyb::array::c_style>;

/// Raises ValueError with this message.
[[noreturn]] void value_error(const std::string& message);

/// `obj` as float64 (C order): any array-like of real numbers (float or integer dtype), copied only where
/// needed. ValueError naming `what` for anything else (complex, strings, objects, booleans).
[[nodiscard]] Doubles real_array(const pyb::handle& obj, std::string_view what);

/// The same, with an exact shape (-1: any length along that axis), and every entry finite.
[[nodiscard]] Doubles real_array(const pyb::handle& obj, std::string_view what, std::initializer_list<pyb::ssize_t> shape);

/// "(3, 3)" or "(n, 3)".
[[nodiscard]] std::string shape_text(const pyb::array& a);

/// A 3x3 matrix or a batch (n, 3, 3) of them, checked: real, finite, and (when `entry_range`) every entry 0
/// or of magnitude in [1e-20, 1e20] (snh material's --F range). `batch` tells which of the two it was.
struct Matrices {
  Doubles data;
  pyb::ssize_t count = 0;
  bool batch = false;
  [[nodiscard]] Mat3 at(pyb::ssize_t k) const;
};
[[nodiscard]] Matrices matrices(const pyb::handle& obj, std::string_view what, bool entry_range);

/// Runs body(k) for every matrix, in parallel over a batch, without the GIL.
template <class Body>
void for_each(const Matrices& F, Body&& body) {
  pyb::gil_scoped_release release;
  const auto n = static_cast<long>(F.count);
#pragma omp parallel for schedule(static) if (n > 64)
  for (long k = 0; k < n; ++k) body(k);
}

/// (n, rest...) for a batch, (rest...) for one matrix.
inline Doubles output(const Matrices& F, std::initializer_list<pyb::ssize_t> rest) {
  std::vector<pyb::ssize_t> shape;
  if (F.batch) shape.push_back(F.count);
  shape.insert(shape.end(), rest);
  return Doubles(shape);
}

/// A 3x3 (or 9x9) Eigen matrix into row-major array storage.
template <class M>
void store(const M& A, double* out) {
  Eigen::Map<Eigen::Matrix<double, M::RowsAtCompileTime, M::ColsAtCompileTime, Eigen::RowMajor>> target(out);
  target = A;
}

/// parse_projection, or ValueError.
[[nodiscard]] PsdProjection projection(const std::string& name);

/// A new float64 array of this shape.
[[nodiscard]] Doubles new_array(std::initializer_list<pyb::ssize_t> shape);

/// 3 #V positions as an (n, 3) array (the same memory order), and back (checked: shape, finite).
[[nodiscard]] Doubles positions_array(const Eigen::VectorXd& x);
[[nodiscard]] Eigen::VectorXd positions_vector(const pyb::handle& obj, std::string_view what, Eigen::Index vertices);

/// A mesh as (vertices (n, 3), cells (m, 4 or 8) int32, kind), and a mesh from such arrays (checked: shapes,
/// dtypes, finite coordinates, indices in range).
[[nodiscard]] pyb::tuple mesh_tuple(const VolumeMesh& mesh);
[[nodiscard]] VolumeMesh mesh_of(const pyb::handle& vertices, const pyb::handle& cells);

/// The energy inside an snh.Material.
[[nodiscard]] const AnyMaterial& any_material(const pyb::handle& obj);

void add_materials(pyb::module_& m);
void add_muscles(pyb::module_& m);
void add_meshes(pyb::module_& m);
void add_simulation(pyb::module_& m);

}  // namespace snh::py
