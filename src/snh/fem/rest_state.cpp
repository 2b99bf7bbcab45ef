#include "snh/fem/rest_state.hpp"

#include <cmath>

#include <fmt/format.h>

namespace snh {
namespace {

std::vector<TetRest> tet_rest(const VolumeMesh& mesh) {
  std::vector<TetRest> out(mesh.cell_count());
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c) {
    Eigen::Matrix3d Dm;
    const Eigen::Vector3d x0 = mesh.vertices.col(mesh.cells(0, c));
    for (int a = 0; a < 3; ++a) Dm.col(a) = mesh.vertices.col(mesh.cells(a + 1, c)) - x0;
    const double volume = Dm.determinant() / 6.0;
    if (!(volume > 0.0))
      throw DegenerateElement(fmt::format("tet {} has rest volume {:g} (must be > 0)", c, volume), c);
    const Eigen::Matrix3d Dinv = Dm.inverse();
    // F = Ds Dm⁻¹ = Σ_a x_a ∇N_aᵀ with ∇N_a = row a−1 of Dm⁻¹ (a = 1..3), ∇N_0 = −Σ of them.
    auto& G = out[c].G[0];
    G.bottomRows<3>() = Dinv;
    G.row(0) = -Dinv.colwise().sum();
    out[c].weight[0] = volume;
  }
  return out;
}

std::vector<HexRest> hex_rest(const VolumeMesh& mesh) {
  // Reference corner signs in the VolumeMesh order: c0 = (−,−,−), c1 = (+,−,−), c2 = (−,+,−), ...
  Eigen::Matrix<double, 8, 3> sign;
  for (int a = 0; a < 8; ++a) sign.row(a) << ((a & 1) ? 1 : -1), ((a & 2) ? 1 : -1), ((a & 4) ? 1 : -1);
  const double g = 1.0 / std::sqrt(3.0);
  std::vector<HexRest> out(mesh.cell_count());
  for (Eigen::Index c = 0; c < mesh.cell_count(); ++c) {
    Eigen::Matrix<double, 3, 8> X;
    for (int a = 0; a < 8; ++a) X.col(a) = mesh.vertices.col(mesh.cells(a, c));
    for (int q = 0; q < 8; ++q) {
      const Eigen::Vector3d xi = g * sign.row(q).transpose();  // Gauss point in the octant of corner q
      Eigen::Matrix<double, 8, 3> dN;  // ∂N_a/∂ξ, N_a = Π_d (1 + s_ad ξ_d)/8
      for (int a = 0; a < 8; ++a)
        for (int d = 0; d < 3; ++d) {
          double v = sign(a, d) / 8.0;
          for (int e = 0; e < 3; ++e)
            if (e != d) v *= 1.0 + sign(a, e) * xi[e];
          dN(a, d) = v;
        }
      const Eigen::Matrix3d J0 = X * dN;  // ∂X/∂ξ
      const double det = J0.determinant();
      if (!(det > 0.0))
        throw DegenerateElement(
            fmt::format("hex {} has a non-positive Jacobian determinant {:g} at Gauss point {}", c, det, q), c);
      out[c].G[q] = dN * J0.inverse();  // ∂N/∂X = ∂N/∂ξ (∂X/∂ξ)⁻¹
      out[c].weight[q] = det;
    }
  }
  return out;
}

}  // namespace

RestState compute_rest_state(const VolumeMesh& mesh) {
  if (mesh.type == CellType::tet4) return tet_rest(mesh);
  return hex_rest(mesh);
}

Eigen::VectorXd rest_volumes(const RestState& rest) {
  return std::visit(
      [](const auto& elems) {
        Eigen::VectorXd v(elems.size());
        for (std::size_t e = 0; e < elems.size(); ++e) {
          double s = 0.0;
          for (double w : elems[e].weight) s += w;
          v[static_cast<Eigen::Index>(e)] = s;
        }
        return v;
      },
      rest);
}

}  // namespace snh
