#include <phri/hardware/kortex_emulator.hpp>

#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/hardware/kortex_units.hpp>

#include <algorithm>
#include <cmath>
#include <optional>
#include <string>

namespace phri {
namespace {
using kortex::CallStatus;
using kortex::ControlMode;
using kortex::ErrorCode;

CallStatus invalid_session() { return CallStatus::failure(ErrorCode::kProtocolServer, kortex::sub_error::kInvalidSession); }
CallStatus timeout() { return CallStatus::failure(ErrorCode::kProtocolClient, kortex::sub_error::kMethodTimeout); }
CallStatus invalid_param() { return CallStatus::failure(ErrorCode::kProtocolServer, kortex::sub_error::kInvalidParam); }

bool emulated(ControlMode mode) {
  return mode == ControlMode::kPosition || mode == ControlMode::kTorque || mode == ControlMode::kTorqueHighVelocity ||
         mode == ControlMode::kCurrent;
}
}  // namespace

KortexEmulator::KortexEmulator(RobotInterface& plant, const RobotState& plant_initial, KortexEmulatorSettings settings)
    : plant_(plant),
      plant_state_(&plant_initial),
      settings_(settings),
      n_(plant.dof()),
      period_(plant.period_s()),
      reported_count_(plant.dof()),
      random_(settings.seed),
      plant_command_(plant.dof()),
      modes_(static_cast<std::size_t>(plant.dof()), ControlMode::kPosition),
      fault_a_(static_cast<std::size_t>(plant.dof()), 0u),
      warning_a_(static_cast<std::size_t>(plant.dof()), 0u) {
  if (plant_initial.q_rad.size() != n_) throw ConfigError("KortexEmulator", "plant_initial", "state of another size than the plant");
  if (!(settings.packet_loss_probability >= 0.0 && settings.packet_loss_probability <= 1.0)) {
    throw ConfigError("KortexEmulator", "packet_loss_probability", "must be in [0, 1]");
  }
  calls_.reserve(settings.call_capacity);
  last_command_.actuators.resize(static_cast<std::size_t>(n_));
  plant_command_.q_rad = plant_initial.q_rad;
}

void KortexEmulator::set_packet_loss(double probability, std::uint64_t seed) {
  settings_.packet_loss_probability = std::clamp(probability, 0.0, 1.0);
  random_.seed(seed);
}

long KortexEmulator::periods(double seconds) const { return std::max(0L, std::lround(seconds / period_)); }

void KortexEmulator::record(CallKind kind, int actuator, std::uint32_t value) {
  if (calls_.size() < calls_.capacity()) calls_.push_back({kind, actuator, value, plant_state_->time_s});
}

CallStatus KortexEmulator::session_check() {
  if (!sessions_open_) return invalid_session();
  last_activity_s_ = plant_state_->time_s;
  return CallStatus::success();
}

bool KortexEmulator::any_fault() const {
  return estop_ || std::any_of(fault_a_.begin(), fault_a_.end(), [](std::uint32_t b) { return b != 0; });
}

kortex::ArmState KortexEmulator::arm_state() const {
  if (any_fault()) return kortex::ArmState::kInFault;
  return servoing_ == kortex::ServoingMode::kLowLevel ? kortex::ArmState::kServoingLowLevel : kortex::ArmState::kServoingReady;
}

// ---------------------------------------------------------------------------- configuration (TCP)

CallStatus KortexEmulator::create_sessions(const kortex::SessionSettings& settings) {
  record(CallKind::kCreateSessions);
  session_ = settings;
  sessions_open_ = true;
  last_activity_s_ = plant_state_->time_s;
  return CallStatus::success();
}

CallStatus KortexEmulator::close_sessions() {
  record(CallKind::kCloseSessions);
  if (!sessions_open_) return invalid_session();
  sessions_open_ = false;
  return CallStatus::success();
}

CallStatus KortexEmulator::actuator_count(int& count) {
  record(CallKind::kActuatorCount);
  const CallStatus s = session_check();
  if (s.ok()) count = reported_count_;
  return s;
}

CallStatus KortexEmulator::arm_state(kortex::ArmState& state) {
  record(CallKind::kArmState);
  const CallStatus s = session_check();
  if (s.ok()) state = arm_state();
  return s;
}

CallStatus KortexEmulator::servoing_mode(kortex::ServoingMode& mode) {
  record(CallKind::kServoingMode);
  const CallStatus s = session_check();
  if (s.ok()) mode = servoing_;
  return s;
}

CallStatus KortexEmulator::set_servoing_mode(kortex::ServoingMode mode) {
  record(CallKind::kSetServoingMode, -1, static_cast<std::uint32_t>(mode));
  const CallStatus s = session_check();
  if (!s.ok()) return s;
  if (mode != kortex::ServoingMode::kSingleLevel && mode != kortex::ServoingMode::kLowLevel) return invalid_param();
  if (mode != servoing_) {
    // Either way the actuators start in their position hold at the measured pose.
    std::fill(modes_.begin(), modes_.end(), ControlMode::kPosition);
    if (servoing_ == kortex::ServoingMode::kLowLevel) hold();
    servoing_ = mode;
    last_command_s_ = plant_state_->time_s;
  }
  return s;
}

CallStatus KortexEmulator::clear_faults() {
  record(CallKind::kClearFaults);
  const CallStatus s = session_check();
  if (!s.ok()) return s;
  std::fill(fault_a_.begin(), fault_a_.end(), 0u);
  std::fill(modes_.begin(), modes_.end(), ControlMode::kPosition);
  estop_ = false;
  holding_ = false;  // the plant keeps its hold until the next command
  last_command_s_ = plant_state_->time_s;
  return s;
}

CallStatus KortexEmulator::stop() {
  record(CallKind::kStop);
  const CallStatus s = session_check();
  if (s.ok()) hold();
  return s;
}

CallStatus KortexEmulator::apply_emergency_stop() {
  record(CallKind::kEmergencyStop);
  const CallStatus s = session_check();
  if (!s.ok()) return s;
  estop_ = true;
  hold();
  return s;
}

CallStatus KortexEmulator::set_control_mode(int actuator, ControlMode mode) {
  record(CallKind::kSetControlMode, actuator, static_cast<std::uint32_t>(mode));
  const CallStatus s = session_check();
  if (!s.ok()) return s;
  if (actuator < 0 || actuator >= n_) return CallStatus::failure(ErrorCode::kProtocolServer, 52);  // INVALID_DEVICE
  if (!emulated(mode)) return invalid_param();
  modes_[index(actuator)] = mode;
  return s;
}

void KortexEmulator::inject_fault(int actuator, std::uint32_t fault_bank_a) {
  fault_a_[index(actuator)] |= fault_bank_a;
  if (any_fault()) hold();
}

// ---------------------------------------------------------------------------- cyclic (UDP)

CallStatus KortexEmulator::refresh_feedback(kortex::CyclicFeedback& feedback) noexcept {
  record(CallKind::kRefreshFeedback);
  const CallStatus s = session_check();
  if (s.ok()) fill(feedback);
  return s;
}

CallStatus KortexEmulator::refresh(const kortex::CyclicCommand& command, kortex::CyclicFeedback& feedback) noexcept {
  ++counters_.refreshes;
  if (scheduled_.kind != ScheduledKortexFault::Kind::kNone && plant_state_->time_s >= scheduled_.at_s - 1e-9) {
    switch (scheduled_.kind) {
      case ScheduledKortexFault::Kind::kPacketLoss: settings_.packet_loss_probability = scheduled_.value; break;
      case ScheduledKortexFault::Kind::kStall: stall_next_refresh(scheduled_.value); break;
      case ScheduledKortexFault::Kind::kDroppedSession: drop_session(); break;
      case ScheduledKortexFault::Kind::kNone: break;
    }
    scheduled_.kind = ScheduledKortexFault::Kind::kNone;
  }
  if (stall_periods_ > 0) {
    ++counters_.stalls;
    for (long k = stall_periods_; k > 0; --k) step(false);
    stall_periods_ = 0;
    return timeout();
  }
  if (settings_.packet_loss_probability > 0.0 &&
      static_cast<double>(random_() >> 11) * 0x1.0p-53 < settings_.packet_loss_probability) {
    ++counters_.lost_packets;
    step(false);
    return timeout();
  }
  CallStatus s = session_check();
  if (s.ok() && servoing_ != kortex::ServoingMode::kLowLevel) {
    s = CallStatus::failure(ErrorCode::kDevice, kortex::sub_error::kWrongServoingMode);
  }
  if (s.ok() && static_cast<int>(command.actuators.size()) != n_) s = invalid_param();
  if (s.ok()) s = apply(command);
  if (!s.ok()) {
    ++counters_.refused_refreshes;
    step(false);
    return s;
  }
  step(true);
  fill(feedback);
  return s;
}

// The command reaches the actuators: the plant's set-point for the next period.
CallStatus KortexEmulator::apply(const kortex::CyclicCommand& command) {
  const ControlMode mode = modes_[0];
  if (std::any_of(modes_.begin(), modes_.end(), [mode](ControlMode m) { return m != mode; })) return invalid_param();
  last_command_.frame_id = command.frame_id;
  std::copy(command.actuators.begin(), command.actuators.end(), last_command_.actuators.begin());
  last_command_s_ = plant_state_->time_s;
  ++counters_.commands_applied;
  if (holding_ || any_fault() || check_following_error(command)) return CallStatus::success();  // ignored: holding
  const RobotState& s = *plant_state_;
  for (int i = 0; i < n_; ++i) {
    const kortex::ActuatorCommand& a = command.actuators[index(i)];
    switch (mode) {
      case ControlMode::kPosition:  // the commanded turn nearest to the measured angle
        plant_command_.q_rad[i] = kortex::unwrap_near(s.q_rad[i], a.position_deg * kortex::kRadPerDeg);
        break;
      case ControlMode::kCurrent: plant_command_.current_A[i] = a.current_motor_A; break;
      default: plant_command_.tau_Nm[i] = a.torque_joint_Nm; break;
    }
  }
  plant_command_.mode = mode == ControlMode::kPosition       ? LowLevelMode::kPosition
                        : mode == ControlMode::kCurrent      ? LowLevelMode::kCurrent
                        : mode == ControlMode::kTorque       ? LowLevelMode::kKinovaTorque
                                                             : LowLevelMode::kKinovaTorqueHighVelocity;
  if (plant_.write(plant_command_) != WriteStatus::kOk) return invalid_param();
  return CallStatus::success();
}

// kortex_lowlevel.md section 5: in TORQUE / CURRENT the position field is a safety check.
bool KortexEmulator::check_following_error(const kortex::CyclicCommand& command) {
  if (modes_[0] == ControlMode::kPosition) return false;
  bool fault = false;
  for (int i = 0; i < n_; ++i) {
    const double measured_deg = plant_state_->q_rad[i] * kortex::kDegPerRad;
    const double error = std::abs(kortex::degrees_between(command.actuators[index(i)].position_deg, measured_deg));
    if (error > settings_.following_error_deg) {
      fault_a_[index(i)] |= kortex::safety_bit::kFollowingError;
      fault = true;
    } else if (error > settings_.following_warning_deg) {
      warning_a_[index(i)] |= kortex::safety_bit::kFollowingError;
    }
  }
  if (fault) {
    ++counters_.following_errors;
    hold();
  }
  return fault;
}

// One control period of the plant; the watchdog and the session timeout count in plant time.
void KortexEmulator::step(bool command_arrived) {
  const double t = plant_state_->time_s;
  if (!command_arrived && servoing_ == kortex::ServoingMode::kLowLevel && !any_fault() &&
      t - last_command_s_ > settings_.watchdog_timeout_s + 1e-9) {
    for (std::uint32_t& bank : fault_a_) bank |= kortex::safety_bit::kWatchdogTriggered;
    ++counters_.watchdog_trips;
    hold();
  }
  if (sessions_open_ && t - last_activity_s_ > 1e-3 * session_.session_inactivity_timeout_ms + 1e-9) {
    sessions_open_ = false;
    ++counters_.session_timeouts;
  }
  plant_state_ = &plant_.read();
}

void KortexEmulator::run_idle(double seconds) {
  for (long k = periods(seconds); k > 0; --k) step(false);
}

// The actuators' position loop at the measured pose (a fault, a stop, the watchdog).
void KortexEmulator::hold() {
  holding_ = true;
  plant_command_.mode = LowLevelMode::kPosition;
  plant_command_.q_rad = plant_state_->q_rad;
  plant_.write(plant_command_);
}

void KortexEmulator::fill(kortex::CyclicFeedback& feedback) const {
  const RobotState& s = *plant_state_;
  feedback.frame_id = last_command_.frame_id;
  feedback.base = {};
  feedback.base.active_state = arm_state();
  const bool low_level = servoing_ == kortex::ServoingMode::kLowLevel;
  for (int i = 0; i < n_ && i < static_cast<int>(feedback.actuators.size()); ++i) {
    kortex::ActuatorFeedback& a = feedback.actuators[index(i)];
    a.command_id = last_command_.actuators[index(i)].command_id;
    a.status_flags = kortex::status_flag::kStabilized | kortex::status_flag::kMotorIndexed |
                     kortex::status_flag::kCalibratedTorque | (low_level ? kortex::status_flag::kServoing : 0u) |
                     (fault_a_[index(i)] != 0 ? kortex::status_flag::kMajorFault : 0u);
    a.jitter_comm_us = 0;
    a.position_deg = kortex::command_degrees(s.q_rad[i]);
    a.velocity_deg_s = static_cast<float>(s.qd_rad_s[i] * kortex::kDegPerRad);
    a.torque_Nm = kortex::feedback_torque_from_joint(s.tau_sensor_Nm[i]);
    a.current_motor_A = static_cast<float>(s.current_A[i]);
    a.voltage_V = 24.0f;
    a.temperature_motor_C = a.temperature_core_C = 35.0f;
    a.fault_bank_a = fault_a_[index(i)];
    a.fault_bank_b = 0;
    a.warning_bank_a = warning_a_[index(i)];
    a.warning_bank_b = 0;
  }
}

}  // namespace phri

