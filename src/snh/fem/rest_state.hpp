#pragma once
// Rest-state precomputation (docs/design.md): per element and quadrature point, the gradients of the
// shape functions with respect to rest coordinates and the volume weight, so that at any deformed
// state F = X_e G (X_e = 3 by N node positions) and ∫ψ dV = Σ_q w_q ψ(F_q).
#include <array>
#include <stdexcept>
#include <string>
#include <variant>
#include <vector>

#include <Eigen/Dense>

#include "snh/mesh/volume_mesh.hpp"

namespace snh {

/// Rest data of one element with N nodes and Q quadrature points.
template <int N, int Q>
struct ElementRest {
  static constexpr int nodes = N;
  static constexpr int points = Q;
  std::array<Eigen::Matrix<double, N, 3>, Q> G;  ///< row a: ∂N_a/∂X at point q
  std::array<double, Q> weight{};                ///< det(∂X/∂ξ) × Gauss weight; Σ_q weight = rest volume
};

using TetRest = ElementRest<4, 1>;  ///< linear tet, one point (exact)
using HexRest = ElementRest<8, 8>;  ///< trilinear hex, 2x2x2 Gauss points at ±1/√3 (weights 1)

/// Rest data for every cell of a mesh: a vector of TetRest or HexRest.
using RestState = std::variant<std::vector<TetRest>, std::vector<HexRest>>;

/// An element whose rest volume (at any quadrature point for hexes) is not positive; the message
/// names the element and its volume.
class DegenerateElement : public std::runtime_error {
 public:
  DegenerateElement(const std::string& what, Eigen::Index element) : std::runtime_error(what), element(element) {}
  Eigen::Index element;
};

/// Computes the rest state (general hexes: any trilinear shape, not only boxes).
/// Throws DegenerateElement for a non-positive rest volume or Jacobian determinant.
[[nodiscard]] RestState compute_rest_state(const VolumeMesh& mesh);

/// Rest volume of every cell (Σ_q weight).
[[nodiscard]] Eigen::VectorXd rest_volumes(const RestState& rest);

}  // namespace snh
