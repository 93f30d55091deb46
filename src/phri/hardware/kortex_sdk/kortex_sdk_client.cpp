#include <phri/hardware/kortex_sdk/kortex_sdk_client.hpp>

#include <phri/hardware/hardware_error.hpp>

// Kinova's Kortex API (flat includes, kortex_sdk_api.md section 2).
#include <ActuatorConfigClientRpc.h>
#include <BaseClientRpc.h>
#include <BaseCyclicClientRpc.h>
#include <KDetailedException.h>
#include <RouterClient.h>
#include <SessionManager.h>
#include <TransportClientTcp.h>
#include <TransportClientUdp.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <exception>

namespace k_api = Kinova::Api;

namespace phri {

struct KortexSdkClient::Sdk {
  // Members in construction order (ros2_kortex holds them the same way); destroyed in reverse.
  k_api::TransportClientTcp tcp_transport;
  k_api::RouterClient tcp_router{&tcp_transport, [](k_api::KError) {}};
  k_api::TransportClientUdp udp_transport;
  k_api::RouterClient udp_router{&udp_transport, [](k_api::KError) {}};
  k_api::SessionManager tcp_session{&tcp_router};
  k_api::SessionManager udp_session{&udp_router};
  k_api::Base::BaseClient base{&tcp_router};
  k_api::ActuatorConfig::ActuatorConfigClient actuator_config{&tcp_router};
  k_api::BaseCyclic::BaseCyclicClient cyclic{&udp_router};
  k_api::BaseCyclic::Command command;
  k_api::BaseCyclic::Feedback feedback;
};

KortexSdkClient::KortexSdkClient(KortexSdkSettings settings) : settings_(std::move(settings)), sdk_(std::make_unique<Sdk>()) {
  if (!sdk_->tcp_transport.connect(settings_.ip, settings_.tcp_port)) {
    throw HardwareError(describe(), "no answer on TCP " + std::to_string(settings_.tcp_port) +
                                        " (cable, the NIC's address on the arm's subnet, the arm powered and booted?)");
  }
  if (!sdk_->udp_transport.connect(settings_.ip, settings_.udp_port)) {
    sdk_->tcp_transport.disconnect();
    throw HardwareError(describe(), "no answer on UDP " + std::to_string(settings_.udp_port));
  }
}

KortexSdkClient::~KortexSdkClient() {
  close_sessions();
  sdk_->tcp_router.SetActivationStatus(false);
  sdk_->udp_router.SetActivationStatus(false);
  sdk_->tcp_transport.disconnect();
  sdk_->udp_transport.disconnect();
}

template <class Call>
kortex::CallStatus KortexSdkClient::guarded(Call&& call) noexcept {
  try {
    call();
    return kortex::CallStatus::success();
  } catch (k_api::KDetailedException& e) {
    const k_api::Error error = e.getErrorInfo().getError();
    try {
      last_error_ = e.what();
    } catch (...) {
    }
    return kortex::CallStatus::failure(static_cast<kortex::ErrorCode>(error.error_code()), error.error_sub_code());
  } catch (const std::exception& e) {  // the SDK's future timed out ("timeout detected: ...")
    try {
      last_error_ = e.what();
    } catch (...) {
    }
    return kortex::CallStatus::failure(kortex::ErrorCode::kProtocolClient, kortex::sub_error::kMethodTimeout);
  } catch (...) {
    return kortex::CallStatus::failure(kortex::ErrorCode::kInternal, kortex::sub_error::kMethodFailed);
  }
}

kortex::CallStatus KortexSdkClient::create_sessions(const kortex::SessionSettings& s) {
  k_api::Session::CreateSessionInfo info;
  info.set_username(s.username);
  info.set_password(s.password);
  info.set_session_inactivity_timeout(s.session_inactivity_timeout_ms);
  info.set_connection_inactivity_timeout(s.connection_inactivity_timeout_ms);
  const kortex::CallStatus status = guarded([&] {
    sdk_->tcp_session.CreateSession(info);
    sdk_->udp_session.CreateSession(info);
  });
  sessions_ = status.ok();
  return status;
}

kortex::CallStatus KortexSdkClient::close_sessions() {
  if (!sessions_) return kortex::CallStatus::success();
  sessions_ = false;
  return guarded([&] {
    sdk_->tcp_session.CloseSession();
    sdk_->udp_session.CloseSession();
  });
}

kortex::CallStatus KortexSdkClient::actuator_count(int& count) {
  return guarded([&] { count = static_cast<int>(sdk_->base.GetActuatorCount().count()); });
}

kortex::CallStatus KortexSdkClient::arm_state(kortex::ArmState& state) {
  return guarded([&] { state = static_cast<kortex::ArmState>(sdk_->base.GetArmState().active_state()); });
}

kortex::CallStatus KortexSdkClient::servoing_mode(kortex::ServoingMode& mode) {
  return guarded([&] { mode = static_cast<kortex::ServoingMode>(sdk_->base.GetServoingMode().servoing_mode()); });
}

kortex::CallStatus KortexSdkClient::set_servoing_mode(kortex::ServoingMode mode) {
  k_api::Base::ServoingModeInformation info;
  info.set_servoing_mode(static_cast<k_api::Base::ServoingMode>(mode));
  return guarded([&] { sdk_->base.SetServoingMode(info, 0, {false, 0, settings_.config_timeout_ms}); });
}

kortex::CallStatus KortexSdkClient::clear_faults() {
  return guarded([&] { sdk_->base.ClearFaults(0, {false, 0, settings_.config_timeout_ms}); });
}

kortex::CallStatus KortexSdkClient::stop() {
  return guarded([&] { sdk_->base.Stop(0, {false, 0, settings_.config_timeout_ms}); });
}

// ros2_kortex: {false, 0, 100} for the emergency stop (it must not wait 3 s).
kortex::CallStatus KortexSdkClient::apply_emergency_stop() {
  return guarded([&] { sdk_->base.ApplyEmergencyStop(0, {false, 0, 100}); });
}

kortex::CallStatus KortexSdkClient::set_control_mode(int actuator, kortex::ControlMode mode) {
  k_api::ActuatorConfig::ControlModeInformation info;
  info.set_control_mode(static_cast<k_api::ActuatorConfig::ControlMode>(mode));
  const auto device_id = static_cast<std::uint32_t>(actuator + 1);
  return guarded([&] { sdk_->actuator_config.SetControlMode(info, device_id, {false, 0, settings_.config_timeout_ms}); });
}

namespace {
void copy_feedback(const k_api::BaseCyclic::Feedback& from, kortex::CyclicFeedback& to) {
  to.frame_id = from.frame_id();
  const k_api::BaseCyclic::BaseFeedback& base = from.base();
  to.base.active_state = static_cast<kortex::ArmState>(base.active_state());
  to.base.fault_bank_a = base.fault_bank_a();
  to.base.fault_bank_b = base.fault_bank_b();
  to.base.warning_bank_a = base.warning_bank_a();
  to.base.warning_bank_b = base.warning_bank_b();
  const int n = std::min(from.actuators_size(), static_cast<int>(to.actuators.size()));
  for (int i = 0; i < n; ++i) {
    const k_api::BaseCyclic::ActuatorFeedback& a = from.actuators(i);
    kortex::ActuatorFeedback& b = to.actuators[static_cast<std::size_t>(i)];
    b.command_id = a.command_id();
    b.status_flags = a.status_flags();
    b.jitter_comm_us = a.jitter_comm();
    b.position_deg = a.position();
    b.velocity_deg_s = a.velocity();
    b.torque_Nm = a.torque();
    b.current_motor_A = a.current_motor();
    b.voltage_V = a.voltage();
    b.temperature_motor_C = a.temperature_motor();
    b.temperature_core_C = a.temperature_core();
    b.fault_bank_a = a.fault_bank_a();
    b.fault_bank_b = a.fault_bank_b();
    b.warning_bank_a = a.warning_bank_a();
    b.warning_bank_b = a.warning_bank_b();
  }
}
}  // namespace

kortex::CallStatus KortexSdkClient::refresh(const kortex::CyclicCommand& command, kortex::CyclicFeedback& feedback) noexcept {
  k_api::BaseCyclic::Command& c = sdk_->command;
  const kortex::CallStatus status = guarded([&] {
    while (c.actuators_size() < static_cast<int>(command.actuators.size())) c.add_actuators();  // first call only
    c.set_frame_id(command.frame_id);
    for (std::size_t i = 0; i < command.actuators.size(); ++i) {
      const kortex::ActuatorCommand& a = command.actuators[i];
      k_api::BaseCyclic::ActuatorCommand* out = c.mutable_actuators(static_cast<int>(i));
      out->set_command_id(a.command_id);
      out->set_flags(a.flags);
      out->set_position(a.position_deg);
      out->set_velocity(a.velocity_deg_s);
      out->set_torque_joint(a.torque_joint_Nm);
      out->set_current_motor(a.current_motor_A);
    }
    sdk_->feedback = sdk_->cyclic.Refresh(c, 0, {false, 0, settings_.cyclic_timeout_ms});
  });
  if (status.ok()) copy_feedback(sdk_->feedback, feedback);
  return status;
}

kortex::CallStatus KortexSdkClient::refresh_feedback(kortex::CyclicFeedback& feedback) noexcept {
  const kortex::CallStatus status =
      guarded([&] { sdk_->feedback = sdk_->cyclic.RefreshFeedback(0, {false, 0, settings_.config_timeout_ms}); });
  if (status.ok()) copy_feedback(sdk_->feedback, feedback);
  return status;
}

double KortexSdkClient::clock_s() const noexcept {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace phri
