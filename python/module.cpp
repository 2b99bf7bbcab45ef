// The Python module `snh` (docs/python.md): NumPy arrays in and out over the C++ library, no logic of its
// own. Errors keep the library's one-line messages: bad input (parameters, meshes, scenes, shapes) raises
// ValueError, a solve that does not converge RuntimeError, a file that cannot be written OSError.
#include <cmath>

#include <fmt/format.h>

#include "common.hpp"
#include "snh/io/atomic_file.hpp"
#include "snh/io/mesh_file.hpp"
#include "snh/solve/memory_estimate.hpp"

namespace snh::py {

void value_error(const std::string& message) { throw pyb::value_error(message); }

Doubles real_array(const pyb::handle& obj, std::string_view what) {
  pyb::array a = pyb::array::ensure(obj);
  if (!a) value_error(fmt::format("{} must be an array of numbers", what));
  const char kind = a.dtype().kind();
  if (kind != 'f' && kind != 'i' && kind != 'u')
    value_error(fmt::format("{} must hold real numbers (float or integer), got dtype {}", what,
                            std::string(pyb::str(a.dtype()))));
  return Doubles::ensure(a);
}

std::string shape_text(const pyb::array& a) {
  std::string s = "(";
  for (pyb::ssize_t i = 0; i < a.ndim(); ++i) s += fmt::format("{}{}", i ? ", " : "", a.shape(i));
  return s + (a.ndim() == 1 ? ",)" : ")");
}

namespace {

std::string wanted_shape(std::initializer_list<pyb::ssize_t> shape) {
  std::string s = "(";
  int i = 0;
  for (pyb::ssize_t d : shape) s += fmt::format("{}{}", i++ ? ", " : "", d < 0 ? std::string("n") : std::to_string(d));
  return s + (shape.size() == 1 ? ",)" : ")");
}

/// The index of flat entry k of an array of this shape, "(i, j)".
std::string index_text(const pyb::array& a, pyb::ssize_t k) {
  std::string s;
  for (pyb::ssize_t d = a.ndim() - 1; d >= 0; --d) {
    s = fmt::format("{}{}", k % a.shape(d), s.empty() ? "" : ", " + s);
    k /= a.shape(d);
  }
  return "(" + s + ")";
}

void check_finite(const Doubles& a, std::string_view what) {
  const double* p = a.data();
  for (pyb::ssize_t k = 0; k < a.size(); ++k)
    if (!std::isfinite(p[k])) value_error(fmt::format("{} entry {} is not a finite number: {}", what, index_text(a, k), p[k]));
}

}  // namespace

Doubles real_array(const pyb::handle& obj, std::string_view what, std::initializer_list<pyb::ssize_t> shape) {
  Doubles a = real_array(obj, what);
  bool ok = a.ndim() == static_cast<pyb::ssize_t>(shape.size());
  pyb::ssize_t d = 0;
  for (pyb::ssize_t want : shape) {
    if (ok && want >= 0 && a.shape(d) != want) ok = false;
    ++d;
  }
  if (!ok) value_error(fmt::format("{} must have shape {}, got {}", what, wanted_shape(shape), shape_text(a)));
  check_finite(a, what);
  return a;
}

Mat3 Matrices::at(pyb::ssize_t k) const {
  // Row-major (i, j) in the array; Eigen's Mat3 is column-major.
  return Eigen::Map<const Eigen::Matrix<double, 3, 3, Eigen::RowMajor>>(data.data() + 9 * k);
}

/// The supported magnitudes of F's entries (snh material's --F): within them every energy's ψ, P and ∂P/∂F
/// stay finite for μ, |λ| ≤ 1e12.
constexpr double kMinEntry = 1e-20, kMaxEntry = 1e20;

Matrices matrices(const pyb::handle& obj, std::string_view what, bool entry_range) {
  Matrices out;
  out.data = real_array(obj, what);
  const Doubles& a = out.data;
  out.batch = a.ndim() == 3;
  if (!((a.ndim() == 2 && a.shape(0) == 3 && a.shape(1) == 3) || (a.ndim() == 3 && a.shape(1) == 3 && a.shape(2) == 3)))
    value_error(fmt::format("{} must have shape (3, 3) or (n, 3, 3), got {}", what, shape_text(a)));
  out.count = out.batch ? a.shape(0) : 1;
  check_finite(a, what);
  if (entry_range) {
    const double* p = a.data();
    for (pyb::ssize_t k = 0; k < a.size(); ++k) {
      const double f = std::abs(p[k]);
      if (f == 0.0 || (f >= kMinEntry && f <= kMaxEntry)) continue;
      value_error(fmt::format("{} entry {} = {:g} is outside the supported range (0 or |f| in [{:g}, {:g}])", what,
                              index_text(a, k), p[k], kMinEntry, kMaxEntry));
    }
  }
  return out;
}

PsdProjection projection(const std::string& name) {
  const auto p = parse_projection(name);
  if (!p) value_error(fmt::format("projection must be none, clamp or abs, got '{}'", name));
  return *p;
}

Doubles new_array(std::initializer_list<pyb::ssize_t> shape) { return Doubles(std::vector<pyb::ssize_t>(shape)); }

Doubles positions_array(const Eigen::VectorXd& x) {
  Doubles a = new_array({x.size() / 3, 3});
  std::copy(x.data(), x.data() + x.size(), a.mutable_data());
  return a;
}

Eigen::VectorXd positions_vector(const pyb::handle& obj, std::string_view what, Eigen::Index vertices) {
  const Doubles a = real_array(obj, what, {vertices, 3});
  return Eigen::Map<const Eigen::VectorXd>(a.data(), a.size());
}

}  // namespace snh::py

PYBIND11_MODULE(snh, m) {
  namespace pyb = pybind11;
  m.doc() = "snh: Stable Neo-Hookean flesh simulation (energies, eigensystems, meshes, simulations) with NumPy arrays";
  m.attr("__version__") = SNH_VERSION;
  // Library errors that are not std::invalid_argument (already ValueError) but mean bad input, or a file.
  pyb::register_exception_translator([](std::exception_ptr p) {
    try {
      if (p) std::rethrow_exception(p);
    } catch (const snh::MeshError& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const snh::OutputRefused& e) {
      PyErr_SetString(PyExc_ValueError, e.what());
    } catch (const snh::WriteError& e) {
      PyErr_SetString(PyExc_OSError, e.what());
    } catch (const snh::OutOfMemoryError& e) {
      PyErr_SetString(PyExc_MemoryError, e.what());
    }
  });
  snh::py::add_materials(m);
  snh::py::add_muscles(m);
  snh::py::add_meshes(m);
  snh::py::add_simulation(m);
}
