#include "snh/contact/barrier.hpp"

#include <cmath>
#include <limits>

namespace snh::contact {

namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}

double barrier(double s, double s_hat) {
  if (s <= 0.0) return kInf;
  if (s >= s_hat) return 0.0;
  const double g = s - s_hat;
  return -g * g * std::log(s / s_hat);
}

double barrier_first_derivative(double s, double s_hat) {
  if (s <= 0.0) return -kInf;
  if (s >= s_hat) return 0.0;
  const double g = s - s_hat;
  return -2.0 * g * std::log(s / s_hat) - g * g / s;
}

double barrier_second_derivative(double s, double s_hat) {
  if (s <= 0.0) return kInf;
  if (s >= s_hat) return 0.0;
  const double g = s - s_hat;
  return -2.0 * std::log(s / s_hat) - 4.0 * g / s + g * g / (s * s);
}

}  // namespace snh::contact
