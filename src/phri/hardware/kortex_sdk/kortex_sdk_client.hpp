#pragma once
// phri::KortexSdkClient: phri::KortexClient over Kinova's Kortex C++ API (the binary SDK, not
// packaged; kortex_sdk_api.md). Compiled only when CMake is given -DPHRI_KORTEX_API_DIR=<the
// unpacked SDK> (target phri_kortex_sdk, linked into `phri`), and in the tests against the
// SDK-shaped double in tests/kortex_sdk_double/. Its header names no SDK type, so the rest of
// phri builds without the SDK.
//
// Objects and order (kortex_sdk_api.md section 3, Kinova's example 108, ros2_kortex): one TCP
// transport (port 10000: sessions, Base, ActuatorConfig) and one UDP transport (port 10001:
// BaseCyclic at 1 kHz), each with its RouterClient and SessionManager; teardown CloseSession ->
// SetActivationStatus(false) -> disconnect. Actuator i is device id i + 1 (example 108, mc_kortex).
// Every SDK exception becomes a CallStatus: KDetailedException -> its error code and sub-code;
// another std::exception (the SDK's "timeout detected: ...") -> METHOD_TIMEOUT; its text is kept
// for last_error_text(). The Refresh messages are members, sized once; the SDK's own protobuf
// code and futures still allocate inside Refresh (not phri's to avoid).
#include <phri/hardware/kortex_client.hpp>

#include <cstdint>
#include <memory>
#include <string>

namespace phri {

struct KortexSdkSettings {
  std::string ip = "192.168.1.10";     ///< the arm's factory address (Kinova's examples)
  std::uint32_t tcp_port = 10000;
  std::uint32_t udp_port = 10001;
  std::uint32_t config_timeout_ms = 3000;  ///< the SDK's default per-call timeout
  /// Refresh's timeout: a cycle is 1 ms; 3 ms lets a late answer through, then the call fails and
  /// KortexRobot counts it (its bound: 3 failures or 5 ms). Not from Kinova: chosen here.
  std::uint32_t cyclic_timeout_ms = 3;
};

class KortexSdkClient final : public KortexClient {
public:
  /// Connects both transports; throws HardwareError when the arm does not answer.
  explicit KortexSdkClient(KortexSdkSettings settings = {});
  ~KortexSdkClient() override;

  kortex::CallStatus create_sessions(const kortex::SessionSettings& settings) override;
  kortex::CallStatus close_sessions() override;
  kortex::CallStatus actuator_count(int& count) override;
  kortex::CallStatus arm_state(kortex::ArmState& state) override;
  kortex::CallStatus servoing_mode(kortex::ServoingMode& mode) override;
  kortex::CallStatus set_servoing_mode(kortex::ServoingMode mode) override;
  kortex::CallStatus clear_faults() override;
  kortex::CallStatus stop() override;
  kortex::CallStatus apply_emergency_stop() override;
  kortex::CallStatus set_control_mode(int actuator, kortex::ControlMode mode) override;
  kortex::CallStatus refresh(const kortex::CyclicCommand& command, kortex::CyclicFeedback& feedback) noexcept override;
  kortex::CallStatus refresh_feedback(kortex::CyclicFeedback& feedback) noexcept override;
  double clock_s() const noexcept override;
  std::string describe() const override { return "kortex " + settings_.ip; }
  std::string last_error_text() const override { return last_error_; }

private:
  struct Sdk;  // the SDK's objects (kortex_sdk_client.cpp)
  template <class Call>
  kortex::CallStatus guarded(Call&& call) noexcept;

  KortexSdkSettings settings_;
  std::unique_ptr<Sdk> sdk_;
  std::string last_error_;
  bool sessions_ = false;
};

}  // namespace phri
