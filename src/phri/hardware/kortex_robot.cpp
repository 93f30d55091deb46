#include <phri/hardware/kortex_robot.hpp>

#include <phri/hardware/kortex_units.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <utility>

namespace phri {

KortexRobotSettings kortex_robot_settings(const RobotDescription& robot, double period_s) {
  KortexRobotSettings s;
  s.dof = robot.dof();
  s.period_s = period_s;
  s.torque_per_amp_Nm_per_A.resize(s.dof);
  for (int i = 0; i < s.dof; ++i) s.torque_per_amp_Nm_per_A[i] = robot.actuators[i].torque_per_amp();
  const std::vector<double>& home = robot.initial_q_rad;
  if (static_cast<int>(home.size()) == s.dof) s.reference_q_rad = Eigen::Map<const Eigen::VectorXd>(home.data(), s.dof);
  return s;
}
namespace {

bool all_finite(const Eigen::VectorXd& v) { return v.allFinite(); }

std::string format_line(const char* format, auto... values) {
  char text[256];
  std::snprintf(text, sizeof text, format, values...);
  return text;
}

}  // namespace

kortex::ControlMode KortexRobot::control_mode_for(LowLevelMode mode) {
  switch (mode) {
    case LowLevelMode::kPosition: return kortex::ControlMode::kPosition;
    case LowLevelMode::kKinovaTorque: return kortex::ControlMode::kTorque;
    case LowLevelMode::kKinovaTorqueHighVelocity: return kortex::ControlMode::kTorqueHighVelocity;
    case LowLevelMode::kCurrent: return kortex::ControlMode::kCurrent;
    case LowLevelMode::kTorque: break;  // a generic drive's plain torque: no Kortex mode
  }
  return kortex::ControlMode::kNone;
}

KortexRobot::KortexRobot(KortexClient& client, KortexRobotSettings settings)
    : client_(client), settings_(std::move(settings)), n_(settings_.dof) {
  check_settings();
  const double inf = std::numeric_limits<double>::infinity();
  lower_ = settings_.position_lower_rad.size() == n_ ? settings_.position_lower_rad : Eigen::VectorXd::Constant(n_, -inf);
  upper_ = settings_.position_upper_rad.size() == n_ ? settings_.position_upper_rad : Eigen::VectorXd::Constant(n_, inf);
  torque_per_amp_ = settings_.torque_per_amp_Nm_per_A;
  reference_ = settings_.reference_q_rad.size() == n_ ? settings_.reference_q_rad : Eigen::VectorXd::Zero(n_);
  command_.actuators.assign(static_cast<std::size_t>(n_), kortex::ActuatorCommand{});
  feedback_.actuators.assign(static_cast<std::size_t>(n_), kortex::ActuatorFeedback{});
  for (auto* bank : {&health_.fault_bank_a, &health_.fault_bank_b, &health_.warning_bank_a, &health_.warning_bank_b}) {
    bank->assign(static_cast<std::size_t>(n_), 0u);
  }
  state_ = RobotState(n_);
  const long window = std::max(1L, std::lround(settings_.loss_window_s / settings_.period_s));
  loss_ring_.assign(static_cast<std::size_t>(window), 0u);
  max_losses_ = static_cast<int>(std::floor(settings_.max_loss_fraction * static_cast<double>(window) + 1e-9));
  start_up();
}

KortexRobot::~KortexRobot() { shutdown(); }

void KortexRobot::check_settings() const {
  const std::string subject = "KortexRobotSettings";
  if (n_ < 1) throw ConfigError(subject, "dof", "must be at least 1");
  if (!(settings_.period_s > 0.0)) throw ConfigError(subject, "period_s", "must be positive");
  if (settings_.torque_per_amp_Nm_per_A.size() != n_ || !(settings_.torque_per_amp_Nm_per_A.array() > 0.0).all()) {
    throw ConfigError(subject, "torque_per_amp_Nm_per_A", "needs one positive K_T G_r per joint");
  }
  for (const auto* limits : {&settings_.position_lower_rad, &settings_.position_upper_rad, &settings_.reference_q_rad}) {
    if (limits->size() != 0 && limits->size() != n_) throw ConfigError(subject, "position limits", "one per joint, or none");
  }
  if (settings_.max_failed_refreshes < 1) throw ConfigError(subject, "max_failed_refreshes", "must be at least 1");
  if (!(settings_.max_silence_s > 0.0)) throw ConfigError(subject, "max_silence_s", "must be positive");
  if (!(settings_.max_loss_fraction >= 0.0 && settings_.max_loss_fraction < 1.0)) {
    throw ConfigError(subject, "max_loss_fraction", "must be in [0, 1)");
  }
  if (!(settings_.loss_window_s >= settings_.period_s && settings_.loss_window_s <= 60.0)) {
    throw ConfigError(subject, "loss_window_s", "must be between one period and 60 s");
  }
}

// kortex_lowlevel.md section 5 (Kinova's example 108, ros2_kortex): sessions, single level,
// low level, the first feedback checked, one Refresh holding the measured pose, POSITION for all.
void KortexRobot::start_up() {
  check(client_.create_sessions(settings_.session), "cannot open a session (TCP 10000 / UDP 10001)");
  sessions_open_ = true;
  int count = 0;
  check(client_.actuator_count(count), "cannot read the actuator count");
  if (count != n_) refuse(format_line("the arm reports %d actuators, the robot has %d joints", count, n_));
  kortex::ArmState arm = kortex::ArmState::kUnspecified;
  check(client_.arm_state(arm), "cannot read the arm state");
  if (arm == kortex::ArmState::kInFault) {
    refuse("the arm is in fault (ARMSTATE_IN_FAULT): clear its faults (Web App or pendant) before starting");
  }
  check(client_.set_servoing_mode(kortex::ServoingMode::kSingleLevel), "cannot set SINGLE_LEVEL_SERVOING");
  low_level_ = true;  // from here on the exit sequence puts it back
  check(client_.set_servoing_mode(kortex::ServoingMode::kLowLevel), "cannot set LOW_LEVEL_SERVOING");
  check(client_.refresh_feedback(feedback_), "no BaseCyclic feedback");
  check_first_feedback();
  clock_start_s_ = client_.clock_s();
  last_good_s_ = clock_start_s_;
  publish_feedback();
  hold_measured_pose();
  frame_id_ = kortex::next_frame_id(frame_id_);
  command_.frame_id = frame_id_;
  for (kortex::ActuatorCommand& a : command_.actuators) a.command_id = frame_id_;
  check(client_.refresh(command_, feedback_), "the first Refresh (holding the measured pose) failed");
  publish_feedback();
  for (int i = 0; i < n_; ++i) {
    check(client_.set_control_mode(i, kortex::ControlMode::kPosition),
          format_line("cannot set actuator %d to POSITION", i + 1).c_str());
  }
  active_mode_ = requested_mode_ = kortex::ControlMode::kPosition;
  state_.cycle = 0;
  state_.time_s = 0.0;
}

void KortexRobot::check_first_feedback() {
  if (static_cast<int>(feedback_.actuators.size()) != n_) {
    refuse(format_line("the feedback has %d actuators, the robot has %d joints", static_cast<int>(feedback_.actuators.size()), n_));
  }
  if (feedback_.base.active_state != kortex::ArmState::kServoingLowLevel) {
    refuse("after LOW_LEVEL_SERVOING the arm reports " + std::string(kortex::to_string(feedback_.base.active_state)) +
           ", not ARMSTATE_SERVOING_LOW_LEVEL");
  }
  if (feedback_.base.fault_bank_a != 0 || feedback_.base.fault_bank_b != 0) {
    refuse(format_line("the base reports faults (bank A 0x%x, bank B 0x%x)", feedback_.base.fault_bank_a, feedback_.base.fault_bank_b));
  }
  for (int i = 0; i < n_; ++i) {
    const kortex::ActuatorFeedback& a = feedback_.actuators[static_cast<std::size_t>(i)];
    if (a.fault_bank_a != 0 || a.fault_bank_b != 0) {
      refuse(format_line("actuator %d reports fault %s (bank B 0x%x)", i + 1, kortex::safety_bits_to_string(a.fault_bank_a).c_str(),
                         a.fault_bank_b));
    }
    const double q = kortex::feedback_radians(a.position_deg);
    if (!std::isfinite(q)) refuse(format_line("joint %d reports a position that is not a number", i + 1));
    if (!continuous(i) && (q < lower_[i] || q > upper_[i])) {
      refuse(format_line("joint %d at %.1f deg is outside its limits [%.1f, %.1f] deg", i + 1, q * kortex::kDegPerRad,
                         lower_[i] * kortex::kDegPerRad, upper_[i] * kortex::kDegPerRad));
    }
  }
}

void KortexRobot::check(kortex::CallStatus status, const char* what) {
  if (status.ok()) return;
  std::string reason = std::string(what) + ": " + kortex::to_string(status);
  const std::string detail = client_.last_error_text();
  if (!detail.empty()) reason += " (" + detail + ")";
  refuse(reason);
}

void KortexRobot::refuse(const std::string& reason) {
  shutdown();
  throw HardwareError(client_.describe(), reason);
}

void KortexRobot::shutdown() noexcept {
  try {
    if (low_level_) {
      if (!settings_.dry_run || active_mode_ != kortex::ControlMode::kPosition) {
        for (int i = 0; i < n_; ++i) client_.set_control_mode(i, kortex::ControlMode::kPosition);
      }
      active_mode_ = kortex::ControlMode::kPosition;
      client_.set_servoing_mode(kortex::ServoingMode::kSingleLevel);
      low_level_ = false;
    }
    if (sessions_open_) {
      client_.close_sessions();
      sessions_open_ = false;
    }
  } catch (...) {  // a client must not throw; the exit sequence is best effort
  }
}

// ---------------------------------------------------------------------------- the cycle

const RobotState& KortexRobot::read() {
  if (!health_.link_lost && requested_mode_ != active_mode_) {
    if (!switch_control_mode(requested_mode_)) enter_link_loss("a control mode switch was refused");
  }
  frame_id_ = kortex::next_frame_id(frame_id_);
  command_.frame_id = frame_id_;
  for (kortex::ActuatorCommand& a : command_.actuators) a.command_id = frame_id_;
  const kortex::CallStatus status = client_.refresh(command_, feedback_);
  ++health_.refreshes;
  if (status.ok()) {
    health_.consecutive_failures = 0;
    last_good_s_ = client_.clock_s();
    publish_feedback();
  } else {
    note_failure(status);
  }
  note_outcome(!status.ok());
  ++state_.cycle;
  state_.time_s = client_.clock_s() - clock_start_s_;
  state_.mode = active_low_level_;
  state_.fault = health_.link_lost || health_.arm_fault;
  if (settings_.wrench_source) settings_.wrench_source(state_);
  return state_;
}

// Every actuator to `mode`; on a refusal the ones switched are put back to POSITION (false).
bool KortexRobot::switch_control_mode(kortex::ControlMode mode) noexcept {
  ++health_.mode_switches;
  for (int i = 0; i < n_; ++i) {
    if (!client_.set_control_mode(i, mode).ok()) {
      ++health_.failed_mode_switches;
      return false;
    }
  }
  active_mode_ = mode;
  active_low_level_ = requested_low_level_;
  return true;
}

void KortexRobot::publish_feedback() noexcept {
  const double t = client_.clock_s() - clock_start_s_;
  bool finite = true;
  for (int i = 0; i < n_; ++i) {
    const kortex::ActuatorFeedback& a = feedback_.actuators[static_cast<std::size_t>(i)];
    const double wrapped = kortex::feedback_radians(a.position_deg);
    const double previous = have_feedback_ ? state_.q_rad[i] : reference_[i];
    state_.q_rad[i] = continuous(i) ? kortex::unwrap_near(previous, wrapped) : wrapped;
    state_.qd_rad_s[i] = a.velocity_deg_s * kortex::kRadPerDeg;
    state_.tau_sensor_Nm[i] = kortex::joint_torque_from_feedback(a.torque_Nm);
    state_.current_A[i] = a.current_motor_A;
    finite = finite && std::isfinite(state_.q_rad[i]) && std::isfinite(state_.qd_rad_s[i]);
  }
  have_feedback_ = true;
  for (SignalStatus* s : {&state_.joints, &state_.torque, &state_.current}) {
    ++s->sequence;
    s->stamp_s = t;
  }
  state_.joints.valid = finite;
  state_.torque.valid = all_finite(state_.tau_sensor_Nm);
  state_.current.valid = all_finite(state_.current_A);
  update_health();
}

void KortexRobot::update_health() noexcept {
  health_.base = feedback_.base;
  health_.arm_state = feedback_.base.active_state;
  bool fault = feedback_.base.active_state == kortex::ArmState::kInFault || feedback_.base.fault_bank_a != 0 ||
               feedback_.base.fault_bank_b != 0;
  bool warning = feedback_.base.warning_bank_a != 0 || feedback_.base.warning_bank_b != 0;
  int first_faulty = -1;
  for (int i = 0; i < n_; ++i) {
    const auto k = static_cast<std::size_t>(i);
    const kortex::ActuatorFeedback& a = feedback_.actuators[k];
    health_.fault_bank_a[k] = a.fault_bank_a;
    health_.fault_bank_b[k] = a.fault_bank_b;
    health_.warning_bank_a[k] = a.warning_bank_a;
    health_.warning_bank_b[k] = a.warning_bank_b;
    if ((a.fault_bank_a | a.fault_bank_b) != 0 && first_faulty < 0) first_faulty = i;
    fault = fault || (a.fault_bank_a | a.fault_bank_b) != 0;
    warning = warning || (a.warning_bank_a | a.warning_bank_b) != 0;
  }
  // A fault latches on the arm until ClearFaults; from its first report on the command is the
  // measured pose with no torque, so nothing stale is applied if the arm is cleared meanwhile.
  if (fault && !health_.arm_fault) hold_measured_pose();
  health_.arm_fault = fault;
  health_.warning = warning;
  if (fault && !fault_logged_) {
    fault_logged_ = true;
    const unsigned bits = first_faulty >= 0 ? health_.fault_bank_a[static_cast<std::size_t>(first_faulty)] : 0u;
    std::snprintf(line_, sizeof line_, "phri: kortex: the arm reports a fault at t = %.3f s (arm state %u; actuator %d, fault bank A 0x%x); "
                  "commands refused from now on\n", state_.time_s, static_cast<unsigned>(feedback_.base.active_state),
                  first_faulty + 1, bits);
    log_line(line_);
  }
}

void KortexRobot::note_failure(kortex::CallStatus status) noexcept {
  ++health_.failed_refreshes;
  ++health_.consecutive_failures;
  health_.longest_failure_run = std::max(health_.longest_failure_run, health_.consecutive_failures);
  health_.last_failure = status;
  if (health_.link_lost) return;
  const double silence = client_.clock_s() - last_good_s_;
  if (health_.consecutive_failures >= settings_.max_failed_refreshes) {
    const std::string_view name = kortex::sub_error_name(health_.last_failure.sub_code);
    std::snprintf(reason_, sizeof reason_, "%d failed Refresh in a row, last: %.*s (sub-code %u)",
                  health_.consecutive_failures, static_cast<int>(name.size()), name.data(), health_.last_failure.sub_code);
    enter_link_loss(reason_);
  } else if (silence >= settings_.max_silence_s - 1e-9) {
    const std::string_view name = kortex::sub_error_name(health_.last_failure.sub_code);
    std::snprintf(reason_, sizeof reason_, "no good feedback for %.1f ms, last: %.*s (sub-code %u)", 1e3 * silence,
                  static_cast<int>(name.size()), name.data(), health_.last_failure.sub_code);
    enter_link_loss(reason_);
  }
}

// The loss rate over the last loss_window_s (a ring of outcomes, allocated at construction).
void KortexRobot::note_outcome(bool lost) noexcept {
  const std::uint8_t now = lost ? 1u : 0u;
  health_.losses_in_window += static_cast<int>(now) - static_cast<int>(loss_ring_[loss_next_]);
  loss_ring_[loss_next_] = now;
  loss_next_ = (loss_next_ + 1) % loss_ring_.size();
  health_.most_losses_in_window = std::max(health_.most_losses_in_window, health_.losses_in_window);
  if (health_.link_lost || health_.link_degraded || health_.losses_in_window <= max_losses_) return;
  std::snprintf(reason_, sizeof reason_, "packet loss: %d of the last %zu Refresh failed, more than %.1f %%",
                health_.losses_in_window, loss_ring_.size(), 100.0 * settings_.max_loss_fraction);
  request_stop(reason_);
}

// The link still carries commands: the controller's safe stop brakes, then holds (see the header).
void KortexRobot::request_stop(const char* why) noexcept {
  health_.link_degraded = true;
  health_.link_degraded_at_s = client_.clock_s() - clock_start_s_;
  state_.stop_requested = true;
  std::snprintf(line_, sizeof line_,
                "phri: kortex: link degraded at t = %.3f s (%s); safe stop requested: the controller brakes, then the "
                "arm's position hold, torque commands refused from then on\n",
                health_.link_degraded_at_s, why);
  log_line(line_);
}

// kortex_lowlevel.md section 6: with the link gone, a torque set-point must not stay in force;
// the actuators' position loop holds the last measured pose (and the arm's watchdog brakes it if
// nothing arrives at all).
void KortexRobot::enter_link_loss(const char* why) noexcept {
  health_.link_lost = true;
  health_.link_lost_at_s = client_.clock_s() - clock_start_s_;
  hold_measured_pose();
  for (int i = 0; i < n_; ++i) client_.set_control_mode(i, kortex::ControlMode::kPosition);
  active_mode_ = requested_mode_ = kortex::ControlMode::kPosition;
  active_low_level_ = requested_low_level_ = LowLevelMode::kPosition;
  std::snprintf(line_, sizeof line_,
                "phri: kortex: communication lost at t = %.3f s (%s); "
                "actuators back to POSITION holding the measured pose, torque commands stopped\n",
                health_.link_lost_at_s, why);
  log_line(line_);
}

void KortexRobot::hold_measured_pose() noexcept {
  for (std::size_t i = 0; i < command_.actuators.size(); ++i) {
    kortex::ActuatorCommand& a = command_.actuators[i];
    a.position_deg = feedback_.actuators[i].position_deg;
    a.velocity_deg_s = 0.0f;
    a.torque_joint_Nm = 0.0f;
    a.current_motor_A = 0.0f;
  }
}

void KortexRobot::log_line(const char* text) noexcept {
  if (settings_.log) std::fputs(text, settings_.log);
}

WriteStatus KortexRobot::validate(const RobotCommand& c) const noexcept {
  if (!is_valid(c.mode) || control_mode_for(c.mode) == kortex::ControlMode::kNone) return WriteStatus::kInvalidMode;
  const Eigen::VectorXd& v = c.mode == LowLevelMode::kPosition ? c.q_rad : c.mode == LowLevelMode::kCurrent ? c.current_A : c.tau_Nm;
  if (v.size() != n_) return WriteStatus::kSizeMismatch;
  if (!v.allFinite()) return WriteStatus::kNotFinite;
  if (c.mode == LowLevelMode::kPosition && ((c.q_rad.array() < lower_.array()).any() || (c.q_rad.array() > upper_.array()).any())) {
    return WriteStatus::kOutOfRange;
  }
  if (health_.link_lost || health_.arm_fault) return WriteStatus::kFault;
  if (position_only_ && c.mode != LowLevelMode::kPosition) return WriteStatus::kFault;
  return WriteStatus::kOk;
}

WriteStatus KortexRobot::write(const RobotCommand& c) {
  const WriteStatus status = validate(c);
  state_.last_write_status = status;
  if (status != WriteStatus::kOk) {
    ++state_.rejected_writes;
    return status;
  }
  if (settings_.dry_run) {
    hold_measured_pose();
    return status;
  }
  requested_mode_ = control_mode_for(c.mode);
  requested_low_level_ = c.mode;
  if (health_.link_degraded && c.mode == LowLevelMode::kPosition) position_only_ = true;
  for (int i = 0; i < n_; ++i) {
    kortex::ActuatorCommand& a = command_.actuators[static_cast<std::size_t>(i)];
    const float measured_deg = feedback_.actuators[static_cast<std::size_t>(i)].position_deg;
    a.velocity_deg_s = 0.0f;
    switch (c.mode) {
      case LowLevelMode::kPosition:
        a.position_deg = kortex::command_degrees(c.q_rad[i]);
        a.torque_joint_Nm = 0.0f;
        a.current_motor_A = 0.0f;
        break;
      case LowLevelMode::kCurrent:
        a.position_deg = measured_deg;
        a.current_motor_A = static_cast<float>(c.current_A[i]);
        a.torque_joint_Nm = static_cast<float>(c.current_A[i] * torque_per_amp_[i]);
        break;
      default:  // the two Kinova torque loops
        a.position_deg = measured_deg;
        a.torque_joint_Nm = static_cast<float>(c.tau_Nm[i]);
        a.current_motor_A = static_cast<float>(kortex::motor_current_for_torque(c.tau_Nm[i], torque_per_amp_[i]));
        break;
    }
  }
  return status;
}

}  // namespace phri
