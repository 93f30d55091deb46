#include <phri/control/end_effector_task.hpp>

#include <phri/model/algorithms.hpp>

#include <algorithm>
#include <cmath>

namespace phri {

Eigen::Vector3d rotation_log(const Eigen::Matrix3d& r) {
  const double cos_angle = std::clamp((r.trace() - 1.0) / 2.0, -1.0, 1.0);
  const double angle = std::acos(cos_angle);
  const Eigen::Vector3d skew(r(2, 1) - r(1, 2), r(0, 2) - r(2, 0), r(1, 0) - r(0, 1));  // 2 sin(angle) axis
  if (angle < 1e-6) return 0.5 * skew;  // sin(angle) ~ angle
  if (M_PI - angle > 1e-6) return angle / (2.0 * std::sin(angle)) * skew;
  // Near pi: the axis from the symmetric part, R = 2 a a' - I, sign from the skew part.
  Eigen::Vector3d axis;
  int k;
  r.diagonal().maxCoeff(&k);
  axis = (r.col(k) + Eigen::Vector3d::Unit(k)) / std::sqrt(2.0 * (1.0 + r(k, k)));
  if (axis.dot(skew) < 0.0) axis = -axis;
  return angle * axis.normalized();
}

EndEffectorTask::EndEffectorTask(const Model& model, int frame_id, double smoothing_time_constant)
    : frame_id_(frame_id),
      stiffness_(Eigen::VectorXd::Zero(6), smoothing_time_constant),
      damping_(Eigen::VectorXd::Zero(6), smoothing_time_constant),
      weight_(Eigen::VectorXd::Zero(1), smoothing_time_constant),
      gamma_(Eigen::VectorXd::Zero(6), smoothing_time_constant),
      jacobian_(Eigen::MatrixXd::Zero(6, model.nv())) {}

void EndEffectorTask::set_stiffness(const Vector6d& stiffness) { stiffness_.set_target(stiffness); }
void EndEffectorTask::set_damping(const Vector6d& damping) { damping_.set_target(damping); }
void EndEffectorTask::set_critical_damping() { damping_.set_target(2.0 * stiffness_.target().cwiseSqrt()); }
void EndEffectorTask::set_weight(double weight) { weight_.set_target_constant(weight); }
void EndEffectorTask::set_gamma(const Vector6d& gamma) { gamma_.set_target(gamma.cwiseMax(0.0).cwiseMin(1.0)); }

void EndEffectorTask::reset_gains(const Vector6d& stiffness, const Vector6d& damping, double weight,
                                  const Vector6d& gamma) {
  stiffness_.reset(stiffness);
  damping_.reset(damping);
  weight_.reset(Eigen::VectorXd::Constant(1, weight));
  gamma_.reset(gamma.cwiseMax(0.0).cwiseMin(1.0));
}

void EndEffectorTask::set_target(const Eigen::Isometry3d& pose, const Vector6d& velocity, const Vector6d& acceleration) {
  target_pose_ = pose;
  target_velocity_ = velocity;
  target_acceleration_ = acceleration;
}

void EndEffectorTask::hold_current_pose(const Data& data) {
  target_pose_ = data.frame_placements[static_cast<std::size_t>(frame_id_)];
  target_velocity_.setZero();
  target_acceleration_.setZero();
}

void EndEffectorTask::update(const Model& model, const Data& data, const Eigen::VectorXd& qdd_external, double dt) {
  stiffness_.step(dt);
  damping_.step(dt);
  weight_.step(dt);
  gamma_.step(dt);
  pose_ = data.frame_placements[static_cast<std::size_t>(frame_id_)];
  frame_jacobian(model, data, frame_id_, ReferenceFrame::kLocalWorldAligned, jacobian_);
  velocity_ = frame_velocity(model, data, frame_id_, ReferenceFrame::kLocalWorldAligned);
  error_.head<3>() = target_pose_.translation() - pose_.translation();
  error_.tail<3>() = rotation_log(target_pose_.linear() * pose_.linear().transpose());
  const Vector6d bias = frame_jdot_qdot(model, data, frame_id_, ReferenceFrame::kLocalWorldAligned);
  // ë* (paper's task reference) minus the drift J̇ qd, plus the compliant part gamma J M^-1 tau_ext.
  reference_ = target_acceleration_ + stiffness_.value().cwiseProduct(error_) +
               damping_.value().cwiseProduct(target_velocity_ - velocity_) - bias;
  reference_.noalias() += gamma_.value().asDiagonal() * (jacobian_ * qdd_external);
}

}  // namespace phri
