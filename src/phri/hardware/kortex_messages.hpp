#pragma once
// The Kortex API's low-level (1 kHz) vocabulary as plain data: the enums, bit masks and the
// fields of the BaseCyclic Command / Feedback messages phri uses, with the SDK's own units
// (degrees, degrees per second, N.m, A). phri::KortexClient speaks these; phri::KortexRobot
// converts them to phri's RobotState / RobotCommand (SI, radians).
//
// Every number here is transcribed from the project's Kortex notes (kortex_lowlevel.md,
// kortex_sdk_api.md), which cite Kinova's .proto files (ros_kortex @ 6cd75d45, kortex_driver/
// protos: Base.proto, BaseCyclic.proto, ActuatorCyclic.proto, ActuatorConfig.proto, Common.proto,
// Errors.proto) and the generated SDK headers. Only the values phri uses are listed.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

namespace phri::kortex {

// Base.proto, ServoingMode.
enum class ServoingMode : std::uint32_t {
  kUnspecified = 0,
  kSingleLevel = 2,  ///< default at boot ("high level")
  kLowLevel = 3,     ///< BaseCyclic at 1 kHz, each actuator commanded individually
  kBypass = 4,
};

// Common.proto, ArmState (the values the notes list).
enum class ArmState : std::uint32_t {
  kUnspecified = 0,
  kIdle = 2,
  kInFault = 4,
  kServoingLowLevel = 6,
  kServoingReady = 7,
};

// ActuatorConfig.proto, ControlMode.
enum class ControlMode : std::uint32_t {
  kNone = 0,
  kPosition = 1,
  kVelocity = 2,
  kTorque = 3,
  kCurrent = 4,
  kCustom = 5,
  kTorqueHighVelocity = 6,
};

// ActuatorCyclic.proto, StatusFlags (ActuatorFeedback.status_flags).
namespace status_flag {
inline constexpr std::uint32_t kStabilized = 0x10;
inline constexpr std::uint32_t kMotorIndexed = 0x20;
inline constexpr std::uint32_t kBraking = 0x400;
inline constexpr std::uint32_t kServoing = 0x800;
inline constexpr std::uint32_t kMajorFault = 0x1000;
inline constexpr std::uint32_t kMinorFault = 0x2000;
inline constexpr std::uint32_t kCalibratedTorque = 0x4000;
}  // namespace status_flag

// ActuatorConfig.proto, SafetyIdentifierBankA (ActuatorFeedback fault_bank_a / warning_bank_a).
namespace safety_bit {
inline constexpr std::uint32_t kFollowingError = 0x1;
inline constexpr std::uint32_t kMaximumVelocity = 0x2;
inline constexpr std::uint32_t kJointLimitHigh = 0x4;
inline constexpr std::uint32_t kJointLimitLow = 0x8;
inline constexpr std::uint32_t kStrainGaugeMismatch = 0x10;
inline constexpr std::uint32_t kMaximumTorque = 0x20;
inline constexpr std::uint32_t kMaximumMotorCurrent = 0x2000;
inline constexpr std::uint32_t kCommunicationTickLost = 0x400000;
inline constexpr std::uint32_t kWatchdogTriggered = 0x800000;
}  // namespace safety_bit

/// "following_error|watchdog_triggered" for the bits of bank A named above (others as hex).
std::string safety_bits_to_string(std::uint32_t bank_a);

// Errors.proto, ErrorCodes and the SubErrorCodes phri meets.
enum class ErrorCode : std::uint32_t {
  kNone = 0,
  kProtocolServer = 1,
  kProtocolClient = 2,
  kDevice = 3,
  kInternal = 4,
};
namespace sub_error {
inline constexpr std::uint32_t kMethodFailed = 1;
inline constexpr std::uint32_t kInvalidParam = 3;
inline constexpr std::uint32_t kUnsupportedService = 4;
inline constexpr std::uint32_t kInvalidSession = 12;
inline constexpr std::uint32_t kRobotNotReady = 21;
inline constexpr std::uint32_t kRobotInFault = 22;
inline constexpr std::uint32_t kDeviceDisconnected = 50;
inline constexpr std::uint32_t kWrongServoingMode = 75;
inline constexpr std::uint32_t kMethodTimeout = 131;
}  // namespace sub_error

/// The outcome of one call: ERROR_NONE, or Kinova's error code and sub-code. Plain data, no
/// allocation (the text of an SDK exception stays with the client: KortexClient::last_error_text).
struct CallStatus {
  ErrorCode code = ErrorCode::kNone;
  std::uint32_t sub_code = 0;

