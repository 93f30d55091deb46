#pragma once
// A vector parameter that moves toward its target with a first-order response, so that a gain,
// weight or gamma changed at run time never steps the commanded torque. With time constant T and
// period dt, each step moves a fraction dt / (T + dt) of the remaining distance (backward Euler).
#include <phri/core/filters.hpp>

#include <Eigen/Core>

namespace phri {

class SmoothedVector {
public:
  SmoothedVector() = default;
  SmoothedVector(const Eigen::VectorXd& initial, double time_constant)
      : value_(initial), target_(initial), time_constant_(time_constant) {}

  /// The value to reach; the current value follows over a few time constants.
  /// (A Ref, so that a fixed-size vector binds without a temporary: no allocation in the cycle.)
  void set_target(const Eigen::Ref<const Eigen::VectorXd>& target) { target_ = target; }
  void set_target_constant(double value) { target_.setConstant(value); }
  /// Sets value and target at once (no smoothing), e.g. at start-up.
  void reset(const Eigen::Ref<const Eigen::VectorXd>& value) {
    value_ = value;
    target_ = value;
  }
  void set_time_constant(double seconds) { time_constant_ = seconds; }

  void step(double dt) {
    value_ += low_pass_gain(time_constant_, dt) * (target_ - value_);
  }
  const Eigen::VectorXd& value() const { return value_; }
  const Eigen::VectorXd& target() const { return target_; }

private:
  Eigen::VectorXd value_;
  Eigen::VectorXd target_;
  double time_constant_ = 0.0;
};

}  // namespace phri
