#include "snh/fem/attachment_term.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include <fmt/format.h>

namespace snh {

AttachmentTerm::AttachmentTerm(std::vector<int> vertices, Eigen::VectorXd stiffness, Targets targets)
    : vertices_(std::move(vertices)), stiffness_(std::move(stiffness)), targets_(std::move(targets)) {
  if (static_cast<Eigen::Index>(vertices_.size()) != stiffness_.size())
    throw std::invalid_argument(
        fmt::format("attachment: {} vertices but {} stiffnesses", vertices_.size(), stiffness_.size()));
  if (!targets_) throw std::invalid_argument("attachment: no targets");
  std::vector<int> sorted = vertices_;
  std::sort(sorted.begin(), sorted.end());
  for (std::size_t i = 0; i < sorted.size(); ++i) {
    if (sorted[i] < 0) throw std::invalid_argument(fmt::format("attachment: vertex index {} is negative", sorted[i]));
    if (i > 0 && sorted[i] == sorted[i - 1])
      throw std::invalid_argument(fmt::format("attachment: vertex {} is attached twice", sorted[i]));
  }
  for (Eigen::Index i = 0; i < stiffness_.size(); ++i)
    if (!(stiffness_[i] >= 0.0) || !std::isfinite(stiffness_[i]))
      throw std::invalid_argument(
          fmt::format("attachment: the stiffness of vertex {} must be finite and >= 0, got {:g}", vertices_[i], stiffness_[i]));
  at_time(0.0);
}

void AttachmentTerm::at_time(double t) {
  targets_(t, current_);
  if (current_.cols() != static_cast<Eigen::Index>(vertices_.size()))
    throw std::logic_error(fmt::format("attachment: {} targets for {} vertices", current_.cols(), vertices_.size()));
}

double AttachmentTerm::energy(const Eigen::VectorXd& x) const { return evaluate(x, nullptr, nullptr, PsdProjection::none); }

double AttachmentTerm::evaluate(const Eigen::VectorXd& x, Eigen::VectorXd* gradient, const HessianValues* hessian,
                                PsdProjection /*projection*/) const {
  double e = 0.0;
  for (std::size_t i = 0; i < vertices_.size(); ++i) {
    const int v = vertices_[i];
    const double k = stiffness_[static_cast<Eigen::Index>(i)];
    const Eigen::Vector3d d = x.segment<3>(3 * v) - current_.col(static_cast<Eigen::Index>(i));
    e += 0.5 * k * d.squaredNorm();
    if (gradient) gradient->segment<3>(3 * v) += k * d;
    if (hessian) hessian->add_block(v, v, k * Mat3::Identity());
  }
  return e;
}

}  // namespace snh
