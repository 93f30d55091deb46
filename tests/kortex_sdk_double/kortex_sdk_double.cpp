// The in-memory behaviour of the Kortex SDK double (include/kortex_sdk_double.h).
#include "kortex_sdk_double.h"

namespace kortex_sdk_double {

namespace {
Arm fresh_arm(int actuator_count) {
  Arm a;
  a.actuator_count = actuator_count;
  a.modes.assign(static_cast<std::size_t>(actuator_count), Kinova::Api::ActuatorConfig::POSITION);
  a.position_deg.assign(static_cast<std::size_t>(actuator_count), 10.0f);
  return a;
}
}  // namespace

Arm& arm() {
  static Arm the_arm = fresh_arm(7);
  return the_arm;
}

void reset(int actuator_count) { arm() = fresh_arm(actuator_count); }

namespace {
void note(const std::string& call) { arm().calls.push_back(call); }

[[noreturn]] void fail(Kinova::Api::SubErrorCodes sub) {
  Kinova::Api::Error error;
  error.set_error_code(Kinova::Api::ERROR_DEVICE);
  error.set_error_sub_code(sub);
  error.set_error_sub_string(Kinova::Api::SubErrorCodes_Name(sub));
  throw Kinova::Api::KDetailedException(Kinova::Api::KError(error));
}

void config_call(const std::string& call) {
  note(call);
  Arm& a = arm();
  if (a.sessions == 0) fail(Kinova::Api::INVALID_SESSION);
  if (a.fail_next_config != Kinova::Api::SUB_ERROR_NONE) {
    const auto sub = a.fail_next_config;
    a.fail_next_config = Kinova::Api::SUB_ERROR_NONE;
    fail(sub);
  }
}

const char* mode_name(Kinova::Api::ActuatorConfig::ControlMode m) {
  static const char* names[] = {"NONE", "POSITION", "VELOCITY", "TORQUE", "CURRENT", "CUSTOM", "TORQUE_HIGH_VELOCITY"};
  return m >= 0 && m <= 6 ? names[m] : "?";
}

Kinova::Api::BaseCyclic::Feedback feedback_now() {
  Arm& a = arm();
  Kinova::Api::BaseCyclic::Feedback f;
  f.set_frame_id(a.last_command.frame_id());
  f.mutable_base()->set_active_state(a.servoing == Kinova::Api::Base::LOW_LEVEL_SERVOING ? Kinova::Api::Common::ARMSTATE_SERVOING_LOW_LEVEL
                                                                                        : a.arm_state);
  for (int i = 0; i < a.actuator_count; ++i) {
    Kinova::Api::BaseCyclic::ActuatorFeedback* fb = f.add_actuators();
    fb->set_position(a.position_deg[static_cast<std::size_t>(i)]);
    if (i < a.last_command.actuators_size()) {
      const auto& c = a.last_command.actuators(i);
      fb->set_command_id(c.command_id());
      fb->set_torque(-c.torque_joint());  // reported reversed, as the real arm does
      fb->set_current_motor(c.current_motor());
    }
  }
  return f;
}
}  // namespace

}  // namespace kortex_sdk_double

