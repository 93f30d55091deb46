#include <phri/experiments/safety_fuzz_metrics.hpp>

#include <phri/model/algorithms.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

namespace phri {

std::string_view violation_name(int index) {
  static constexpr std::array<std::string_view, kFuzzViolationCount> kNames = {
      "joint_limit", "overspeed", "collision", "nan_command", "crash", "unhandled_refusal", "refused_write",
      "no_recovery", "safe_stop_moving"};
  return index >= 0 && index < kFuzzViolationCount ? kNames[static_cast<std::size_t>(index)] : "unknown";
}

double required_torque_ratio(const Eigen::VectorXd& gravity, const Eigen::VectorXd& push_torque,
                             const Eigen::VectorXd& torque_limit) {
  double ratio = 0.0;
  for (Eigen::Index i = 0; i < gravity.size(); ++i) {
    ratio = std::max(ratio, std::abs(gravity[i] - push_torque[i]) / torque_limit[i]);
  }
  return ratio;
}

FuzzVerdict classify(const WindowMetrics& m, const SafetyFuzzThresholds& t) {
  FuzzVerdict v;
  if (m.min_limit_margin_rad < 0.0) v.violations |= kViolationJointLimit;
  if (m.max_speed_ratio > t.speed_factor) v.violations |= kViolationOverspeed;
  if (m.min_capsule_distance_m < t.collision_distance_m) v.violations |= kViolationCollision;
  if (m.nan_command) v.violations |= kViolationNanCommand;
  if (m.crashed) v.violations |= kViolationCrash;
  if (m.unhandled_refusals > 0) v.violations |= kViolationUnhandledRefusal;
  if (m.refused_writes > 0) v.violations |= kViolationRefusedWrite;
  // A crash cut the window short: whether the arm would have recovered is unknown.
  if (!m.crashed && !m.safe_stop && m.recovery_time_s < 0.0) v.violations |= kViolationNoRecovery;
  if (!m.crashed && m.safe_stop && m.safe_stop_rest_time_s < 0.0) v.violations |= kViolationSafeStopMoving;
  v.operator_possible = m.max_required_torque_ratio > 1.0;
  v.held_command = v.violations == kViolationOverspeed && m.max_held_speed_ratio > t.speed_factor &&
                   m.max_controlled_speed_ratio <= t.speed_factor && m.max_inherited_speed_ratio <= m.max_held_speed_ratio;
  v.invalid = m.off_intent_cycles > 0;
  return v;
}

SafetyMonitor::SafetyMonitor(const Model& model, const CollisionModel* collision, const Eigen::VectorXd& velocity_limit,
                             const Eigen::VectorXd& torque_limit)
    : model_(model),
      collision_(collision),
      data_(model),
      collision_data_(collision != nullptr ? CollisionData(model, *collision) : CollisionData(model, CollisionModel())),
      velocity_limit_(velocity_limit),
      torque_limit_(torque_limit),
      lower_(model.lower_limits()),
      upper_(model.upper_limits()),
      push_torque_(Eigen::VectorXd::Zero(model.nv())),
      q_(Eigen::VectorXd::Zero(model.nq())),
      jacobian_(Eigen::MatrixXd::Zero(3, model.nv())) {
  for (int i = 0; i < model.nq(); ++i) {
    if (!model.joint(i).has_position_limits()) {
      lower_[i] = -std::numeric_limits<double>::infinity();
      upper_[i] = std::numeric_limits<double>::infinity();
    }
  }
}

void SafetyMonitor::update(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, WindowMetrics& m) {
  q_ = q;
  speed_ratio_ = 0.0;
  limit_margin_ = std::numeric_limits<double>::infinity();
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    speed_ratio_ = std::max(speed_ratio_, std::abs(qd[i]) / velocity_limit_[i]);
    if (std::isfinite(lower_[i])) limit_margin_ = std::min({limit_margin_, q[i] - lower_[i], upper_[i] - q[i]});
  }
  forward_kinematics(model_, data_, q_);
  capsule_distance_ = std::numeric_limits<double>::infinity();
  if (collision_ != nullptr && collision_->num_pairs() > 0) {
    compute_collision_distances(model_, data_, *collision_, collision_data_, false);
    capsule_distance_ = collision_data_.distance.minCoeff();
  }
  m.max_speed_ratio = std::max(m.max_speed_ratio, speed_ratio_);
  m.min_limit_margin_rad = std::min(m.min_limit_margin_rad, limit_margin_);
  m.min_capsule_distance_m = std::min(m.min_capsule_distance_m, capsule_distance_);
}

