#pragma once
// A minimal, SDK-shaped test double of Kinova's Kortex C++ API: the classes, calls and
// protobuf-style accessors phri's adapter (src/phri/hardware/kortex_sdk/kortex_sdk_client.cpp)
// uses, declared as the project's notes transcribe them from the SDK's headers
// (kortex_sdk_api.md sections 2-6: namespace Kinova::Api, TransportClientTcp/Udp, RouterClient,
// SessionManager, BaseClient, BaseCyclicClient, ActuatorConfigClient, RouterClientSendOptions
// {andForget, delay_ms, timeout_ms}, KDetailedException -> std::runtime_error, getErrorInfo()
// .getError().error_code() / error_sub_code()). Not Kinova's code: written here, trivial
// in-memory behaviour (kortex_sdk_double.cpp), so the adapter compiles and is unit-tested in CI.
//
// The in-memory arm (namespace kortex_sdk_double) records every call as a line of text and
// answers Refresh by echoing the command: POSITION actuators move to their set-point, the
// measured torque is the commanded torque_joint with the reversed sign (as the real arm reports
// it), the current is current_motor. Tests reach it through kortex_sdk_double::arm().
#include <cstdint>
#include <functional>
#include <future>
#include <stdexcept>
#include <string>
#include <vector>

namespace Kinova {
namespace Api {

// ---------------------------------------------------------------- Errors.pb.h, Frame.pb.h
enum ErrorCodes { ERROR_NONE = 0, ERROR_PROTOCOL_SERVER = 1, ERROR_PROTOCOL_CLIENT = 2, ERROR_DEVICE = 3, ERROR_INTERNAL = 4 };
enum SubErrorCodes {
  SUB_ERROR_NONE = 0, METHOD_FAILED = 1, UNIMPLEMENTED = 2, INVALID_PARAM = 3, UNSUPPORTED_SERVICE = 4,
  INVALID_SESSION = 12, ROBOT_NOT_READY = 21, ROBOT_IN_FAULT = 22, DEVICE_DISCONNECTED = 50, INVALID_DEVICE = 52,
  WRONG_SERVOING_MODE = 75, SESSION_NOT_IN_CONTROL = 130, METHOD_TIMEOUT = 131, CONTROL_PERMISSION_DENIED = 141,
};
std::string ErrorCodes_Name(ErrorCodes code);
std::string SubErrorCodes_Name(SubErrorCodes code);

class Error {
public:
  ErrorCodes error_code() const { return error_code_; }
  std::uint32_t error_sub_code() const { return error_sub_code_; }
  const std::string& error_sub_string() const { return error_sub_string_; }
  void set_error_code(ErrorCodes c) { error_code_ = c; }
  void set_error_sub_code(std::uint32_t c) { error_sub_code_ = c; }
  void set_error_sub_string(const std::string& s) { error_sub_string_ = s; }

private:
  ErrorCodes error_code_ = ERROR_NONE;
  std::uint32_t error_sub_code_ = 0;
  std::string error_sub_string_;
};

// ---------------------------------------------------------------- KError.h, KBasicException.h, KDetailedException.h
class KError {
public:
  explicit KError(Error error = {}) : error_(std::move(error)) {}
  Error getError() const { return error_; }
  std::string toString() const { return ErrorCodes_Name(error_.error_code()) + " " + error_.error_sub_string(); }

private:
  Error error_;
};

class KBasicException : public std::runtime_error {
public:
  explicit KBasicException(const KError& error) : std::runtime_error(error.toString()), error_(error) {}
  KError& getErrorInfo() { return error_; }

private:
  KError error_;
};

class KDetailedException : public KBasicException {
public:
  using KBasicException::KBasicException;
};

// ---------------------------------------------------------------- IRouterClient.h, RouterClient.h
typedef struct {
  bool andForget;
  std::uint32_t delay_ms;
  std::uint32_t timeout_ms;
} RouterClientSendOptions;

class ITransportClient {
public:
  virtual ~ITransportClient() = default;
  virtual bool connect(std::string host, std::uint32_t port) = 0;
  virtual void disconnect() = 0;
};

// TransportClientTcp.h / TransportClientUdp.h
class TransportClientTcp : public ITransportClient {
public:
  explicit TransportClientTcp(bool isUsingRcvThread = true);
  bool connect(std::string host = "127.0.0.1", std::uint32_t port = 10000) override;
  void disconnect() override;
};

class TransportClientUdp : public ITransportClient {
public:
  TransportClientUdp(bool isUsingRcvThread = true);
  bool connect(std::string host = "127.0.0.1", std::uint32_t port = 10000) override;
  void disconnect() override;
};

class IRouterClient {
public:
  virtual ~IRouterClient() = default;
};

class RouterClient : public IRouterClient {
public:
  RouterClient(ITransportClient* transport, std::function<void(KError)> errorCallback);
  void SetActivationStatus(bool isActive);
  ITransportClient* transport() const { return transport_; }

private:
  ITransportClient* transport_;
  std::function<void(KError)> error_callback_;
};

// ---------------------------------------------------------------- Session.pb.h, SessionManager.h
namespace Session {
class CreateSessionInfo {
public:
  void set_username(const std::string& v) { username_ = v; }
  void set_password(const std::string& v) { password_ = v; }
  void set_session_inactivity_timeout(std::uint32_t v) { session_inactivity_timeout_ = v; }
  void set_connection_inactivity_timeout(std::uint32_t v) { connection_inactivity_timeout_ = v; }
  const std::string& username() const { return username_; }
  const std::string& password() const { return password_; }
  std::uint32_t session_inactivity_timeout() const { return session_inactivity_timeout_; }
  std::uint32_t connection_inactivity_timeout() const { return connection_inactivity_timeout_; }

private:
  std::string username_, password_;
  std::uint32_t session_inactivity_timeout_ = 0, connection_inactivity_timeout_ = 0;
};
}  // namespace Session

class SessionManager {
public:
  SessionManager() = delete;
  explicit SessionManager(IRouterClient* router, std::function<void()> connectionTimeoutCallback = nullptr);
  void CreateSession(const Session::CreateSessionInfo& info);
  void CloseSession();

private:
  IRouterClient* router_;
};

// ---------------------------------------------------------------- Common.pb.h
namespace Common {
enum ArmState {
  ARMSTATE_UNSPECIFIED = 0, ARMSTATE_BASE_INITIALIZATION = 1, ARMSTATE_IDLE = 2, ARMSTATE_INITIALIZATION = 3,
  ARMSTATE_IN_FAULT = 4, ARMSTATE_MAINTENANCE = 5, ARMSTATE_SERVOING_LOW_LEVEL = 6, ARMSTATE_SERVOING_READY = 7,
};
}  // namespace Common

// ---------------------------------------------------------------- Base.pb.h, BaseClientRpc.h
namespace Base {
enum ServoingMode { UNSPECIFIED_SERVOING_MODE = 0, SINGLE_LEVEL_SERVOING = 2, LOW_LEVEL_SERVOING = 3, BYPASS_SERVOING = 4 };

class ServoingModeInformation {
public:
  void set_servoing_mode(ServoingMode m) { servoing_mode_ = m; }
  ServoingMode servoing_mode() const { return servoing_mode_; }

private:
  ServoingMode servoing_mode_ = UNSPECIFIED_SERVOING_MODE;
};

class ActuatorInformation {
public:
  std::uint32_t count() const { return count_; }
  void set_count(std::uint32_t c) { count_ = c; }

private:
  std::uint32_t count_ = 0;
};

class ArmStateInformation {
public:
  Common::ArmState active_state() const { return active_state_; }
  void set_active_state(Common::ArmState s) { active_state_ = s; }

private:
  Common::ArmState active_state_ = Common::ARMSTATE_UNSPECIFIED;
};

class BaseClient {
public:
  explicit BaseClient(IRouterClient* clientRouter);
  void SetServoingMode(const ServoingModeInformation& mode, std::uint32_t deviceId = 0,
                       const RouterClientSendOptions& options = {false, 0, 3000});
  ServoingModeInformation GetServoingMode(std::uint32_t deviceId = 0, const RouterClientSendOptions& options = {false, 0, 3000});
  ActuatorInformation GetActuatorCount(std::uint32_t deviceId = 0, const RouterClientSendOptions& options = {false, 0, 3000});
  ArmStateInformation GetArmState(std::uint32_t deviceId = 0, const RouterClientSendOptions& options = {false, 0, 3000});
  void ClearFaults(std::uint32_t deviceId = 0, const RouterClientSendOptions& options = {false, 0, 3000});
  void ApplyEmergencyStop(std::uint32_t deviceId = 0, const RouterClientSendOptions& options = {false, 0, 3000});
  void Stop(std::uint32_t deviceId = 0, const RouterClientSendOptions& options = {false, 0, 3000});
};
}  // namespace Base

// ---------------------------------------------------------------- ActuatorConfig.pb.h, ActuatorConfigClientRpc.h
namespace ActuatorConfig {
enum ControlMode { NONE = 0, POSITION = 1, VELOCITY = 2, TORQUE = 3, CURRENT = 4, CUSTOM = 5, TORQUE_HIGH_VELOCITY = 6 };

class ControlModeInformation {
public:
  void set_control_mode(ControlMode m) { control_mode_ = m; }
  ControlMode control_mode() const { return control_mode_; }

private:
  ControlMode control_mode_ = NONE;
};

class ActuatorConfigClient {
public:
  explicit ActuatorConfigClient(IRouterClient* clientRouter);
  void SetControlMode(const ControlModeInformation& mode, std::uint32_t deviceId = 0,
                      const RouterClientSendOptions& options = {false, 0, 3000});
  ControlModeInformation GetControlMode(std::uint32_t deviceId = 0, const RouterClientSendOptions& options = {false, 0, 3000});
  void ClearFaults(std::uint32_t deviceId = 0, const RouterClientSendOptions& options = {false, 0, 3000});
};
}  // namespace ActuatorConfig

// ---------------------------------------------------------------- BaseCyclic.pb.h, BaseCyclicClientRpc.h
namespace BaseCyclic {
class ActuatorCommand {
public:
  std::uint32_t command_id() const { return command_id_; }
  std::uint32_t flags() const { return flags_; }
  float position() const { return position_; }
  float velocity() const { return velocity_; }
  float torque_joint() const { return torque_joint_; }
  float current_motor() const { return current_motor_; }
  void set_command_id(std::uint32_t v) { command_id_ = v; }
  void set_flags(std::uint32_t v) { flags_ = v; }
  void set_position(float v) { position_ = v; }
  void set_velocity(float v) { velocity_ = v; }
  void set_torque_joint(float v) { torque_joint_ = v; }
  void set_current_motor(float v) { current_motor_ = v; }

private:
  std::uint32_t command_id_ = 0, flags_ = 0;
  float position_ = 0, velocity_ = 0, torque_joint_ = 0, current_motor_ = 0;
};

class Command {
public:
  std::uint32_t frame_id() const { return frame_id_; }
  void set_frame_id(std::uint32_t v) { frame_id_ = v; }
  ActuatorCommand* add_actuators() { return &actuators_.emplace_back(); }
  ActuatorCommand* mutable_actuators(int i) { return &actuators_.at(static_cast<std::size_t>(i)); }
  const ActuatorCommand& actuators(int i) const { return actuators_.at(static_cast<std::size_t>(i)); }
  const std::vector<ActuatorCommand>& actuators() const { return actuators_; }
  int actuators_size() const { return static_cast<int>(actuators_.size()); }

private:
  std::uint32_t frame_id_ = 0;
  std::vector<ActuatorCommand> actuators_;
};

class ActuatorFeedback {
public:
  std::uint32_t command_id() const { return command_id_; }
  std::uint32_t status_flags() const { return status_flags_; }
  std::uint32_t jitter_comm() const { return jitter_comm_; }
  float position() const { return position_; }
  float velocity() const { return velocity_; }
  float torque() const { return torque_; }
  float current_motor() const { return current_motor_; }
  float voltage() const { return voltage_; }
  float temperature_motor() const { return temperature_motor_; }
  float temperature_core() const { return temperature_core_; }
  std::uint32_t fault_bank_a() const { return fault_bank_a_; }
  std::uint32_t fault_bank_b() const { return fault_bank_b_; }
  std::uint32_t warning_bank_a() const { return warning_bank_a_; }
  std::uint32_t warning_bank_b() const { return warning_bank_b_; }
  void set_command_id(std::uint32_t v) { command_id_ = v; }
  void set_status_flags(std::uint32_t v) { status_flags_ = v; }
  void set_position(float v) { position_ = v; }
  void set_velocity(float v) { velocity_ = v; }
  void set_torque(float v) { torque_ = v; }
  void set_current_motor(float v) { current_motor_ = v; }
  void set_fault_bank_a(std::uint32_t v) { fault_bank_a_ = v; }
  void set_warning_bank_a(std::uint32_t v) { warning_bank_a_ = v; }

private:
  std::uint32_t command_id_ = 0, status_flags_ = 0, jitter_comm_ = 0;
  float position_ = 0, velocity_ = 0, torque_ = 0, current_motor_ = 0, voltage_ = 24, temperature_motor_ = 30,
        temperature_core_ = 30;
  std::uint32_t fault_bank_a_ = 0, fault_bank_b_ = 0, warning_bank_a_ = 0, warning_bank_b_ = 0;
};

class BaseFeedback {
public:
  Common::ArmState active_state() const { return active_state_; }
  std::uint32_t fault_bank_a() const { return fault_bank_a_; }
  std::uint32_t fault_bank_b() const { return fault_bank_b_; }
  std::uint32_t warning_bank_a() const { return warning_bank_a_; }
  std::uint32_t warning_bank_b() const { return warning_bank_b_; }
  void set_active_state(Common::ArmState s) { active_state_ = s; }

private:
  Common::ArmState active_state_ = Common::ARMSTATE_UNSPECIFIED;
  std::uint32_t fault_bank_a_ = 0, fault_bank_b_ = 0, warning_bank_a_ = 0, warning_bank_b_ = 0;
};

class Feedback {
public:
  std::uint32_t frame_id() const { return frame_id_; }
  void set_frame_id(std::uint32_t v) { frame_id_ = v; }
  const BaseFeedback& base() const { return base_; }
  BaseFeedback* mutable_base() { return &base_; }
  const ActuatorFeedback& actuators(int i) const { return actuators_.at(static_cast<std::size_t>(i)); }
  ActuatorFeedback* mutable_actuators(int i) { return &actuators_.at(static_cast<std::size_t>(i)); }
  ActuatorFeedback* add_actuators() { return &actuators_.emplace_back(); }
  const std::vector<ActuatorFeedback>& actuators() const { return actuators_; }
  int actuators_size() const { return static_cast<int>(actuators_.size()); }

private:
  std::uint32_t frame_id_ = 0;
  BaseFeedback base_;
  std::vector<ActuatorFeedback> actuators_;
};

class BaseCyclicClient {
public:
  explicit BaseCyclicClient(IRouterClient* clientRouter);
  Feedback Refresh(const Command& command, std::uint32_t deviceId = 0, const RouterClientSendOptions& options = {false, 0, 3000});
  Feedback RefreshFeedback(std::uint32_t deviceId = 0, const RouterClientSendOptions& options = {false, 0, 3000});
};
}  // namespace BaseCyclic

}  // namespace Api
}  // namespace Kinova

