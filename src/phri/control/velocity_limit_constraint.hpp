#pragma once
// Joint velocity limits of the QP (paper: 0.9 of the robot's limits), as bounds on qdd that drive
// qd back within +-v_max at the rate lambda: qdd <= -lambda (qd - v_max), qdd >= -lambda (qd + v_max).
// lambda per joint: its joint-limit damper's for a limited joint, a set gain for a continuous one.
#include <Eigen/Core>

namespace phri {

class VelocityLimitConstraint {
public:
  VelocityLimitConstraint(const Eigen::VectorXd& velocity_limit, const Eigen::VectorXd& gain)
      : velocity_limit_(velocity_limit), gain_(gain) {}

  /// Sets the acceleration bounds from the velocity limits.
  void bound(const Eigen::VectorXd& qd, Eigen::VectorXd& lower, Eigen::VectorXd& upper) const {
    for (int i = 0; i < qd.size(); ++i) {
      upper[i] = -gain_[i] * (qd[i] - velocity_limit_[i]);
      lower[i] = -gain_[i] * (qd[i] + velocity_limit_[i]);
    }
  }
  const Eigen::VectorXd& velocity_limit() const { return velocity_limit_; }

private:
  Eigen::VectorXd velocity_limit_, gain_;
};

}  // namespace phri