double SafetyMonitor::deviation(const Eigen::VectorXd& q, const Eigen::Ref<const Eigen::VectorXd>& reference,
                                int& joint) const {
  double worst = 0.0;
  joint = -1;
  for (Eigen::Index i = 0; i < q.size(); ++i) {
    double d = q[i] - reference[i];
    if (!model_.joint(static_cast<int>(i)).has_position_limits()) d = std::remainder(d, 2.0 * std::numbers::pi);
    if (!(std::abs(d) <= worst)) {  // NaN counts as the worst
      worst = std::abs(d);
      joint = static_cast<int>(i);
    }
  }
  return worst;
}

double SafetyMonitor::push_torque_ratio(int body, const Eigen::Vector3d& point_local, const Eigen::Vector3d& force_N,
                                        bool local_frame, WindowMetrics& m) {
  const Eigen::Isometry3d& placement = data_.body_placements[static_cast<std::size_t>(body)];
  const Eigen::Vector3d point = placement * point_local;
  const Eigen::Vector3d force = local_frame ? Eigen::Vector3d(placement.linear() * force_N) : force_N;
  body_point_linear_jacobian(model_, data_, body, point, jacobian_);
  push_torque_.noalias() = jacobian_.transpose() * force;
  const Eigen::VectorXd& gravity = compute_gravity(model_, data_, q_);
  const double ratio = required_torque_ratio(gravity, push_torque_, torque_limit_);
  m.max_required_torque_ratio = std::max(m.max_required_torque_ratio, ratio);
  return ratio;
}

void HeldCommandTracker::sample(double speed_ratio, bool held, WindowMetrics& m) {
  if (held) {
    m.max_held_speed_ratio = std::max(m.max_held_speed_ratio, speed_ratio);
    inheriting_ = speed_ratio > speed_factor_;
  } else if (inheriting_ && speed_ratio > speed_factor_) {
    m.max_inherited_speed_ratio = std::max(m.max_inherited_speed_ratio, speed_ratio);
  } else {
    inheriting_ = false;
    m.max_controlled_speed_ratio = std::max(m.max_controlled_speed_ratio, speed_ratio);
  }
}

RecoveryTracker::RecoveryTracker(const SafetyFuzzThresholds& thresholds, double end_time_s, double min_observation_s)
    : t_(thresholds), end_(end_time_s), min_observation_(min_observation_s) {}

void RecoveryTracker::sample(double t, double deviation, double speed, double safe_stop_time_s) {
  if (done_) return;
  if (safe_stop_time_s >= 0.0) {
    // A latched safe stop decides the window: at rest in time, or not.
    safe_stop_time_ = safe_stop_time_s;
    if (rest_after_ < 0.0 && speed < t_.rest_speed_rad_s) rest_after_ = t - safe_stop_time_s;
    done_ = rest_after_ >= 0.0 || t - safe_stop_time_s > t_.safe_stop_rest_time_s;
    return;
  }
  if (t < end_) return;
  const double since = t - end_;
  if (deviation < t_.recovery_tolerance_rad) {
    if (recovered_at_ < 0.0) recovered_at_ = since;
  } else {
    recovered_at_ = -1.0;  // left the tolerance again: not back yet
  }
  if (std::isfinite(deviation)) allowed_s_ = std::max(allowed_s_, t_.recovery_time_s + deviation / t_.return_speed_rad_s);
  const bool settled = speed < t_.settle_speed_rad_s;
  done_ = (recovered_at_ >= 0.0 && settled && since >= min_observation_) || since >= std::max(allowed_s_, t_.recovery_time_s);
}

void RecoveryTracker::allow_walk_back(double t, double rest_distance_rad) {
  if (done_ || walk_back_allowed_ || t < end_ || !std::isfinite(rest_distance_rad)) return;
  walk_back_allowed_ = true;
  allowed_s_ = std::max(allowed_s_, (t - end_) + t_.recovery_time_s + rest_distance_rad / t_.return_speed_rad_s);
}

void RecoveryTracker::finish(WindowMetrics& m) const {
  m.recovery_time_s = recovered_at_;
  m.safe_stop = safe_stop_time_ >= 0.0;
  m.safe_stop_time_s = safe_stop_time_;
  m.safe_stop_rest_time_s = rest_after_;
}

}  // namespace phri
