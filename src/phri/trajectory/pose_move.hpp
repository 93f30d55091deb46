#pragma once
// Minimum-jerk move of an end-effector reference between two poses.
#include <phri/control/controller_targets.hpp>

#include <Eigen/Geometry>

namespace phri {

/// Minimum-jerk move between two poses: straight line, and the geodesic for the orientation.
class PoseMove {
public:
  /// Duration: the longest of min_duration and what keeps the peak speeds within the bounds.
  void start(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to, double max_speed, double max_angular_speed,
             double min_duration);
  void evaluate(double t, PoseReference& out) const;
  double duration() const { return duration_; }
  const Eigen::Isometry3d& goal() const { return to_; }

private:
  Eigen::Isometry3d from_ = Eigen::Isometry3d::Identity(), to_ = Eigen::Isometry3d::Identity();
  Eigen::Vector3d displacement_ = Eigen::Vector3d::Zero();
  Eigen::Vector3d rotation_ = Eigen::Vector3d::Zero();  // log(R_to R_from^T), world axes
  double duration_ = 0.0;
};

}  // namespace phri
