#include <phri/control/end_effector_task.hpp>

#include <phri/control/stiction_term.hpp>
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
                                 const TargetLimits& limits, double singular_value_threshold, std::string name,
                                 ComplianceRole role)
    : Task(std::move(name), role),
      frame_id_(frame_id),
      limits_(limits),
      stiffness_(Eigen::VectorXd::Zero(6), smoothing_time_constant),
      damping_(Eigen::VectorXd::Zero(6), smoothing_time_constant),
      weight_(Eigen::VectorXd::Zero(1), smoothing_time_constant),
      gamma_(Eigen::VectorXd::Zero(6), smoothing_time_constant),
      jacobian_(Eigen::MatrixXd::Zero(6, model.nv())),
      singular_weight_(singular_value_threshold, model.nv()),
      frame_jacobian_(Eigen::MatrixXd::Zero(6, model.nv())),
      weighted_rows_(Eigen::MatrixXd::Zero(6, model.nv())),
      selected_rows_(Eigen::MatrixXd::Zero(6, model.nv())) {}

void EndEffectorTask::set_fixed_gamma(const Vector6d& gamma) {
  fixed_gamma_ = true;
  gamma_.reset(gamma.cwiseMax(0.0).cwiseMin(1.0));
}

void EndEffectorTask::set_selection(const Vector6d& selection) {
  selection_ = selection.cwiseMax(0.0).cwiseMin(1.0);
  selecting_ = (selection_.array() < 1.0).any();
}

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
  if (!fixed_gamma_) gamma_.reset(gamma.cwiseMax(0.0).cwiseMin(1.0));
}

void EndEffectorTask::set_integral(const TaskIntegralSettings& settings) {
  integral_ = settings;
  integral_term_.setZero();
}

void EndEffectorTask::set_target(const Eigen::Isometry3d& pose, const Vector6d& velocity, const Vector6d& acceleration) {
  if (pose.matrix() != commanded_pose_.matrix()) integral_term_.setZero();
  commanded_pose_ = pose;
  commanded_velocity_ = velocity;
  commanded_acceleration_ = acceleration;
}

void EndEffectorTask::hold_current_pose(const Data& data) {
  commanded_pose_ = data.frame_placements[static_cast<std::size_t>(frame_id_)];
  integral_term_.setZero();
  commanded_velocity_.setZero();
  commanded_acceleration_.setZero();
  target_pose_ = commanded_pose_;
  target_velocity_.setZero();
  target_acceleration_.setZero();
  tracking_position_ = tracking_rotation_ = true;
  governor_linear_speed_ = governor_angular_speed_ = 0.0;
}

void EndEffectorTask::set_target_offset(const Eigen::Isometry3d& offset) {
  target_offset_ = offset;
  offset_on_ = offset.matrix() != Eigen::Matrix4d::Identity();
}

// The tracked target: the governed one carried by the offset (its velocity and acceleration rotated).
void EndEffectorTask::apply_target_offset() {
  if (!offset_on_) {
    tracked_pose_ = target_pose_;
    tracked_velocity_ = target_velocity_;
    tracked_acceleration_ = target_acceleration_;
    return;
  }
  const Eigen::Matrix3d& r = target_offset_.linear();
  tracked_pose_ = target_offset_ * target_pose_;
  tracked_velocity_.head<3>() = r * target_velocity_.head<3>();
  tracked_velocity_.tail<3>() = r * target_velocity_.tail<3>();
  tracked_acceleration_.head<3>() = r * target_acceleration_.head<3>();
  tracked_acceleration_.tail<3>() = r * target_acceleration_.tail<3>();
}

bool EndEffectorTask::target_reached() const {
  return (commanded_pose_.translation() - target_pose_.translation()).norm() < 1e-9 &&
         (commanded_pose_.linear() - target_pose_.linear()).cwiseAbs().maxCoeff() < 1e-9;
}

