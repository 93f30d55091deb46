#include <phri/control/end_effector_task.hpp>

#include <phri/model/algorithms.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace phri {

Eigen::Vector3d rotation_log(const Eigen::Matrix3d& r) {
  const double cos_angle = std::clamp((r.trace() - 1.0) / 2.0, -1.0, 1.0);
  const double angle = std::acos(cos_angle);
  const Eigen::Vector3d skew(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));  // 2 sin(angle) axis
  if (angle < 1e-6) return 0.5 * skew;  // sin(angle) ~ angle
  if (std::numbers::pi - angle > 1e-6) return angle / (2.0 * std::sin(angle)) * skew;
  // Near pi: the axis from the symmetric part, R = 2 a a' - I, sign from the skew part.
  Eigen::Vector3d axis;
  int k;
  r.diagonal().maxCoeff(&k);
  axis = (r.col(k) + Eigen::Vector3d::Unit(k)) / std::sqrt(2.0 * (1.0 + r(k, k)));
  if (axis.dot(skew) < 0.0) axis = -axis;
  return angle * axis.normalized();
}

EndEffectorTask::EndEffectorTask(const Model& model, int frame_id, double smoothing_time_constant,
                                 const TargetLimits& limits)
    : frame_id_(frame_id),
      limits_(limits),
      stiffness_(Eigen::VectorXd::Zero(6), smoothing_time_constant),
      damping_(Eigen::VectorXd::Zero(6), smoothing_time_constant),
      weight_(Eigen::VectorXd::Zero(1), smoothing_time_constant),
      gamma_(Eigen::VectorXd::Zero(6), smoothing_time_constant),
      jacobian_(Eigen::MatrixXd::Zero(6, model.nv())) {}

void EndEffectorTask::set_stiffness(const Vector6d& stiffness) { stiffness_.set_target(stiffness); }
void EndEffectorTask::set_damping(const Vector6d& damping) { damping_.set_target(damping); }
void EndEffectorTask::set_critical_damping() {
  const Vector6d damping = 2.0 * stiffness_.target().cwiseSqrt();  // fixed size: no temporary on the heap
  damping_.set_target(damping);
}
void EndEffectorTask::set_weight(double weight) { weight_.set_target_constant(weight); }
void EndEffectorTask::set_gamma(const Vector6d& gamma) {
  const Vector6d clamped = gamma.cwiseMax(0.0).cwiseMin(1.0);
  gamma_.set_target(clamped);
}

void EndEffectorTask::reset_gains(const Vector6d& stiffness, const Vector6d& damping, double weight,
                                  const Vector6d& gamma) {
  stiffness_.reset(stiffness);
  damping_.reset(damping);
  weight_.reset(Eigen::VectorXd::Constant(1, weight));
  gamma_.reset(gamma.cwiseMax(0.0).cwiseMin(1.0));
}

void EndEffectorTask::set_target(const Eigen::Isometry3d& pose, const Vector6d& velocity, const Vector6d& acceleration) {
  commanded_pose_ = pose;
  commanded_velocity_ = velocity;
  commanded_acceleration_ = acceleration;
}

void EndEffectorTask::hold_current_pose(const Data& data) {
  commanded_pose_ = data.frame_placements[static_cast<std::size_t>(frame_id_)];
  commanded_velocity_.setZero();
  commanded_acceleration_.setZero();
  target_pose_ = commanded_pose_;
  target_velocity_.setZero();
  target_acceleration_.setZero();
  tracking_position_ = tracking_rotation_ = true;
  governor_linear_speed_ = governor_angular_speed_ = 0.0;
}

bool EndEffectorTask::target_reached() const {
  return (commanded_pose_.translation() - target_pose_.translation()).norm() < 1e-9 &&
         (commanded_pose_.linear() - target_pose_.linear()).cwiseAbs().maxCoeff() < 1e-9;
}