namespace phri {

ScheduledKortexFault ScheduledKortexFault::parse(const std::string& text, const std::string& option) {
  const std::string usage = "packet-loss:P@T (0 < P <= 1), stall:MS@T (1 to 1000 ms) or drop-session@T (T >= 0 s)";
  auto number = [&](const std::string& s) {
    const std::optional<double> v = parse_number(s);
    if (!v || !std::isfinite(*v)) throw ConfigError(option, text, "expected " + usage);
    return *v;
  };
  const std::size_t at = text.rfind('@');
  if (at == std::string::npos) throw ConfigError(option, text, "expected " + usage);
  ScheduledKortexFault f;
  f.at_s = number(text.substr(at + 1));
  const std::string head = text.substr(0, at);
  const std::size_t colon = head.find(':');
  const std::string kind = head.substr(0, colon);
  const bool has_value = colon != std::string::npos;
  if (kind == "packet-loss" && has_value) {
    f.kind = Kind::kPacketLoss;
    f.value = number(head.substr(colon + 1));
    if (!(f.value > 0.0 && f.value <= 1.0)) throw ConfigError(option, text, "the loss probability must be in (0, 1]");
  } else if (kind == "stall" && has_value) {
    f.kind = Kind::kStall;
    const double ms = number(head.substr(colon + 1));
    if (!(ms >= 1.0 && ms <= 1000.0)) throw ConfigError(option, text, "the stall must be 1 to 1000 ms");
    f.value = 1e-3 * ms;
  } else if (kind == "drop-session" && !has_value) {
    f.kind = Kind::kDroppedSession;
  } else {
    throw ConfigError(option, text, "expected " + usage);
  }
  if (!(f.at_s >= 0.0 && f.at_s <= 3600.0)) throw ConfigError(option, text, "the time must be 0 to 3600 s");
  return f;
}

}  // namespace phri
