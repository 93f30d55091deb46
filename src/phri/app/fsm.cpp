#include <phri/app/fsm.hpp>

#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>

#include <algorithm>
#include <cmath>

namespace phri {
namespace {

void check_settings(const FsmSettings& s, int nv) {
  auto fail = [](const std::string& key, const std::string& reason) { throw ConfigError("FsmSettings", key, reason); };
  auto positive = [&](double v, const std::string& key) {
    if (!(v > 0.0) || !std::isfinite(v)) fail(key, "must be finite and > 0");
  };
  auto non_negative = [&](double v, const std::string& key) {
    if (!(v >= 0.0) || !std::isfinite(v)) fail(key, "must be finite and >= 0");
  };
  auto posture = [&](const std::vector<double>& q, const std::string& key) {
    if (static_cast<int>(q.size()) != nv) fail(key, "needs " + std::to_string(nv) + " values (one per joint)");
    for (double v : q) {
      if (!std::isfinite(v)) fail(key, "must be finite");
    }
  };
  posture(s.startup.home_q_rad, "startup.home_q_rad");
  posture(s.static_scenario.posture_q_rad, "static.posture_q_rad");
  positive(s.startup.max_joint_speed_rad_s, "startup.max_joint_speed_rad_s");
  non_negative(s.startup.min_duration_s, "startup.min_duration_s");
  positive(s.startup.tolerance_rad, "startup.tolerance_rad");
  non_negative(s.startup.timeout_s, "startup.timeout_s");
  positive(s.static_scenario.move_speed_m_s, "static.move_speed_m_s");
  positive(s.static_scenario.move_angular_speed_rad_s, "static.move_angular_speed_rad_s");
  positive(s.static_scenario.move_joint_speed_rad_s, "static.move_joint_speed_rad_s");
  non_negative(s.static_scenario.min_move_duration_s, "static.min_move_duration_s");
  const DynamicScenarioSettings& d = s.dynamic_scenario;
  non_negative(d.vertical_amplitude_m, "dynamic.vertical_amplitude_m");
  non_negative(d.vertical_angular_frequency_rad_s, "dynamic.vertical_angular_frequency_rad_s");
  non_negative(d.horizontal_speed_m_s, "dynamic.horizontal_speed_m_s");
  positive(d.horizontal_turn_acceleration_m_s2, "dynamic.horizontal_turn_acceleration_m_s2");
  non_negative(d.ramp_s, "dynamic.ramp_s");
  if (!(d.horizontal_min_offset_m <= 0.0 && d.horizontal_max_offset_m >= 0.0)) {
    fail("dynamic.horizontal_min_offset_m", "need horizontal_min_offset_m <= 0 <= horizontal_max_offset_m");
  }
  const double span = d.horizontal_max_offset_m - d.horizontal_min_offset_m;
  if (d.horizontal_speed_m_s * d.horizontal_speed_m_s > d.horizontal_turn_acceleration_m_s2 * span + 1e-12) {
    fail("dynamic.horizontal_speed_m_s", "the turns need a span >= speed^2 / turn acceleration");
  }
  positive(s.brake.linear_deceleration_m_s2, "brake.linear_deceleration_m_s2");
  positive(s.brake.angular_deceleration_rad_s2, "brake.angular_deceleration_rad_s2");
  positive(s.brake.joint_deceleration_rad_s2, "brake.joint_deceleration_rad_s2");
  positive(s.brake.min_duration_s, "brake.min_duration_s");
  if (!(s.stiffness_step >= 1.0) || !std::isfinite(s.stiffness_step)) fail("stiffness_step", "must be >= 1");
  positive(s.rest_speed_rad_s, "rest_speed_rad_s");
  if (s.torque_loop == LowLevelMode::kPosition) fail("torque_loop", "must be a torque loop");
  for (std::size_t i = 0; i < s.timeline.size(); ++i) {
    if (!(s.timeline[i].time_s >= 0.0) || !std::isfinite(s.timeline[i].time_s)) {
      fail("timeline[" + std::to_string(i) + "].at", "must be finite and >= 0");
    }
  }
}

Eigen::VectorXd to_vector(const std::vector<double>& v) {
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

}  // namespace

Fsm::Fsm(const FsmSettings& settings, const Controller& cycle)
    : settings_(settings),
      model_(cycle.model()),
      data_(model_),
      ee_frame_(cycle.end_effector_frame()),
      queue_(settings.queue_capacity),
      gain_queue_(settings.queue_capacity),
      target_queue_(settings.queue_capacity),
      targets_(model_.nv()),
      after_startup_(settings.first_scenario),
      torque_loop_(settings.torque_loop),
      startup_handover_(settings.torque_loop),
      joint_move_(model_),
      joint_brake_(model_.nv()),
      dynamic_(settings.dynamic_scenario) {
  const int nv = model_.nv();
  check_settings(settings_, nv);
  if (!cycle.settings().offered_loops.contains(settings_.torque_loop)) {
    throw ConfigError("FsmSettings", "torque_loop",
                      "'" + std::string(to_string(settings_.torque_loop)) + "' is not a loop the robot's drives offer (" +
                          cycle.settings().offered_loops.names() + ")");
  }
  std::stable_sort(settings_.timeline.begin(), settings_.timeline.end(),
                   [](const TimedEvent& a, const TimedEvent& b) { return a.time_s < b.time_s; });
  home_q_ = to_vector(settings_.startup.home_q_rad);
  static_q_ = to_vector(settings_.static_scenario.posture_q_rad);
  q_ref_ = Eigen::VectorXd::Zero(nv);
  qd_ref_ = Eigen::VectorXd::Zero(nv);
  qdd_ref_ = Eigen::VectorXd::Zero(nv);
  scratch_ = Eigen::VectorXd::Zero(nv);
  forward_kinematics(model_, data_, static_q_);
  update_frame_placements(model_, data_);
  static_pose_ = data_.frame_placements[static_cast<std::size_t>(ee_frame_)];
}

bool Fsm::post(Event event) noexcept {
  if (queue_.try_push(event)) return true;
  ++events_dropped_;
  return false;
}

bool Fsm::post(const GainRequest& request) noexcept {
  if (gain_queue_.try_push(request)) return true;
  ++events_dropped_;
  return false;
}

bool Fsm::post(const LiveTarget& target) noexcept {
  if (target_queue_.try_push(target)) return true;
  ++targets_refused_;
  return false;
}

// The latest queued target becomes the end effector's while a pose is held; a move, a brake, the
// dynamic scenario or the start-up own the reference, so a target then is refused.
void Fsm::take_targets() {
  bool any = false;
  LiveTarget latest;
  for (LiveTarget t; target_queue_.try_pop(t);) {
    if (any) ++targets_refused_;  // superseded in the same cycle
    latest = t;
    any = true;
  }
  if (!any) return;
  if ((state_ != FsmState::kStatic && state_ != FsmState::kStopped) || motion_ != Motion::kHold) {
    ++targets_refused_;
    return;
  }
  targets_.has_pose = true;
  targets_.pose.pose = Eigen::Isometry3d::Identity();
  targets_.pose.pose.linear() = latest.orientation.normalized().toRotationMatrix();
  targets_.pose.pose.translation() = latest.position;
  targets_.pose.velocity.setZero();
  targets_.pose.acceleration.setZero();
  ++targets_taken_;
}

double Fsm::joint_speed(const RobotState& state) const {
  return state.qd_rad_s.size() > 0 ? state.qd_rad_s.cwiseAbs().maxCoeff() : 0.0;
}

// The end-effector task's governed target as of the last cycle (a pose given this period has not
// passed through its reference governor yet): where a new move starts from.
const Eigen::Isometry3d& Fsm::pose_target(const Controller& cycle) const { return cycle.qp().end_effector().target_pose(); }

const Eigen::VectorXd& Fsm::posture_target(const Controller& cycle) const {
  return targets_.has_posture ? targets_.posture.q : cycle.qp().posture().target();
}

LowLevelMode Fsm::requested_loop(const Controller& cycle) const {
  return targets_.low_level_mode.value_or(cycle.low_level().requested());
}

double Fsm::stiffness_scale(const Controller& cycle) const {
  return targets_.stiffness_scale.value_or(cycle.compliance().stiffness_scale());
}

const ControllerTargets& Fsm::update(double t, const RobotState& state, const Controller& cycle) {
  last_event_ = -1;
  targets_.clear();
  // The cycle's first step takes the arm's pose as its targets; the FSM takes over after it.
  if (!cycle.started()) return targets_;
  if (!initialised_) {
    initialised_ = true;
    if (settings_.startup.enabled) {
      enter_startup(t, state);
    } else {
      startup_complete_ = true;
      targets_.low_level_mode = torque_loop_;
      enter(after_startup_ == Scenario::kStatic ? FsmState::kStatic : FsmState::kDynamic, t, cycle);
    }
  }
  while (next_timed_ < settings_.timeline.size() && settings_.timeline[next_timed_].time_s <= t) {
    handle(settings_.timeline[next_timed_++].event, t, state, cycle);
  }
  Event event;
  while (queue_.try_pop(event)) handle(event, t, state, cycle);
  for (GainRequest gain; gain_queue_.try_pop(gain);) apply(gain, targets_);

  if (state_ == FsmState::kStartup && motion_ == Motion::kHold) {
    joint_move_.difference(state.q_rad, home_q_, scratch_);
    if (scratch_.norm() < settings_.startup.tolerance_rad) {
      finish_startup(t, cycle, false);
    } else if (t - motion_start_ >= settings_.startup.timeout_s) {
      finish_startup(t, cycle, true);
    }
  }
  run_motion(t, cycle);
  take_targets();
  finished_ = stop_requested_ && state_ == FsmState::kStopped && !braking() &&
              joint_speed(state) < settings_.rest_speed_rad_s;
  return targets_;
}

// ------------------------------------------------------------------------------------ events
void Fsm::handle(Event event, double t, const RobotState& /*state*/, const Controller& cycle) {
  last_event_ = code(event);
  ++events_handled_;
  const bool starting = state_ == FsmState::kStartup && !startup_complete_;
  if (const auto mode = compliance_of(event)) {
    targets_.compliance_mode = *mode;
    return;
  }
  if (const auto loop = loop_of(event)) {
    // A loop the drives lack goes on to the controller, which rejects it (the cycle's status says
    // so); it never becomes the loop start-up or toggle_loop hands over to.
    if (!cycle.settings().offered_loops.contains(*loop)) {
      targets_.low_level_mode = *loop;
      return;
    }
    if (*loop != LowLevelMode::kPosition) torque_loop_ = *loop;
    if (starting) {
      startup_handover_ = *loop;  // the start-up move itself stays in Position
    } else {
      targets_.low_level_mode = *loop;
    }
    return;
  }
  switch (event) {
    case Event::kToggleLoop:
      if (starting) {
        startup_handover_ = startup_handover_ == LowLevelMode::kPosition ? torque_loop_ : LowLevelMode::kPosition;
      } else {
        targets_.low_level_mode = requested_loop(cycle) == LowLevelMode::kPosition ? torque_loop_ : LowLevelMode::kPosition;
      }
      return;
    case Event::kStaticScenario: request(FsmState::kStatic, t, cycle); return;
    case Event::kDynamicScenario: request(FsmState::kDynamic, t, cycle); return;
    case Event::kToggleScenario: {
      FsmState current = braking() ? pending_ : state_;
      if (starting) current = after_startup_ == Scenario::kStatic ? FsmState::kStatic : FsmState::kDynamic;
      request(current == FsmState::kDynamic ? FsmState::kStatic : FsmState::kDynamic, t, cycle);
      return;
    }
    case Event::kStopScenario: request(FsmState::kStopped, t, cycle); return;
    case Event::kStop:
      request(FsmState::kStopped, t, cycle);
      stop_requested_ = true;
      return;
    case Event::kStiffnessUp:
      targets_.stiffness_scale =
          ComplianceController::clamped_stiffness_scale(stiffness_scale(cycle) * settings_.stiffness_step);
      return;
    case Event::kStiffnessDown:
      targets_.stiffness_scale =
          ComplianceController::clamped_stiffness_scale(stiffness_scale(cycle) / settings_.stiffness_step);
      return;
    default: return;
  }
}

// A new state: at once when the reference rests, after a brake when it moves.
void Fsm::request(FsmState next, double t, const Controller& cycle) {
  if (stop_requested_) return;  // the session is over: only compliance and loop events still act
  if (state_ == FsmState::kStartup && !startup_complete_ && next != FsmState::kStopped) {
    after_startup_ = next == FsmState::kStatic ? Scenario::kStatic : Scenario::kDynamic;
    return;
  }
  if (braking()) {
    pending_ = next;
    return;
  }
  // Static again: back to the static pose (e.g. after dual compliance moved the end effector).
  if (next == state_ && next != FsmState::kStatic) return;
  pending_ = next;
  switch (motion_) {
    case Motion::kHold:
      enter(next, t, cycle);
      return;
    case Motion::kJointMove:
      joint_brake_.start(q_ref_, qd_ref_, qdd_ref_, settings_.brake);
      motion_ = Motion::kJointBrake;
      motion_start_ = t;
      return;
    case Motion::kPoseMove:
    case Motion::kTrajectory:
      pose_brake_.start(pose_ref_, settings_.brake);
      // The static move also moves the posture target: it brakes alongside.
      posture_braking_ = motion_ == Motion::kPoseMove;
      if (posture_braking_) joint_brake_.start(q_ref_, qd_ref_, qdd_ref_, settings_.brake);
      motion_ = Motion::kPoseBrake;
      motion_start_ = t;
      return;
    case Motion::kPoseBrake:
    case Motion::kJointBrake:
      return;  // handled above
  }
}

void Fsm::enter(FsmState next, double t, const Controller& cycle) {
  state_ = next;
  state_entry_time_ = t;
  motion_start_ = t;
  switch (next) {
    case FsmState::kStatic: {
      const StaticScenarioSettings& s = settings_.static_scenario;
      const Eigen::Isometry3d from = pose_target(cycle);
      q_ref_ = posture_target(cycle);
      pose_move_.start(from, static_pose_, s.move_speed_m_s, s.move_angular_speed_rad_s, s.min_move_duration_s);
      joint_move_.start(q_ref_, static_q_, s.move_joint_speed_rad_s, s.min_move_duration_s);
      // One duration for both, the longer.
      const double duration = std::max(pose_move_.duration(), joint_move_.duration());
      pose_move_.start(from, static_pose_, s.move_speed_m_s, s.move_angular_speed_rad_s, duration);
      joint_move_.start(q_ref_, static_q_, s.move_joint_speed_rad_s, duration);
      motion_ = Motion::kPoseMove;
      return;
    }
    case FsmState::kDynamic:
      dynamic_.start(pose_target(cycle));
      if (settings_.dynamic_scenario.compliance) targets_.compliance_mode = *settings_.dynamic_scenario.compliance;
      motion_ = Motion::kTrajectory;
      return;
    case FsmState::kStopped:
    case FsmState::kStartup:
      motion_ = Motion::kHold;  // the brake left the targets at rest
      return;
  }
}

void Fsm::enter_startup(double t, const RobotState& state) {
  state_ = FsmState::kStartup;
  state_entry_time_ = t;
  targets_.low_level_mode = LowLevelMode::kPosition;
  q_ref_ = state.q_rad;
  joint_move_.start(q_ref_, home_q_, settings_.startup.max_joint_speed_rad_s, settings_.startup.min_duration_s);
  motion_ = Motion::kJointMove;
  motion_start_ = t;
}

void Fsm::finish_startup(double t, const Controller& cycle, bool timed_out) {
  startup_complete_ = true;
  startup_timed_out_ = timed_out;
  targets_.low_level_mode = startup_handover_;
  enter(after_startup_ == Scenario::kStatic ? FsmState::kStatic : FsmState::kDynamic, t, cycle);
}

// ------------------------------------------------------------------------------------ references
void Fsm::stream_joint_reference() {
  set_posture_target();
  forward_kinematics(model_, data_, q_ref_, qd_ref_, qdd_ref_);
  update_frame_placements(model_, data_);
  pose_ref_.pose = data_.frame_placements[static_cast<std::size_t>(ee_frame_)];
  pose_ref_.velocity = frame_velocity(model_, data_, ee_frame_, ReferenceFrame::kLocalWorldAligned);
  pose_ref_.acceleration = frame_acceleration(model_, data_, ee_frame_, ReferenceFrame::kLocalWorldAligned);
  stream_pose_reference();
}

void Fsm::set_posture_target() {
  targets_.has_posture = true;
  targets_.posture.q = q_ref_;
  targets_.posture.qd = qd_ref_;
  targets_.posture.qdd = qdd_ref_;
}

void Fsm::stream_pose_reference() {
  targets_.has_pose = true;
  targets_.pose = pose_ref_;
}

// A move that is over leaves its last reference as the held target.
void Fsm::hold_when_done(double t, bool done) {
  if (!done) return;
  motion_ = Motion::kHold;
  motion_start_ = t;
}

void Fsm::run_motion(double t, const Controller& cycle) {
  const double elapsed = t - motion_start_;
  switch (motion_) {
    case Motion::kHold:
      return;
    case Motion::kJointMove:
      joint_move_.evaluate(elapsed, q_ref_, qd_ref_, qdd_ref_);
      stream_joint_reference();
      hold_when_done(t, elapsed >= joint_move_.duration());
      return;
    case Motion::kPoseMove:
      joint_move_.evaluate(elapsed, q_ref_, qd_ref_, qdd_ref_);
      set_posture_target();
      pose_move_.evaluate(elapsed, pose_ref_);
      stream_pose_reference();
      hold_when_done(t, elapsed >= pose_move_.duration());
      return;
    case Motion::kTrajectory:
      dynamic_.evaluate(elapsed, pose_ref_);
      stream_pose_reference();
      return;
    case Motion::kPoseBrake:
      pose_brake_.evaluate(elapsed, pose_ref_);
      stream_pose_reference();
      if (posture_braking_) {
        joint_brake_.evaluate(elapsed, q_ref_, qd_ref_, qdd_ref_);
        set_posture_target();
      }
      if (elapsed >= pose_brake_.duration() && (!posture_braking_ || elapsed >= joint_brake_.duration())) {
        posture_braking_ = false;
        motion_ = Motion::kHold;
        enter(pending_, t, cycle);
        run_motion(t, cycle);  // the next state's first reference in this same period
      }
      return;
    case Motion::kJointBrake:
      joint_brake_.evaluate(elapsed, q_ref_, qd_ref_, qdd_ref_);
      stream_joint_reference();
      if (elapsed >= joint_brake_.duration()) {
        motion_ = Motion::kHold;
        enter(pending_, t, cycle);
        run_motion(t, cycle);
      }
      return;
  }
}

}  // namespace phri
