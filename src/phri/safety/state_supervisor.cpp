#include <phri/safety/state_supervisor.hpp>

#include <phri/core/error.hpp>

#include <algorithm>
#include <cmath>

namespace phri {
namespace {
constexpr const char* kWhere = "SupervisorSettings";

int first_not_finite(const Eigen::VectorXd& v) {
  for (int i = 0; i < v.size(); ++i) {
    if (!std::isfinite(v[i])) return i;
  }
  return -1;
}

// First joint whose |value| exceeds factor * range (-1: none).
int first_beyond(const Eigen::VectorXd& v, const Eigen::VectorXd& range, double factor) {
  for (int i = 0; i < v.size(); ++i) {
    if (std::abs(v[i]) > factor * range[i]) return i;
  }
  return -1;
}

double median_of_three(double a, double b, double c) { return std::max(std::min(a, b), std::min(std::max(a, b), c)); }

bool identical(const Eigen::VectorXd& a, const Eigen::VectorXd& b) {
  return a.size() == b.size() && (a.array() == b.array()).all();
}

void check_settings(const SensorRanges& r, const SupervisorSettings& s) {
  const long n = r.velocity_limit.size();
  if (n == 0) throw ConfigError(kWhere, "velocity_limit", "no joints");
  for (const Eigen::VectorXd* v : {&r.q_lower, &r.q_upper, &r.torque_range, &r.current_range}) {
    if (v->size() != n) throw ConfigError(kWhere, "ranges", "one entry per joint needed in every range");
  }
  if (!((r.velocity_limit.array() > 0).all() && (r.torque_range.array() > 0).all() &&
        (r.current_range.array() > 0).all() && (r.q_lower.array() < r.q_upper.array()).all())) {
    throw ConfigError(kWhere, "ranges", "limits must be > 0 and lower < upper");
  }
  const long compared = r.torque_per_amp.size();
  for (const Eigen::VectorXd* v : {&r.torque_per_amp, &r.reflected_inertia, &r.friction_static, &r.friction_coulomb,
                                   &r.friction_viscous, &r.transmission_compliance}) {
    if (v->size() != compared || (compared != 0 && v->size() != n) || !v->allFinite() || !(v->array() >= 0).all()) {
      throw ConfigError(kWhere, "ranges",
                        "torque_per_amp, reflected_inertia, friction_*, transmission_compliance: none, or one finite value >= 0 per joint");
    }
  }
  if (!(s.torque_current_filter_s >= 0) || !(s.torque_current_friction_relative >= 0) || !(s.torque_current_moving_rad_s >= 0) || !(s.torque_current_relative >= 0) ||
      !(s.torque_current_margin_Nm > 0) || !(s.torque_current_inertia_relative >= 0) || !(s.motor_acceleration_clamp_rad_s2 >= 0) ||
      !std::isfinite(s.torque_current_filter_s + s.torque_current_friction_relative + s.torque_current_moving_rad_s + s.torque_current_relative +
                     s.torque_current_margin_Nm + s.motor_acceleration_clamp_rad_s2 + s.torque_current_inertia_relative)) {
    throw ConfigError(kWhere, "settings", "the torque-current tolerances must be finite (>= 0, margin > 0)");
  }
  if (!(s.period_s > 0) || !(s.position_margin_rad >= 0) || !(s.velocity_bound_factor >= 1) ||
      !(s.position_step_factor >= 1) || !(s.position_step_slack_rad >= 0) || !(s.velocity_consistency_rad_s > 0) || !(s.encoder_quantum_rad >= 0) || !(s.torque_range_factor >= 1) ||
      !(s.current_range_factor >= 1) || !(s.max_degraded_s >= s.period_s) || !(s.recovery_samples >= 1) ||
      !(s.max_fault_budget >= 1) || !(s.fault_budget_decay_per_good >= 0) || !(s.frozen_s >= 0) ||
      !(s.frozen_command_samples >= 2) || !(s.frozen_command_Nm > 0) || !std::isfinite(s.frozen_command_Nm)) {
    throw ConfigError(kWhere, "settings", "a bound is out of range (factors >= 1, times >= the period)");
  }
}
}  // namespace

StateSupervisor::StateSupervisor(const SensorRanges& ranges, const SupervisorSettings& settings)
    : ranges_(ranges), settings_(settings), n_(static_cast<int>(ranges.velocity_limit.size())) {
  check_settings(ranges_, settings_);
  last_good_ = RobotState(n_);
  previous_ = RobotState(n_);
  candidate_q_ = candidate_qd_ = kinematic_q_ = kinematic_qd_ = Eigen::VectorXd::Zero(n_);
  torque_command_ = freeze_command_ = Eigen::VectorXd::Zero(n_);
  for (ResidualTrack& track : residual_track_) track.resize(n_);
  residual_qd_ = Eigen::VectorXd::Zero(n_);
  residual_tau_[0] = residual_tau_[1] = Eigen::VectorXd::Zero(n_);
}

void StateSupervisor::ResidualTrack::resize(int n) {
  filtered = acceleration_size = raw[0] = raw[1] = Eigen::VectorXd::Zero(n);
}

double StateSupervisor::ResidualTrack::update(int i, double residual, double acceleration, double alpha, bool started) {
  // Median of the last three raw residuals: an impact (a hard stop, a step push, the drive's first
  // command) aliases into one or two samples of ~100 N.m between a 1 kHz q̈ and the sensor's
  // instant; a fault persists. The filter starts at the third sample, when the median and τ̈_s (the
  // elastic hypothesis) are both known.
  const double m = median_of_three(residual, raw[0][i], raw[1][i]);
  raw[1][i] = raw[0][i];
  raw[0][i] = residual;
  if (!started) return filtered[i];
  filtered[i] += alpha * (m - filtered[i]);
  acceleration_size[i] += alpha * (std::abs(acceleration) - acceleration_size[i]);
  return filtered[i];
}

void StateSupervisor::reset() {
  state_ = SupervisorState::kNormal;
  has_good_ = has_previous_ = has_sequence_ = has_seen_ = has_candidate_ = has_kinematics_ = false;
  kinematics_fresh_ = resync_ = false;
  escalation_ = SafetyTransition{};
  frozen_since_s_ = -1.0;
  frozen_samples_ = 0;
  has_torque_command_ = freeze_command_known_ = false;
  residual_updates_ = 0;
  good_in_row_ = bad_in_row_ = 0;
  fault_budget_ = 0.0;
  sample_fault_ = SafetyFault::kNone;
  sample_fault_joint_ = -1;
}

// The sample's sequence and stamp against a reference's (kNone: it follows on from it).
SafetyFault StateSupervisor::freshness_against(const RobotState& s, std::uint32_t sequence, double stamp,
                                               bool stamp_known) const {
  const auto advance = static_cast<std::int32_t>(s.joints.sequence - sequence);
  if (advance <= 0) return SafetyFault::kStale;
  const long max_advance = static_cast<long>(std::ceil(settings_.max_degraded_s / settings_.period_s)) + 1;
  if (advance > max_advance) return SafetyFault::kStampJump;  // a jumping sequence: frames lost or garbage
  if (!stamp_known) return SafetyFault::kNone;
  const double dt = s.joints.stamp_s - stamp;
  if (!(dt > 0.0)) return dt == 0.0 ? SafetyFault::kStampFrozen : SafetyFault::kStampJump;
  if (dt > settings_.max_degraded_s + static_cast<double>(advance) * settings_.period_s) return SafetyFault::kStampJump;
  return SafetyFault::kNone;
}

// Fresh against the reference; else, a sample that follows on from the last one whose counter or
// stamp jumped re-synchronises (a gap, or a counter that restarted, is not invalid for ever).
SafetyFault StateSupervisor::check_freshness(const RobotState& s) {
  resync_ = false;
  if (has_seen_ && s.joints.sequence == seen_sequence_) return SafetyFault::kStale;  // the same frame again
  if (!has_sequence_) return SafetyFault::kNone;
  const SafetyFault fault = freshness_against(s, last_sequence_, last_stamp_, has_good_);
  if (fault == SafetyFault::kNone) return fault;
  if (has_candidate_ && freshness_against(s, candidate_sequence_, candidate_stamp_, true) == SafetyFault::kNone) {
    resync_ = true;
    return SafetyFault::kNone;
  }
  return fault;
}

void StateSupervisor::keep_candidate(const RobotState& s) {
  candidate_sequence_ = s.joints.sequence;
  candidate_stamp_ = s.joints.stamp_s;
  candidate_q_ = s.q_rad;
  candidate_qd_ = s.qd_rad_s;
  has_candidate_ = true;
}

// q and q̇ within range, and consistent with the last plausible kinematics (after a re-sync: with
// the sample it follows on from); `joint` names the first culprit.
SafetyFault StateSupervisor::check_kinematics(const RobotState& s, int& joint) const {
  const SupervisorSettings& c = settings_;
  const bool compare = resync_ || has_kinematics_;
  const Eigen::VectorXd& q_ref = resync_ ? candidate_q_ : kinematic_q_;
  const Eigen::VectorXd& qd_ref = resync_ ? candidate_qd_ : kinematic_qd_;
  const double stamp_ref = resync_ ? candidate_stamp_ : kinematic_stamp_;
  for (int i = 0; i < n_; ++i) {
    joint = i;
    const double q = s.q_rad[i];
    if (q < ranges_.q_lower[i] - c.position_margin_rad || q > ranges_.q_upper[i] + c.position_margin_rad) {
      return SafetyFault::kPositionRange;
    }
    const double v_limit = ranges_.velocity_limit[i];
    if (std::abs(s.qd_rad_s[i]) > c.velocity_bound_factor * v_limit) return SafetyFault::kVelocityRange;
    if (compare) {
      const double dt = std::max(s.joints.stamp_s - stamp_ref, c.period_s);
      const double step = std::abs(q - q_ref[i]);
      if (step > c.position_step_factor * v_limit * dt + c.position_step_slack_rad) return SafetyFault::kPositionJump;
      // q̇ must agree with the position's own rate: over the gap since the reference the mean
      // velocity is (q̇ + q̇_ref) / 2 at constant acceleration. A q̇ offset or spike within range
      // would otherwise make the controller brake against a phantom motion.
      const double mean_qd = 0.5 * (s.qd_rad_s[i] + qd_ref[i]);
      if (std::abs(mean_qd - (q - q_ref[i]) / dt) > c.velocity_consistency_rad_s + 2.0 * c.encoder_quantum_rad / dt) {
        return SafetyFault::kVelocityMismatch;
      }
      // A position that did not change by a single bit while q̇ says the joint moved more than two
      // encoder quanta: the reading is stuck (within the tolerance above, it would pass for
      // frozen_s while the arm moves on). Moved: the same way at both ends, at least the slower
      // end's speed; a joint that stopped or turned back within a gap may be back on the same count.
      const double surely_moved = s.qd_rad_s[i] * qd_ref[i] > 0.0 ? std::min(std::abs(s.qd_rad_s[i]), std::abs(qd_ref[i])) : 0.0;
      if (q == q_ref[i] && surely_moved * dt > 2.0 * c.encoder_quantum_rad) return SafetyFault::kFrozenValues;
    }
  }
  joint = -1;
  return SafetyFault::kNone;
}

// τ_s and the current within what the drives can produce.
SafetyFault StateSupervisor::check_drive_ranges(const RobotState& s, int& joint) const {
  const SupervisorSettings& c = settings_;
  if ((joint = first_beyond(s.tau_sensor_Nm, ranges_.torque_range, c.torque_range_factor)) >= 0) {
    return SafetyFault::kTorqueRange;
  }
  if (s.current.valid && (joint = first_beyond(s.current_A, ranges_.current_range, c.current_range_factor)) >= 0) {
    return SafetyFault::kCurrentRange;
  }
  joint = -1;
  return SafetyFault::kNone;
}

// The joint part first (its verdict feeds the brake's kinematics), then torque and current.
SafetyFault StateSupervisor::classify(const RobotState& s, int& joint) {
  joint = -1;
  kinematics_passed_ = header_passed_ = false;
  if (s.q_rad.size() != n_ || s.qd_rad_s.size() != n_) return SafetyFault::kSize;
  if (s.fault) return SafetyFault::kRobotFault;
  if (!s.joints.valid) return SafetyFault::kInvalid;
  for (const Eigen::VectorXd* v : {&s.q_rad, &s.qd_rad_s}) {
    if ((joint = first_not_finite(*v)) >= 0) return SafetyFault::kNotFinite;
  }
  if (!std::isfinite(s.joints.stamp_s)) return SafetyFault::kStampJump;
  const SafetyFault fresh = check_freshness(s);
  if (fresh != SafetyFault::kNone) {
    if (fresh != SafetyFault::kStale || s.joints.sequence != last_sequence_) keep_candidate(s);
    return fresh;
  }
  header_passed_ = true;
  const SafetyFault kinematic = check_kinematics(s, joint);
  if (kinematic != SafetyFault::kNone) return kinematic;
  kinematics_passed_ = true;
  // A torque or current vector of the wrong size spoils only its own part: the joints still feed
  // the brake (a stop on stale joints coasts a prediction the servo then yanks the arm to).
  if (s.tau_sensor_Nm.size() != n_ || (s.current.valid && s.current_A.size() != n_)) return SafetyFault::kSize;
  if (!s.torque.valid) return SafetyFault::kInvalid;
  if ((joint = first_not_finite(s.tau_sensor_Nm)) >= 0) return SafetyFault::kNotFinite;
  if (s.current.valid && (joint = first_not_finite(s.current_A)) >= 0) return SafetyFault::kNotFinite;
  return check_drive_ranges(s, joint);
}

// Real sensors carry noise: q̇, τ_s and the current bit-identical for frozen_s while the sequence
// advances means the values are not being updated.
bool StateSupervisor::frozen(const RobotState& s) {
  if (settings_.frozen_s <= 0.0) return false;
  const bool same = has_previous_ && identical(s.qd_rad_s, previous_.qd_rad_s) &&
                    identical(s.tau_sensor_Nm, previous_.tau_sensor_Nm) &&
                    (!s.current.valid || identical(s.current_A, previous_.current_A));
  if (!same) {
    frozen_since_s_ = -1.0;
    frozen_samples_ = 0;
    return false;
  }
  if (frozen_since_s_ < 0.0) {
    frozen_since_s_ = s.joints.stamp_s;
    freeze_stamp_ = previous_stamp_;
    freeze_sequence_ = previous_sequence_;
    freeze_command_known_ = has_torque_command_;
    if (has_torque_command_) freeze_command_ = torque_command_;
  }
  ++frozen_samples_;
  const bool command_moved = freeze_command_known_ && has_torque_command_ &&
                             frozen_samples_ >= settings_.frozen_command_samples &&
                             (torque_command_ - freeze_command_).cwiseAbs().maxCoeff() > settings_.frozen_command_Nm;
  return command_moved || s.joints.stamp_s - frozen_since_s_ >= settings_.frozen_s;
}

void StateSupervisor::note_command(const RobotCommand& command) {
  switch (command.mode) {
    case LowLevelMode::kKinovaTorque:
    case LowLevelMode::kKinovaTorqueHighVelocity:
    case LowLevelMode::kTorque:
      has_torque_command_ = command.tau_Nm.size() == n_ && command.tau_Nm.allFinite();
      if (has_torque_command_) torque_command_ = command.tau_Nm;
      return;
    case LowLevelMode::kCurrent:
      has_torque_command_ = command.current_A.size() == n_ && ranges_.torque_per_amp.size() == n_ && command.current_A.allFinite();
      if (has_torque_command_) torque_command_ = command.current_A.cwiseProduct(ranges_.torque_per_amp);
      return;
    case LowLevelMode::kPosition: has_torque_command_ = false; return;
  }
}

// The first joint whose τ_s the motor current cannot explain (-1: none, or nothing to compare).
// Runs on samples that passed every other check; the residual's filter advances on each of them,
// also while it flags, so that it recovers when the fault ends.
int StateSupervisor::first_torque_current_mismatch(const RobotState& s) {
  if (ranges_.torque_per_amp.size() != n_ || !s.current.valid) return -1;
  const SupervisorSettings& c = settings_;
  // q̈, τ̈_s and the filter's step from the last samples that came this far (not only good ones).
  double dt = std::max(s.joints.stamp_s - residual_stamp_s_, c.period_s);
  if (residual_updates_ > 0 && dt > c.max_degraded_s) residual_updates_ = 0;  // a gap: start again
  // The filter starts from zero: a push at the first sample is not a fault, an offset soon is.
  if (residual_updates_ == 0) {
    dt = c.period_s;
    for (ResidualTrack& track : residual_track_) {
      track.filtered.setZero();
      track.acceleration_size.setZero();
    }
  }
  const double alpha = dt / (c.torque_current_filter_s + dt);
  const double clamp = c.motor_acceleration_clamp_rad_s2;
  int culprit = -1;
  for (int i = 0; i < n_; ++i) {
    const double motor = ranges_.torque_per_amp[i] * s.current_A[i];
    // The rotor's acceleration, rigid and with the transmission's deflection τ_s / K.
    double rigid = 0.0, elastic = 0.0;
    if (residual_updates_ >= 1) rigid = elastic = (s.qd_rad_s[i] - residual_qd_[i]) / dt;
    if (residual_updates_ >= 2) {
      const double tau_dd = (s.tau_sensor_Nm[i] - 2.0 * residual_tau_[0][i] + residual_tau_[1][i]) / (dt * dt);
      elastic += ranges_.transmission_compliance[i] * tau_dd;
    }
    const double acceleration[2] = {std::clamp(rigid, -clamp, clamp), std::clamp(elastic, -clamp, clamp)};
    // Kinetic friction as modelled while the joint moves; stiction (unknown sign) in the tolerance.
    const double speed = std::abs(s.qd_rad_s[i]);
    const double kinetic = speed > c.torque_current_moving_rad_s
                               ? std::copysign(ranges_.friction_coulomb[i] + ranges_.friction_viscous[i] * speed, s.qd_rad_s[i])
                               : 0.0;
    const double base_tolerance = ranges_.friction_static[i] + c.torque_current_friction_relative * std::abs(kinetic) +
                                  c.torque_current_relative * std::min(std::abs(s.tau_sensor_Nm[i]), std::abs(motor)) +
                                  c.torque_current_margin_Nm;
    // A mismatch under both hypotheses with one sign: no compliance in between explains it either.
    double excess[2];
    for (int h = 0; h < 2; ++h) {
      const double residual = motor - s.tau_sensor_Nm[i] - ranges_.reflected_inertia[i] * acceleration[h] - kinetic;
      const double filtered = residual_track_[h].update(i, residual, acceleration[h], alpha, residual_updates_ >= 2);
      const double tolerance =
          base_tolerance + c.torque_current_inertia_relative * ranges_.reflected_inertia[i] * residual_track_[h].acceleration_size[i];
      excess[h] = std::abs(filtered) > tolerance ? filtered : 0.0;
    }
    if (culprit < 0 && ranges_.torque_per_amp[i] > 0.0 && excess[0] * excess[1] > 0.0) culprit = i;
  }
  residual_qd_ = s.qd_rad_s;
  residual_tau_[1] = residual_tau_[0];
  residual_tau_[0] = s.tau_sensor_Nm;
  residual_stamp_s_ = s.joints.stamp_s;
  residual_updates_ = std::min(residual_updates_ + 1, 2);
  return culprit;
}

bool StateSupervisor::check(const RobotState& s) {
  int joint = -1;
  SafetyFault fault = classify(s, joint);
  if (fault == SafetyFault::kNone && (joint = first_torque_current_mismatch(s)) >= 0) {
    fault = SafetyFault::kTorqueCurrentMismatch;
  }
  if (s.q_rad.size() == n_ && s.qd_rad_s.size() == n_ && s.tau_sensor_Nm.size() == n_) {
    if (fault == SafetyFault::kNone && frozen(s)) fault = SafetyFault::kFrozenValues;
    if (fault != SafetyFault::kStale) {
      // Sizes equal: these copies allocate nothing (the current only when it has the right size).
      previous_.qd_rad_s = s.qd_rad_s;
      previous_.tau_sensor_Nm = s.tau_sensor_Nm;
      if (s.current_A.size() == n_) previous_.current_A = s.current_A;
      if (frozen_since_s_ < 0.0) {  // during a freeze previous_ stands for its first, live sample
        previous_stamp_ = s.joints.stamp_s;
        previous_sequence_ = s.joints.sequence;
      }
      has_previous_ = true;
    }
  }
  if (fault != SafetyFault::kSize) {
    seen_sequence_ = s.joints.sequence;
    has_seen_ = true;
  }
  // The reference moves to every sample whose sequence and stamp passed.
  if (header_passed_) {
    last_sequence_ = s.joints.sequence;
    last_stamp_ = s.joints.stamp_s;
    has_sequence_ = true;
    if (resync_) {
      ++resyncs_;
      has_candidate_ = false;
    }
  }
  kinematics_fresh_ = kinematics_passed_ && fault != SafetyFault::kFrozenValues;
  if (fault == SafetyFault::kFrozenValues && frozen_since_s_ >= 0.0 && has_kinematics_) {
    // The samples since the freeze began only repeated its first: the kinematics are that old.
    kinematic_stamp_ = freeze_stamp_;
    kinematic_sequence_ = freeze_sequence_;
  }
  if (kinematics_fresh_) {
    if (fault == SafetyFault::kNone) check_gap(s);
    kinematic_q_ = s.q_rad;
    kinematic_qd_ = s.qd_rad_s;
    kinematic_stamp_ = s.joints.stamp_s;
    kinematic_sequence_ = s.joints.sequence;
    has_kinematics_ = true;
  }
  if (fault == SafetyFault::kNone) {
    accept(s);
    // A good sample from a robot that asks to stop: the safe stop brakes on it (the link still works).
    if (s.stop_requested) report(SafetyFault::kRobotStopRequest, s.time_s);
    return true;
  }
  reject(s, fault, joint);
  return false;
}

// A good sample after a gap longer than the degraded budget, in both the sequence and the stamps
// (the control thread stalled, frames were lost): the robot ran that long on its last command.
void StateSupervisor::check_gap(const RobotState& s) {
  if (!has_good_) return;
  const double by_sequence =
      static_cast<double>(static_cast<std::uint32_t>(s.joints.sequence - last_good_.joints.sequence)) * settings_.period_s;
  const double gap = std::min(s.joints.stamp_s - last_good_.joints.stamp_s, by_sequence);
  if (gap > settings_.max_degraded_s + 0.5 * settings_.period_s) report(SafetyFault::kDegradedTooLong, s.time_s);
}

void StateSupervisor::accept(const RobotState& s) {
  last_good_.time_s = s.time_s;
  last_good_.cycle = s.cycle;
  last_good_.mode = s.mode;
  last_good_.q_rad = s.q_rad;
  last_good_.qd_rad_s = s.qd_rad_s;
  last_good_.tau_sensor_Nm = s.tau_sensor_Nm;
  if (s.current.valid) last_good_.current_A = s.current_A;
  last_good_.wrench_sensor = s.wrench_sensor;
  last_good_.joints = s.joints;
  last_good_.torque = s.torque;
  last_good_.current = s.current;
  last_good_.wrench = s.wrench;
  has_good_ = true;
  sample_fault_ = SafetyFault::kNone;
  sample_fault_joint_ = -1;
  bad_in_row_ = 0;
  fault_budget_ = std::max(0.0, fault_budget_ - settings_.fault_budget_decay_per_good);
  if (state_ == SupervisorState::kDegraded && ++good_in_row_ >= settings_.recovery_samples) {
    transition(SupervisorState::kNormal, SafetyFault::kNone, -1, s.time_s);
  }
}

void StateSupervisor::reject(const RobotState& s, SafetyFault fault, int joint) {
  ++implausible_;
  sample_fault_ = fault;
  sample_fault_joint_ = joint;
  good_in_row_ = 0;
  fault_budget_ += 1.0;
  // Robot time of this cycle: the sample's if it is believable, else the last good one's.
  const double t = std::isfinite(s.time_s) && s.time_s >= last_good_.time_s ? s.time_s : last_good_.time_s;
  if (state_ == SupervisorState::kSafeStop) return;
  // The robot itself stopped obeying; or τ_s and the current disagree over the residual's filter
  // time: a persistent fault, and holding the previous torque command would repeat the phantom
  // push it cancelled.
  if (fault == SafetyFault::kRobotFault || fault == SafetyFault::kTorqueCurrentMismatch) {
    transition(SupervisorState::kSafeStop, fault, joint, t);
    return;
  }
  if (state_ == SupervisorState::kNormal) transition(SupervisorState::kDegraded, fault, joint, t);
  // Cycles in a row without a usable sample (the stamps may be the fault, so cycles, not time).
  ++bad_in_row_;
  if (static_cast<double>(bad_in_row_) * settings_.period_s > settings_.max_degraded_s) {
    transition(SupervisorState::kSafeStop, fault, joint, t);
  } else if (fault_budget_ > settings_.max_fault_budget) {
    transition(SupervisorState::kSafeStop, SafetyFault::kTooManyFaults, joint, t);
  }
}

void StateSupervisor::report(SafetyFault fault, double t, int joint) {
  if (state_ == SupervisorState::kSafeStop) {
    if (fault == SafetyFault::kHoldRefused && escalation_.reason == SafetyFault::kNone) {
      escalation_ = SafetyTransition{t, state_, state_, fault, joint};
    }
    return;
  }
  transition(SupervisorState::kSafeStop, fault, joint, t);
}

void StateSupervisor::transition(SupervisorState to, SafetyFault reason, int joint, double t) {
  if (to == state_) return;
  last_transition_ = SafetyTransition{t, state_, to, reason, joint};
  if (to == SupervisorState::kSafeStop) safe_stop_transition_ = last_transition_;
  state_ = to;
  good_in_row_ = 0;
  ++transitions_;
}

}  // namespace phri