  bool ok() const { return code == ErrorCode::kNone; }
  static CallStatus success() { return {}; }
  static CallStatus failure(ErrorCode code, std::uint32_t sub_code) { return {code, sub_code}; }
};

/// "ok", "wrong_servoing_mode (75)", ...
std::string to_string(CallStatus status);
/// The name of a Kortex sub-error code ("method_timeout" for 131), "error" for one it does not know.
std::string_view sub_error_name(std::uint32_t sub_code);
std::string_view to_string(ControlMode mode);
std::string_view to_string(ServoingMode mode);
std::string_view to_string(ArmState state);

// BaseCyclic.proto, ActuatorCommand.
struct ActuatorCommand {
  std::uint32_t command_id = 0;  ///< the examples write frame_id here (its low 16 bits: the sequence)
  std::uint32_t flags = 0;       ///< CommandFlags; Kinova's examples, ros2_kortex and mc_kortex leave 0
  float position_deg = 0.0f;     ///< [deg] in [0, 360); in TORQUE / CURRENT the measured position
  float velocity_deg_s = 0.0f;   ///< [deg/s]
  float torque_joint_Nm = 0.0f;  ///< [N.m]
  float current_motor_A = 0.0f;  ///< [A], motor side
};

// BaseCyclic.proto, ActuatorFeedback.
struct ActuatorFeedback {
  std::uint32_t command_id = 0;
  std::uint32_t status_flags = 0;
  std::uint32_t jitter_comm_us = 0;
  float position_deg = 0.0f;     ///< [deg] in [0, 360)
  float velocity_deg_s = 0.0f;   ///< [deg/s]
  float torque_Nm = 0.0f;        ///< [N.m], sign opposite to torque_joint's ("reversed", Kinova example 108)
  float current_motor_A = 0.0f;  ///< [A]
  float voltage_V = 0.0f;
  float temperature_motor_C = 0.0f;
  float temperature_core_C = 0.0f;
  std::uint32_t fault_bank_a = 0, fault_bank_b = 0, warning_bank_a = 0, warning_bank_b = 0;
};

// BaseCyclic.proto, BaseFeedback (the fields phri reads).
struct BaseFeedback {
  ArmState active_state = ArmState::kUnspecified;
  std::uint32_t fault_bank_a = 0, fault_bank_b = 0, warning_bank_a = 0, warning_bank_b = 0;
};

/// BaseCyclic.Command: sized once (one ActuatorCommand per actuator), then reused every cycle.
struct CyclicCommand {
  std::uint32_t frame_id = 0;
  std::vector<ActuatorCommand> actuators;
};

/// BaseCyclic.Feedback: sized once, then overwritten by every Refresh.
struct CyclicFeedback {
  std::uint32_t frame_id = 0;
  BaseFeedback base;
  std::vector<ActuatorFeedback> actuators;
};

/// Session.CreateSessionInfo; the timeouts Kinova's examples, mc_kortex and ros2_kortex use.
struct SessionSettings {
  std::string username = "admin";  ///< the arm's factory default
  std::string password = "admin";
  std::uint32_t session_inactivity_timeout_ms = 60000;
  std::uint32_t connection_inactivity_timeout_ms = 2000;
};

/// The 16-bit frame counter: +1 per cycle, 65535 -> 0 (Kinova example 108 and ros2_kortex:
/// "Incrementing identifier ensures actuators can reject out of time frames").
constexpr std::uint32_t next_frame_id(std::uint32_t frame_id) { return (frame_id + 1u) & 0xFFFFu; }

}  // namespace phri::kortex
