#pragma once
// phri::KortexClient: exactly the Kortex API calls phri::KortexRobot needs, over plain data
// (hardware/kortex_messages.hpp). Two implementations:
//   KortexSdkClient   Kinova's Kortex C++ API (TCP 10000 for sessions and configuration, UDP
//                     10001 for BaseCyclic at 1 kHz); hardware/kortex_sdk/, compiled when CMake is
//                     given -DPHRI_KORTEX_API_DIR (and in the tests against an SDK-shaped double)
//   KortexEmulator    in process, over a simulated plant, as the reference notes describe the arm
//
// Actuators are addressed by index 0..n-1, base to wrist (the SDK's device id is index + 1, as in
// Kinova's example 108 and mc_kortex). Every call returns a CallStatus and never throws; refresh()
// and refresh_feedback() are the cycle's calls (the emulator's allocate nothing; the SDK's own
// protobuf code may).
#include <phri/hardware/kortex_messages.hpp>

#include <string>

namespace phri {

class KortexClient {
public:
  virtual ~KortexClient() = default;
  KortexClient() = default;
  KortexClient(const KortexClient&) = delete;
  KortexClient& operator=(const KortexClient&) = delete;

  // ---- Session (one on the TCP router, one on the UDP router)
  virtual kortex::CallStatus create_sessions(const kortex::SessionSettings& settings) = 0;
  virtual kortex::CallStatus close_sessions() = 0;

  // ---- Base (TCP)
  virtual kortex::CallStatus actuator_count(int& count) = 0;
  virtual kortex::CallStatus arm_state(kortex::ArmState& state) = 0;
  virtual kortex::CallStatus servoing_mode(kortex::ServoingMode& mode) = 0;
  virtual kortex::CallStatus set_servoing_mode(kortex::ServoingMode mode) = 0;
  virtual kortex::CallStatus clear_faults() = 0;
  virtual kortex::CallStatus stop() = 0;
  virtual kortex::CallStatus apply_emergency_stop() = 0;

  // ---- ActuatorConfig (TCP), per actuator
  virtual kortex::CallStatus set_control_mode(int actuator, kortex::ControlMode mode) = 0;

  // ---- BaseCyclic (UDP, 1 kHz)
  /// Sends `command`, fills `feedback` (sized by the caller: one entry per actuator).
  virtual kortex::CallStatus refresh(const kortex::CyclicCommand& command, kortex::CyclicFeedback& feedback) noexcept = 0;
  /// The feedback alone (no command).
  virtual kortex::CallStatus refresh_feedback(kortex::CyclicFeedback& feedback) noexcept = 0;

  /// The link's time base [s]: the host's steady clock for the real arm, the simulated time for
  /// the emulator (whose stalls and lost packets take simulated time).
  virtual double clock_s() const noexcept = 0;
  /// "kortex 192.168.1.10", "kortex emulator": the subject of error messages.
  virtual std::string describe() const = 0;
  /// What the latest failed call said (an SDK exception's text), for messages outside the cycle.
  virtual std::string last_error_text() const { return {}; }
};

}  // namespace phri
