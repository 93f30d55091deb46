#pragma once
// End-effector wrench from a flange F/T sensor (a Bota SensONE on the paper's arm): removes the
// sensor's bias (averaged at start-up), removes the tool's weight for the current orientation,
// and expresses what is left, the wrench the operator applies, at the end effector in world
// axes. Its norm drives dual compliance. Tool inertial forces (0.3 kg x the tool's acceleration)
// are not removed: at the paper's speeds they stay well below the 4 N release threshold.
//
// Sensor convention (RobotState): the wrench (f; m) the tool exerts on the flange side, in the
// sensor frame, about its origin; a tool at rest reads m_tool * g in sensor axes.
#include <phri/model/spatial.hpp>

#include <Eigen/Geometry>

namespace phri {

struct WrenchEstimatorSettings {
  double tool_mass_kg = 0.0;                                 ///< what hangs below the sensor (none by default)
  Eigen::Vector3d tool_com_m = Eigen::Vector3d::Zero();      ///< in the sensor frame
  Eigen::Vector3d gravity = Eigen::Vector3d(0, 0, -9.81);    ///< world (Controller: its model's)
  int bias_samples = 200;  ///< samples averaged at start-up (0.2 s at 1 kHz), arm at rest
};

class WrenchEstimator {
public:
  explicit WrenchEstimator(const WrenchEstimatorSettings& settings = {});

  /// One sample. sensor_pose: the sensor frame in the world; end_effector: the point the wrench
  /// is expressed about. The first bias_samples samples estimate the bias (the result is zero
  /// meanwhile). Non-finite samples are ignored (the last estimate is kept) and counted.
  void update(const Vector6d& wrench_sensor, const Eigen::Isometry3d& sensor_pose, const Eigen::Vector3d& end_effector);

  bool calibrated() const { return samples_ >= settings_.bias_samples; }
  /// The operator's wrench at the end effector, world axes: (force; moment about the EE origin).
  const Vector6d& wrench_world() const { return wrench_world_; }
  double norm() const { return wrench_world_.norm(); }
  const Vector6d& bias() const { return bias_; }
  long rejected_samples() const { return rejected_; }
  /// Restarts the bias estimation (e.g. after a tool change, arm at rest).
  void recalibrate();

  /// The tool's static load on the sensor (f; m) in sensor axes for the sensor orientation.
  Vector6d tool_load(const Eigen::Matrix3d& sensor_rotation) const;

private:
  WrenchEstimatorSettings settings_;
  int samples_ = 0;
  long rejected_ = 0;
  Vector6d bias_sum_ = Vector6d::Zero();
  Vector6d bias_ = Vector6d::Zero();
  Vector6d wrench_world_ = Vector6d::Zero();
};

}  // namespace phri