// ---------------------------------------------------------------- the in-memory arm behind the double
namespace kortex_sdk_double {

struct Arm {
  int actuator_count = 7;
  bool reachable = true;  ///< false: TransportClient*::connect returns false
  Kinova::Api::Base::ServoingMode servoing = Kinova::Api::Base::SINGLE_LEVEL_SERVOING;
  Kinova::Api::Common::ArmState arm_state = Kinova::Api::Common::ARMSTATE_SERVOING_READY;
  std::vector<Kinova::Api::ActuatorConfig::ControlMode> modes;
  std::vector<float> position_deg;  ///< what the actuators read
  std::vector<std::string> calls;   ///< "SetControlMode device 3 TORQUE", ...
  std::vector<std::uint32_t> timeouts_ms;  ///< RouterClientSendOptions::timeout_ms of each Refresh
  Kinova::Api::BaseCyclic::Command last_command;
  int sessions = 0;
  // failures injected into the next Refresh: a KDetailedException with this sub-code, or a
  // std::runtime_error "timeout detected" (as the SDK's future times out)
  Kinova::Api::SubErrorCodes fail_next_refresh = Kinova::Api::SUB_ERROR_NONE;
  bool time_out_next_refresh = false;
  Kinova::Api::SubErrorCodes fail_next_config = Kinova::Api::SUB_ERROR_NONE;
};

/// The one arm every double object talks to; reset() puts it back to the defaults for n actuators.
Arm& arm();
void reset(int actuator_count = 7);

}  // namespace kortex_sdk_double
