#pragma once
// Minimum-jerk move of the posture reference between two joint configurations.
#include <phri/model/model.hpp>

#include <Eigen/Core>
#include <vector>

namespace phri {

/// Joint-space references (posture task): quintic move and a brake. Continuous joints move the
/// short way round (the error wrapped to (-pi, pi]).
class JointMove {
public:
  explicit JointMove(const Model& model);
  void start(const Eigen::VectorXd& from, const Eigen::VectorXd& to, double max_speed, double min_duration);
  void evaluate(double t, Eigen::VectorXd& q, Eigen::VectorXd& qd, Eigen::VectorXd& qdd) const;
  double duration() const { return duration_; }
  /// Difference to - from, wrapped for continuous joints (into `out`, sized).
  void difference(const Eigen::VectorXd& from, const Eigen::VectorXd& to, Eigen::VectorXd& out) const;

private:
  std::vector<bool> continuous_;
  Eigen::VectorXd from_, delta_;
  double duration_ = 0.0;
};

}  // namespace phri
