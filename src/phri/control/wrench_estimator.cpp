#include <phri/control/wrench_estimator.hpp>

namespace phri {

WrenchEstimator::WrenchEstimator(const WrenchEstimatorSettings& settings) : settings_(settings) {}

void WrenchEstimator::recalibrate() {
  samples_ = 0;
  bias_sum_.setZero();
  bias_.setZero();
  wrench_world_.setZero();
}

Vector6d WrenchEstimator::tool_load(const Eigen::Matrix3d& sensor_rotation) const {
  const Eigen::Vector3d weight = sensor_rotation.transpose() * (settings_.tool_mass_kg * settings_.gravity);
  Vector6d load;
  load << weight, settings_.tool_com_m.cross(weight);
  return load;
}

void WrenchEstimator::update(const Vector6d& wrench_sensor, const Eigen::Isometry3d& sensor_pose,
                             const Eigen::Vector3d& end_effector) {
  if (!wrench_sensor.allFinite() || !sensor_pose.matrix().allFinite()) {
    ++rejected_;
    return;
  }
  const Vector6d expected_tool = tool_load(sensor_pose.linear());
  if (samples_ < settings_.bias_samples) {
    // Bias: what the sensor reads beyond the tool's own weight, the arm at rest.
    bias_sum_ += wrench_sensor - expected_tool;
    ++samples_;
    bias_ = bias_sum_ / samples_;
    wrench_world_.setZero();
    return;
  }
  const Vector6d external = wrench_sensor - bias_ - expected_tool;  // sensor axes, about its origin
  const Eigen::Vector3d force = sensor_pose.linear() * external.head<3>();
  const Eigen::Vector3d moment = sensor_pose.linear() * external.tail<3>();
  // Shift the moment from the sensor origin to the end effector: m_ee = m_s + (p_s - p_ee) x f.
  wrench_world_ << force, moment + (sensor_pose.translation() - end_effector).cross(force);
}

}  // namespace phri