namespace Kinova::Api {
using kortex_sdk_double::arm;
using kortex_sdk_double::config_call;
using kortex_sdk_double::note;

std::string ErrorCodes_Name(ErrorCodes code) {
  static const char* names[] = {"ERROR_NONE", "ERROR_PROTOCOL_SERVER", "ERROR_PROTOCOL_CLIENT", "ERROR_DEVICE", "ERROR_INTERNAL"};
  return code >= 0 && code <= 4 ? names[code] : "ERROR_UNKNOWN";
}

std::string SubErrorCodes_Name(SubErrorCodes code) {
  switch (code) {
    case INVALID_SESSION: return "INVALID_SESSION";
    case WRONG_SERVOING_MODE: return "WRONG_SERVOING_MODE";
    case METHOD_TIMEOUT: return "METHOD_TIMEOUT";
    case INVALID_PARAM: return "INVALID_PARAM";
    case ROBOT_IN_FAULT: return "ROBOT_IN_FAULT";
    default: return "SUB_ERROR_" + std::to_string(static_cast<int>(code));
  }
}

TransportClientTcp::TransportClientTcp(bool) {}
bool TransportClientTcp::connect(std::string host, std::uint32_t port) {
  note("TCP connect " + host + ":" + std::to_string(port));
  return arm().reachable;
}
void TransportClientTcp::disconnect() { note("TCP disconnect"); }

TransportClientUdp::TransportClientUdp(bool) {}
bool TransportClientUdp::connect(std::string host, std::uint32_t port) {
  note("UDP connect " + host + ":" + std::to_string(port));
  return arm().reachable;
}
void TransportClientUdp::disconnect() { note("UDP disconnect"); }

RouterClient::RouterClient(ITransportClient* transport, std::function<void(KError)> errorCallback)
    : transport_(transport), error_callback_(std::move(errorCallback)) {}
void RouterClient::SetActivationStatus(bool isActive) { note(std::string("SetActivationStatus ") + (isActive ? "true" : "false")); }

SessionManager::SessionManager(IRouterClient* router, std::function<void()>) : router_(router) {}
void SessionManager::CreateSession(const Session::CreateSessionInfo& info) {
  note("CreateSession " + info.username() + " " + std::to_string(info.session_inactivity_timeout()) + " " +
       std::to_string(info.connection_inactivity_timeout()));
  ++arm().sessions;
}
void SessionManager::CloseSession() {
  note("CloseSession");
  --arm().sessions;
}

namespace Base {
BaseClient::BaseClient(IRouterClient*) {}
void BaseClient::SetServoingMode(const ServoingModeInformation& mode, std::uint32_t, const RouterClientSendOptions&) {
  config_call("SetServoingMode " + std::to_string(static_cast<int>(mode.servoing_mode())));
  arm().servoing = mode.servoing_mode();
}
ServoingModeInformation BaseClient::GetServoingMode(std::uint32_t, const RouterClientSendOptions&) {
  config_call("GetServoingMode");
  ServoingModeInformation info;
  info.set_servoing_mode(arm().servoing);
  return info;
}
ActuatorInformation BaseClient::GetActuatorCount(std::uint32_t, const RouterClientSendOptions&) {
  config_call("GetActuatorCount");
  ActuatorInformation info;
  info.set_count(static_cast<std::uint32_t>(arm().actuator_count));
  return info;
}
ArmStateInformation BaseClient::GetArmState(std::uint32_t, const RouterClientSendOptions&) {
  config_call("GetArmState");
  ArmStateInformation info;
  info.set_active_state(arm().arm_state);
  return info;
}
void BaseClient::ClearFaults(std::uint32_t, const RouterClientSendOptions&) { config_call("ClearFaults"); }
void BaseClient::ApplyEmergencyStop(std::uint32_t, const RouterClientSendOptions& options) {
  config_call("ApplyEmergencyStop timeout " + std::to_string(options.timeout_ms));
}
void BaseClient::Stop(std::uint32_t, const RouterClientSendOptions&) { config_call("Stop"); }
}  // namespace Base

namespace ActuatorConfig {
ActuatorConfigClient::ActuatorConfigClient(IRouterClient*) {}
void ActuatorConfigClient::SetControlMode(const ControlModeInformation& mode, std::uint32_t deviceId, const RouterClientSendOptions&) {
  config_call("SetControlMode device " + std::to_string(deviceId) + " " + kortex_sdk_double::mode_name(mode.control_mode()));
  if (deviceId < 1 || deviceId > static_cast<std::uint32_t>(arm().actuator_count)) kortex_sdk_double::fail(INVALID_DEVICE);
  arm().modes[deviceId - 1] = mode.control_mode();
}
ControlModeInformation ActuatorConfigClient::GetControlMode(std::uint32_t deviceId, const RouterClientSendOptions&) {
  config_call("GetControlMode device " + std::to_string(deviceId));
  ControlModeInformation info;
  info.set_control_mode(arm().modes.at(deviceId - 1));
  return info;
}
void ActuatorConfigClient::ClearFaults(std::uint32_t deviceId, const RouterClientSendOptions&) {
  config_call("ActuatorClearFaults device " + std::to_string(deviceId));
}
}  // namespace ActuatorConfig

namespace BaseCyclic {
BaseCyclicClient::BaseCyclicClient(IRouterClient*) {}
Feedback BaseCyclicClient::Refresh(const Command& command, std::uint32_t, const RouterClientSendOptions& options) {
  kortex_sdk_double::Arm& a = arm();
  a.timeouts_ms.push_back(options.timeout_ms);
  if (a.time_out_next_refresh) {
    a.time_out_next_refresh = false;
    throw std::runtime_error("timeout detected: BaseCyclicClient::Refresh");
  }
  if (a.fail_next_refresh != SUB_ERROR_NONE) {
    const auto sub = a.fail_next_refresh;
    a.fail_next_refresh = SUB_ERROR_NONE;
    kortex_sdk_double::fail(sub);
  }
  if (a.sessions == 0) kortex_sdk_double::fail(INVALID_SESSION);
  if (a.servoing != Base::LOW_LEVEL_SERVOING) kortex_sdk_double::fail(WRONG_SERVOING_MODE);
  a.last_command = command;
  for (int i = 0; i < command.actuators_size() && i < a.actuator_count; ++i) {
    if (a.modes[static_cast<std::size_t>(i)] == ActuatorConfig::POSITION) a.position_deg[static_cast<std::size_t>(i)] = command.actuators(i).position();
  }
  return kortex_sdk_double::feedback_now();
}
Feedback BaseCyclicClient::RefreshFeedback(std::uint32_t, const RouterClientSendOptions&) {
  note("RefreshFeedback");
  if (arm().sessions == 0) kortex_sdk_double::fail(INVALID_SESSION);
  return kortex_sdk_double::feedback_now();
}
}  // namespace BaseCyclic

}  // namespace Kinova::Api
