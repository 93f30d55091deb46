#pragma once
// Small signal filters of the control cycle, each one named and tested alone (tests/test_filters.cpp).
//   LowPassFilter        first-order low-pass, backward Euler: y += dt / (T + dt) (x - y)
//   ComplementaryFilter  low-frequency part of one signal + high-frequency part of another,
//                        crossover at a pole K (exact discretisation: 1 - exp(-K dt))
//   soft_deadband        x -> sign(x) max(|x| - b, 0), continuous at the band's edge
// SmoothedVector (smoothed_vector.hpp) is the low-pass of a vector toward a target.
// No allocation after construction; nothing throws after construction.
#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace phri {

/// Gain of one backward-Euler step of T y' = x - y with period dt (1 for T = 0: no filtering).
inline double low_pass_gain(double time_constant_s, double dt) {
  return time_constant_s > 0.0 ? dt / (time_constant_s + dt) : 1.0;
}

class LowPassFilter {
public:
  LowPassFilter() = default;
  /// time_constant_s >= 0 (0: the output is the input), dt > 0.
  LowPassFilter(double time_constant_s, double dt) : alpha_(low_pass_gain(time_constant_s, dt)) {}

  double update(double x) {
    value_ += alpha_ * (x - value_);
    return value_;
  }
  void reset(double value) { value_ = value; }
  double value() const { return value_; }

private:
  double alpha_ = 1.0;
  double value_ = 0.0;
};

class ComplementaryFilter {
public:
  ComplementaryFilter() = default;
  /// n channels; crossover_rad_s > 0 is the pole K of the high-pass on `high`.
  ComplementaryFilter(int n, double crossover_rad_s, double dt)
      : gain_(1.0 - std::exp(-crossover_rad_s * dt)), high_low_(Eigen::VectorXd::Zero(n)), out_(Eigen::VectorXd::Zero(n)) {}

  /// low + (high - its low-pass at K): `low` contributes below K, `high` above it.
  const Eigen::VectorXd& update(const Eigen::VectorXd& low, const Eigen::VectorXd& high) {
    high_low_ += gain_ * (high - high_low_);
    out_ = low + high - high_low_;
    return out_;
  }
  const Eigen::VectorXd& value() const { return out_; }

private:
  double gain_ = 1.0;
  Eigen::VectorXd high_low_, out_;
};

/// sign(x) max(|x| - band, 0).
inline double soft_deadband(double x, double band) { return std::copysign(std::max(std::abs(x) - band, 0.0), x); }

/// The soft dead band per entry: out[i] = soft_deadband(x[i], band[i]).
inline void soft_deadband(const Eigen::VectorXd& x, const Eigen::VectorXd& band, Eigen::VectorXd& out) {
  for (Eigen::Index i = 0; i < x.size(); ++i) out[i] = soft_deadband(x[i], band[i]);
}

}  // namespace phri
