#include <phri/hardware/kortex_messages.hpp>

#include <cstdio>
#include <utility>

namespace phri::kortex {

std::string safety_bits_to_string(std::uint32_t bank_a) {
  static constexpr std::pair<std::uint32_t, const char*> kNames[] = {
      {safety_bit::kFollowingError, "following_error"},
      {safety_bit::kMaximumVelocity, "maximum_velocity"},
      {safety_bit::kJointLimitHigh, "joint_limit_high"},
      {safety_bit::kJointLimitLow, "joint_limit_low"},
      {safety_bit::kStrainGaugeMismatch, "strain_gauge_mismatch"},
      {safety_bit::kMaximumTorque, "maximum_torque"},
      {safety_bit::kMaximumMotorCurrent, "maximum_motor_current"},
      {safety_bit::kCommunicationTickLost, "communication_tick_lost"},
      {safety_bit::kWatchdogTriggered, "watchdog_triggered"},
  };
  std::string text;
  std::uint32_t rest = bank_a;
  for (const auto& [bit, name] : kNames) {
    if ((bank_a & bit) == 0) continue;
    if (!text.empty()) text += '|';
    text += name;
    rest &= ~bit;
  }
  if (rest != 0) {
    char hex[16];
    std::snprintf(hex, sizeof hex, "0x%x", rest);
    if (!text.empty()) text += '|';
    text += hex;
  }
  return text.empty() ? "none" : text;
}

std::string_view sub_error_name(std::uint32_t sub_code) {
  switch (sub_code) {
    case sub_error::kMethodFailed: return "method_failed";
    case sub_error::kInvalidParam: return "invalid_param";
    case sub_error::kUnsupportedService: return "unsupported_service";
    case sub_error::kInvalidSession: return "invalid_session";
    case sub_error::kRobotNotReady: return "robot_not_ready";
    case sub_error::kRobotInFault: return "robot_in_fault";
    case sub_error::kDeviceDisconnected: return "device_disconnected";
    case sub_error::kWrongServoingMode: return "wrong_servoing_mode";
    case sub_error::kMethodTimeout: return "method_timeout";
  }
  return "error";
}

std::string to_string(CallStatus status) {
  if (status.ok()) return "ok";
  std::string text(sub_error_name(status.sub_code));
  text += " (";
  text += std::to_string(status.sub_code);
  text += ')';
  return text;
}

std::string_view to_string(ControlMode mode) {
  switch (mode) {
    case ControlMode::kNone: return "NONE";
    case ControlMode::kPosition: return "POSITION";
    case ControlMode::kVelocity: return "VELOCITY";
    case ControlMode::kTorque: return "TORQUE";
    case ControlMode::kCurrent: return "CURRENT";
    case ControlMode::kCustom: return "CUSTOM";
    case ControlMode::kTorqueHighVelocity: return "TORQUE_HIGH_VELOCITY";
  }
  return "UNKNOWN";
}

std::string_view to_string(ServoingMode mode) {
  switch (mode) {
    case ServoingMode::kUnspecified: return "UNSPECIFIED_SERVOING_MODE";
    case ServoingMode::kSingleLevel: return "SINGLE_LEVEL_SERVOING";
    case ServoingMode::kLowLevel: return "LOW_LEVEL_SERVOING";
    case ServoingMode::kBypass: return "BYPASS_SERVOING";
  }
  return "UNKNOWN";
}

std::string_view to_string(ArmState state) {
  switch (state) {
    case ArmState::kUnspecified: return "ARMSTATE_UNSPECIFIED";
    case ArmState::kIdle: return "ARMSTATE_IDLE";
    case ArmState::kInFault: return "ARMSTATE_IN_FAULT";
    case ArmState::kServoingLowLevel: return "ARMSTATE_SERVOING_LOW_LEVEL";
    case ArmState::kServoingReady: return "ARMSTATE_SERVOING_READY";
  }
  return "ARMSTATE_OTHER";
}

}  // namespace phri::kortex
