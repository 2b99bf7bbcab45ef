#include "snh/fem/embedded_points.hpp"

#include <algorithm>
#include <stdexcept>

#include <fmt/format.h>

namespace snh {

EmbeddedPoints::EmbeddedPoints(Eigen::MatrixXi vertex, Eigen::MatrixXd weight, const std::string& who,
                               Eigen::Index volume_vertices)
    : vertex_(std::move(vertex)), weight_(std::move(weight)) {
  if (vertex_.rows() != weight_.rows() || vertex_.cols() != weight_.cols() || (vertex_.rows() < 1 && vertex_.cols() > 0))
    throw std::invalid_argument(fmt::format("{}: vertex ids ({} by {}) and weights ({} by {}) differ in shape", who,
                                            vertex_.rows(), vertex_.cols(), weight_.rows(), weight_.cols()));
  if (!weight_.allFinite()) throw std::invalid_argument(fmt::format("{}: the weights are not all finite", who));
  check_vertices(volume_vertices, who);
}

void EmbeddedPoints::check_vertices(Eigen::Index volume_vertices, const std::string& who) const {
  for (Eigen::Index i = 0; i < vertex_.size(); ++i) {
    const int v = vertex_.data()[i];
    if (v < 0 || (volume_vertices >= 0 && v >= volume_vertices))
      throw std::invalid_argument(volume_vertices >= 0
                                      ? fmt::format("{}: point {} has volume vertex id {} outside [0, {})", who,
                                                    i / vertex_.rows(), v, volume_vertices)
                                      : fmt::format("{}: point {} has a negative vertex id {}", who, i / vertex_.rows(), v));
  }
}

EmbeddedPoints EmbeddedPoints::plain(const std::vector<int>& vertices, const std::string& who) {
  const auto n = static_cast<Eigen::Index>(vertices.size());
  return {Eigen::Map<const Eigen::RowVectorXi>(vertices.data(), n), Eigen::MatrixXd::Ones(1, n), who, -1};
}

EmbeddedPoints EmbeddedPoints::every(Eigen::Index n) {
  EmbeddedPoints out;
  out.vertex_ = Eigen::RowVectorXi::LinSpaced(n, 0, static_cast<int>(n) - 1);
  out.weight_ = Eigen::MatrixXd::Ones(1, n);
  return out;
}

bool EmbeddedPoints::is_plain() const { return arity() == 1 && (weight_.array() == 1.0).all(); }

EmbeddedPoints EmbeddedPoints::select(const std::vector<int>& ids) const {
  EmbeddedPoints out;
  out.vertex_.resize(vertex_.rows(), static_cast<Eigen::Index>(ids.size()));
  out.weight_.resize(weight_.rows(), out.vertex_.cols());
  for (std::size_t i = 0; i < ids.size(); ++i) {
    out.vertex_.col(static_cast<Eigen::Index>(i)) = vertex_.col(ids[i]);
    out.weight_.col(static_cast<Eigen::Index>(i)) = weight_.col(ids[i]);
  }
  return out;
}

Vec3 EmbeddedPoints::point(const Eigen::VectorXd& x, Eigen::Index i) const {
  // w₀ x₀ first (not 0 + w₀ x₀): one weight 1 gives the vertex's coordinates bit for bit, signed zeros included.
  Vec3 p;
  for (Eigen::Index k = 0; k < vertex_.rows(); ++k) {
    const int v = vertex_(k, i);
    if (3 * static_cast<Eigen::Index>(v) + 3 > x.size())
      throw std::logic_error(fmt::format("embedded point {}: vertex {} is beyond the {} DOFs given", i, v, x.size()));
    if (k == 0) p = weight_(k, i) * x.segment<3>(3 * v);
    else p += weight_(k, i) * x.segment<3>(3 * v);
  }
  return p;
}

Eigen::Matrix3Xd EmbeddedPoints::points(const Eigen::VectorXd& x) const {
  Eigen::Matrix3Xd P(3, size());
  for (Eigen::Index i = 0; i < size(); ++i) P.col(i) = point(x, i);
  return P;
}

void EmbeddedPoints::volume_vertices(const std::array<int, 4>& ids, int count, std::vector<int>& out) const {
  out.clear();
  for (int i = 0; i < count; ++i)
    if (const int p = ids[static_cast<std::size_t>(i)]; p >= 0)
      for (Eigen::Index c = 0; c < vertex_.rows(); ++c) out.push_back(vertex_(c, p));
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
}

void EmbeddedPoints::couple(const std::array<int, 4>& ids, int count, std::vector<int>& pairs) const {
  std::vector<int> volume;
  volume_vertices(ids, count, volume);
  for (std::size_t i = 0; i < volume.size(); ++i)
    for (std::size_t j = i + 1; j < volume.size(); ++j) pairs.insert(pairs.end(), {volume[i], volume[j]});
}

template <int N>
void EmbeddedPoints::scatter(const contact::Derivatives<N>& d, const std::array<int, 4>& ids, Eigen::VectorXd* gradient,
                             const HessianValues* hessian) const {
  constexpr int M = N / 3;
  const Eigen::Index k = vertex_.rows();
  if (gradient)
    for (int i = 0; i < M; ++i)
      if (const int p = ids[static_cast<std::size_t>(i)]; p >= 0)
        for (Eigen::Index c = 0; c < k; ++c)
          gradient->segment<3>(3 * vertex_(c, p)) += weight_(c, p) * d.gradient.template segment<3>(3 * i);
  if (!hessian) return;
  // J (N by 3U): the slots' coordinates as linear functions of their U distinct volume vertices; H_x = Jᵀ H J.
  std::vector<int> volume;
  volume_vertices(ids, M, volume);
  const auto U = static_cast<Eigen::Index>(volume.size());
  Eigen::MatrixXd C = Eigen::MatrixXd::Zero(M, U);  // C(i, u): slot i's weight on volume vertex u
  for (int i = 0; i < M; ++i)
    if (const int p = ids[static_cast<std::size_t>(i)]; p >= 0)
      for (Eigen::Index c = 0; c < k; ++c) {
        const auto u = std::lower_bound(volume.begin(), volume.end(), vertex_(c, p)) - volume.begin();
        C(i, u) += weight_(c, p);
      }
  Eigen::MatrixXd HJ(N, 3 * U);  // H J
  for (int i = 0; i < M; ++i)
    for (Eigen::Index u = 0; u < U; ++u) {
      Mat3 sum = Mat3::Zero();
      for (int j = 0; j < M; ++j) sum += C(j, u) * d.hessian.template block<3, 3>(3 * i, 3 * j);
      HJ.block<3, 3>(3 * i, 3 * u) = sum;
    }
  for (Eigen::Index u = 0; u < U; ++u)
    for (Eigen::Index v = u; v < U; ++v) {
      Mat3 block = Mat3::Zero();
      for (int i = 0; i < M; ++i) block += C(i, u) * HJ.block<3, 3>(3 * i, 3 * v);
      hessian->add_block(volume[static_cast<std::size_t>(u)], volume[static_cast<std::size_t>(v)], block);
    }
}

template void EmbeddedPoints::scatter<3>(const contact::Derivatives<3>&, const std::array<int, 4>&, Eigen::VectorXd*,
                                         const HessianValues*) const;
template void EmbeddedPoints::scatter<6>(const contact::Derivatives<6>&, const std::array<int, 4>&, Eigen::VectorXd*,
                                         const HessianValues*) const;
template void EmbeddedPoints::scatter<9>(const contact::Derivatives<9>&, const std::array<int, 4>&, Eigen::VectorXd*,
                                         const HessianValues*) const;
template void EmbeddedPoints::scatter<12>(const contact::Derivatives<12>&, const std::array<int, 4>&, Eigen::VectorXd*,
                                          const HessianValues*) const;

}  // namespace snh
