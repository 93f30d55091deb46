#pragma once
// phri::GroundTruth: what a simulated arm knows and a real one does not, the plant's true link-side
// joint positions and velocities (no sensor noise, no transmission between them and the link). The run loop gets
// one from the backend that built the robot (RunOptions::ground_truth) to measure the end effector's
// true error beside the QP's own task error, so nothing above the robot interface needs to know
// which robot it is. A real arm has none.
#include <Eigen/Core>

namespace phri {

class GroundTruth {
public:
  virtual ~GroundTruth() = default;
  GroundTruth() = default;
  GroundTruth(const GroundTruth&) = delete;
  GroundTruth& operator=(const GroundTruth&) = delete;

  /// The true link-side joint positions [rad] after the latest write() (the model's joint order).
  /// No allocation, no throw (read in the cycle).
  virtual const Eigen::VectorXd& true_joint_positions() const = 0;
  /// The true link-side joint velocities [rad/s], likewise.
  virtual const Eigen::VectorXd& true_joint_velocities() const = 0;
};

}  // namespace phri