// A target that moves by about its own velocity per period is a trajectory: tracked as given.
// Otherwise the tracked target runs toward it at bounded speed and acceleration, braking so as to
// stop on it (speed <= sqrt(2 a d)), with its velocity as feed-forward: continuous references,
// hence no torque step.
// One channel of the reference governor (position, or orientation along the geodesic). `gap`
// goes from the tracked target to the set one (a translation or a rotation vector). Either the
// set reference is streamed (it moves by about its own speed per period: tracked as given, snap)
// or the tracked target moves `step` along `direction` at `speed`.
struct EndEffectorTask::GovernorMove {
  bool snap = true;
  Eigen::Vector3d direction = Eigen::Vector3d::Zero();
  double step = 0.0;
  double speed = 0.0;
};

EndEffectorTask::GovernorMove EndEffectorTask::govern_channel(const Eigen::Vector3d& gap, double commanded_speed,
                                                             double max_speed, double max_acceleration, double dt,
                                                             const Eigen::Vector3d& direction_at_zero, bool& tracking,
                                                             double& speed_state) {
  const double distance = gap.norm();
  const double streamed = 1.5 * dt * std::max(max_speed, commanded_speed) + 1e-9;
  if (tracking && distance <= streamed) {
    speed_state = commanded_speed;
    return {};
  }
  tracking = false;
  GovernorMove move;
  move.snap = false;
  move.speed = std::min({speed_state + max_acceleration * dt, max_speed, std::sqrt(2.0 * max_acceleration * distance)});
  move.step = std::min(move.speed * dt, distance);
  move.direction = distance > 0.0 ? Eigen::Vector3d(gap / distance) : direction_at_zero;
  speed_state = move.speed;
  if (distance - move.step < 1e-7) tracking = true;
  return move;
}

void EndEffectorTask::set_governed_motion(const GovernorMove& move, Eigen::Index offset) {
  if (move.snap) {
    target_velocity_.segment<3>(offset) = commanded_velocity_.segment<3>(offset);
    target_acceleration_.segment<3>(offset) = commanded_acceleration_.segment<3>(offset);
  } else {
    target_velocity_.segment<3>(offset) = move.direction * move.speed;
    target_acceleration_.segment<3>(offset).setZero();
  }
}

void EndEffectorTask::govern_target(double dt) {
  const GovernorMove linear =
      govern_channel(commanded_pose_.translation() - target_pose_.translation(), commanded_velocity_.head<3>().norm(),
                     limits_.linear_speed, limits_.linear_acceleration, dt, Eigen::Vector3d::Zero(), tracking_position_,
                     governor_linear_speed_);
  if (linear.snap) {
    target_pose_.translation() = commanded_pose_.translation();
  } else {
    target_pose_.translation() += linear.direction * linear.step;
  }
  set_governed_motion(linear, 0);
  const GovernorMove angular =
      govern_channel(rotation_log(commanded_pose_.linear() * target_pose_.linear().transpose()),
                     commanded_velocity_.tail<3>().norm(), limits_.angular_speed, limits_.angular_acceleration, dt,
                     Eigen::Vector3d::UnitZ(), tracking_rotation_, governor_angular_speed_);
  if (angular.snap) {
    target_pose_.linear() = commanded_pose_.linear();
  } else {
    target_pose_.linear() = Eigen::AngleAxisd(angular.step, angular.direction).toRotationMatrix() * target_pose_.linear();
  }
  set_governed_motion(angular, 3);
}

void EndEffectorTask::update_integral(double dt) {
  if (integral_.gain <= 0.0) return;
  const double bleed = std::exp(-dt / kIntegralBleed_s);
  const bool creeping = integral_enabled_ && commanded_velocity_.isZero(0.0) && target_reached() &&
                        velocity_.head<3>().norm() < kCreepLinear_m_s && velocity_.tail<3>().norm() < kCreepAngular_rad_s;
  for (Eigen::Index i = 0; i < 6; ++i) {
    const bool linear = i < 3;
    const double e = task_error_[i];
    const double zone = linear ? integral_.linear_zone : integral_.angular_zone;
    const double limit = linear ? integral_.linear_limit : integral_.angular_limit;
    const bool active = creeping && std::abs(e) < zone && stiffness_.value()[i] > 0.0;
    integral_term_[i] = stiction_step(integral_term_[i], e, active, integral_.gain, limit, dt, bleed);
  }
}