// A target that moves by about its own velocity per period is a trajectory: tracked as given.
// Otherwise the tracked target runs toward it at bounded speed and acceleration, braking so as to
// stop on it (speed <= sqrt(2 a d)), with its velocity as feed-forward: continuous references,
// hence no torque step.
void EndEffectorTask::govern_target(double dt) {
  // Position.
  const Eigen::Vector3d gap = commanded_pose_.translation() - target_pose_.translation();
  const double distance = gap.norm();
  const double streamed = 1.5 * dt * std::max(limits_.linear_speed, commanded_velocity_.head<3>().norm()) + 1e-9;
  if (tracking_position_ && distance <= streamed) {
    target_pose_.translation() = commanded_pose_.translation();
    target_velocity_.head<3>() = commanded_velocity_.head<3>();
    target_acceleration_.head<3>() = commanded_acceleration_.head<3>();
    governor_linear_speed_ = commanded_velocity_.head<3>().norm();
  } else {
    tracking_position_ = false;
    const double speed = std::min({governor_linear_speed_ + limits_.linear_acceleration * dt, limits_.linear_speed,
                                   std::sqrt(2.0 * limits_.linear_acceleration * distance)});
    const double step = std::min(speed * dt, distance);
    const Eigen::Vector3d direction = distance > 0.0 ? Eigen::Vector3d(gap / distance) : Eigen::Vector3d::Zero();
    target_pose_.translation() += direction * step;
    target_velocity_.head<3>() = direction * speed;
    target_acceleration_.head<3>().setZero();
    governor_linear_speed_ = speed;
    if (distance - step < 1e-7) tracking_position_ = true;
  }
  // Orientation: the same along the geodesic from the tracked to the set orientation.
  const Eigen::Vector3d rotation = rotation_log(commanded_pose_.linear() * target_pose_.linear().transpose());
  const double angle = rotation.norm();
  const double streamed_angle = 1.5 * dt * std::max(limits_.angular_speed, commanded_velocity_.tail<3>().norm()) + 1e-9;
  if (tracking_rotation_ && angle <= streamed_angle) {
    target_pose_.linear() = commanded_pose_.linear();
    target_velocity_.tail<3>() = commanded_velocity_.tail<3>();
    target_acceleration_.tail<3>() = commanded_acceleration_.tail<3>();
    governor_angular_speed_ = commanded_velocity_.tail<3>().norm();
  } else {
    tracking_rotation_ = false;
    const double speed = std::min({governor_angular_speed_ + limits_.angular_acceleration * dt, limits_.angular_speed,
                                   std::sqrt(2.0 * limits_.angular_acceleration * angle)});
    const double step = std::min(speed * dt, angle);
    const Eigen::Vector3d axis = angle > 0.0 ? Eigen::Vector3d(rotation / angle) : Eigen::Vector3d::UnitZ();
    target_pose_.linear() = Eigen::AngleAxisd(step, axis).toRotationMatrix() * target_pose_.linear();
    target_velocity_.tail<3>() = axis * speed;
    target_acceleration_.tail<3>().setZero();
    governor_angular_speed_ = speed;
    if (angle - step < 1e-7) tracking_rotation_ = true;
  }
}

void EndEffectorTask::update(const Model& model, const Data& data, const Eigen::VectorXd& qdd_external, double dt) {
  stiffness_.step(dt);
  damping_.step(dt);
  weight_.step(dt);
  gamma_.step(dt);
  govern_target(dt);
  pose_ = data.frame_placements[static_cast<std::size_t>(frame_id_)];
  frame_jacobian(model, data, frame_id_, ReferenceFrame::kLocalWorldAligned, jacobian_);
  velocity_ = frame_velocity(model, data, frame_id_, ReferenceFrame::kLocalWorldAligned);
  error_.head<3>() = target_pose_.translation() - pose_.translation();
  error_.tail<3>() = rotation_log(target_pose_.linear() * pose_.linear().transpose());
  const Vector6d bias = frame_jdot_qdot(model, data, frame_id_, ReferenceFrame::kLocalWorldAligned);
  // ë* (paper's task reference) minus the drift J̇ qd, plus the compliant part gamma J M^-1 tau_ext.
  reference_ = target_acceleration_ + stiffness_.value().cwiseProduct(error_) +
               damping_.value().cwiseProduct(target_velocity_ - velocity_) - bias;
  external_task_acceleration_.noalias() = jacobian_ * qdd_external;
  reference_ += gamma_.value().cwiseProduct(external_task_acceleration_);
}

}  // namespace phri
