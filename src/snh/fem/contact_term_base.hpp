#pragma once
// What every contact term shares (self-contact, planes and shapes, mesh colliders): counters of what it did
// (wall time, step bounds asked, primitives tested), and its statistics at a state (active pairs, the
// smallest distance), reported through the Term interface (Term::report_contact) once per frame.
#include <chrono>
#include <cmath>

#include <Eigen/Core>

#include "snh/fem/term.hpp"

namespace snh {

/// What a contact term did since its counters were last reset.
struct ContactCounters {
  double seconds = 0.0;     ///< wall time in energy, evaluate, stencil and max_step
  long long ccd_calls = 0;  ///< max_step evaluations
  long long ccd_tests = 0;  ///< primitive pairs (surfaces) or points (shapes) max_step tested
};

class ContactTermBase : public Term {
 public:
  /// Active pairs at x (surfaces: merged pairs closer than d̂; shapes: points closer than d̂).
  [[nodiscard]] virtual int active_pairs(const Eigen::VectorXd& x) const = 0;
  /// The smallest distance at x (asked for the statistics only where there are active pairs, whose smallest
  /// distance it then is).
  [[nodiscard]] virtual double min_distance(const Eigen::VectorXd& x) const = 0;

  [[nodiscard]] bool reports_contact() const final { return true; }
  void report_contact(const Eigen::VectorXd& x, ContactStatistics& into) final {
    const int pairs = active_pairs(x);
    into.pairs += pairs;
    if (pairs > 0) into.min_distance = std::fmin(into.min_distance, min_distance(x));
    into.ccd_calls += counters_.ccd_calls;
    into.ccd_tests += counters_.ccd_tests;
    into.seconds += counters_.seconds;
    counters_ = {};
  }

 protected:
  mutable ContactCounters counters_;
};

/// Adds the wall time of its scope to a counter.
class ScopeTimer {
 public:
  explicit ScopeTimer(double& seconds) : seconds_(seconds), start_(std::chrono::steady_clock::now()) {}
  ~ScopeTimer() { seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count(); }
  ScopeTimer(const ScopeTimer&) = delete;
  ScopeTimer& operator=(const ScopeTimer&) = delete;

 private:
  double& seconds_;
  std::chrono::steady_clock::time_point start_;
};

}  // namespace snh