void EndEffectorTask::update(const Model& model, const Data& data, const Eigen::VectorXd& qdd_external, double dt) {
  stiffness_.step(dt);
  damping_.step(dt);
  weight_.step(dt);
  gamma_.step(dt);
  govern_target(dt);
  apply_target_offset();
  pose_ = data.frame_placements[static_cast<std::size_t>(frame_id_)];
  frame_jacobian(model, data, frame_id_, ReferenceFrame::kLocalWorldAligned, jacobian_);
  velocity_ = frame_velocity(model, data, frame_id_, ReferenceFrame::kLocalWorldAligned);
  error_.head<3>() = tracked_pose_.translation() - pose_.translation();
  error_.tail<3>() = rotation_log(tracked_pose_.linear() * pose_.linear().transpose());
  task_error_ = in_task_axes(error_);
  update_integral(dt);
  const Vector6d bias = frame_jdot_qdot(model, data, frame_id_, ReferenceFrame::kLocalWorldAligned);
  // ë* (paper's task reference) minus the drift J̇ qd, plus the compliant part gamma J M^-1 tau_ext,
  // each in the rows' axes (K, D and gamma diagonal there).
  reference_ = in_task_axes(tracked_acceleration_) + stiffness_.value().cwiseProduct(task_error_) +
               damping_.value().cwiseProduct(in_task_axes(tracked_velocity_ - velocity_)) + integral_term_ -
               in_task_axes(bias);
  external_task_acceleration_.noalias() = jacobian_.lazyProduct(qdd_external);
  reference_ += gamma_.value().cwiseProduct(in_task_axes(external_task_acceleration_));
  if (axes_ == TaskAxes::kFrame) {
    const Eigen::Matrix3d rt = pose_.linear().transpose();
    frame_jacobian_.topRows<3>().noalias() = rt * jacobian_.topRows<3>();
    frame_jacobian_.bottomRows<3>().noalias() = rt * jacobian_.bottomRows<3>();
  }
  weigh_rows();
}

Vector6d EndEffectorTask::in_task_axes(const Vector6d& world) const {
  if (axes_ == TaskAxes::kWorld) return world;
  const Eigen::Matrix3d rt = pose_.linear().transpose();
  Vector6d local;
  local.head<3>().noalias() = rt * world.head<3>();
  local.tail<3>().noalias() = rt * world.tail<3>();
  return local;
}

// S^1/2 W S^1/2 A: the singular-direction weight W (identity when every singular value is above
// its threshold, not formed) between the selection's square roots.
void EndEffectorTask::weigh_rows() {
  const Eigen::MatrixXd& a = rows();
  const bool singular = singular_weight_.update(a);
  weighted_ = singular || selecting_;
  if (!weighted_) return;
  if (!selecting_ && singular_weight_.rank_one()) {
    // W A = A - shrink u (u^T A), column by column.
    const Vector6d& u = singular_weight_.weak_direction();
    const double shrink = singular_weight_.shrink();
    for (Eigen::Index j = 0; j < a.cols(); ++j) {
      const Eigen::Map<const Vector6d> column(a.col(j).data());
      weighted_rows_.col(j) = column - (shrink * u.dot(column)) * u;
    }
    return;
  }
  if (!selecting_) {
    weighted_rows_.noalias() = singular_weight_.weight() * a;
    return;
  }
  const Vector6d root = selection_.cwiseSqrt();
  selected_rows_.noalias() = root.asDiagonal() * a;
  if (singular) {
    weighted_rows_.noalias() = singular_weight_.weight() * selected_rows_;
    weighted_rows_.array().colwise() *= root.array();
  } else {
    weighted_rows_.noalias() = root.asDiagonal() * selected_rows_;
  }
}

void EndEffectorTask::add_objective(ObjectiveTerms& objective) const {
  const double w = weight();
  const Eigen::MatrixXd& a = rows();
  // w || (S^1/2 W S^1/2)^1/2 (A qdd - b) ||^2 (singular_direction_weight.hpp).
  objective.add_least_squares(w, a, weighted_ ? weighted_rows_ : a, reference_);
}

}  // namespace phri
