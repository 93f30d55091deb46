#pragma once
// phri::KortexEmulator: a Kinova Gen3 in Kortex low-level servoing, in process, over a simulated
// plant (any RobotInterface; phri::SimRobot in practice), behaving as the project's Kortex notes
// describe the arm (kortex_lowlevel.md, kortex_sdk_api.md):
//
//   * Refresh is answered only in LOW_LEVEL_SERVOING (else WRONG_SERVOING_MODE, 75) and only with
//     a session open (else INVALID_SESSION, 12); each Refresh is one control period of the plant
//     (the actuators run at 1 kHz whether or not a command arrived).
//   * Units: positions in degrees, [0, 360) in feedback and commands; deg/s; the measured torque
//     reported with the reversed sign; the motor current in A.
//   * Control modes per actuator: POSITION (position), TORQUE and TORQUE_HIGH_VELOCITY
//     (torque_joint), CURRENT (current_motor), run by the plant's matching loop (LowLevelMode);
//     all actuators must share one mode when a command is applied (the plant has one mode), and
//     VELOCITY / CUSTOM / NONE are refused (INVALID_PARAM): phri does not use them.
//   * Following error: in TORQUE / CURRENT modes |position - measured| beyond 5 deg faults the
//     actuator (FOLLOWING_ERROR; warning beyond 3 deg): Kinova issue #26, user guide p. 85.
//   * Watchdog: no command for longer than watchdog_timeout_s in low level -> WATCHDOG_TRIGGERED
//     on every actuator. The real timeout is not public ("not found" in the notes): 10 ms here.
//   * Session inactivity: no call for session_inactivity_timeout_ms closes the session.
//   * A fault (any actuator bit, an emergency stop) puts the arm in ARMSTATE_IN_FAULT and the
//     actuators hold their measured pose (the plant's position loop), ignoring commands, until
//     ClearFaults; the control modes are then POSITION.
//   * Configuration calls (TCP) take no simulated time.
//
// Fault injection for tests: packet loss (each Refresh lost with a probability: the command never
// arrives, the call times out, METHOD_TIMEOUT), stalls (the next Refresh takes N ms of plant time,
// then times out), a dropped session, actuator faults and warnings, a wrong actuator count.
//
// Every call is recorded (calls()) in a buffer sized at construction: refresh() and
// set_control_mode() allocate nothing.
#include <phri/hardware/kortex_client.hpp>
#include <phri/robot/robot_interface.hpp>

#include <cstdint>
#include <random>
#include <string>
#include <vector>

namespace phri {

struct KortexEmulatorSettings {
  double watchdog_timeout_s = 0.010;     ///< assumed (the notes: "watchdog timeout value: not found")
  double following_error_deg = 5.0;      ///< fault threshold (Kinova issue #26; UG default error)
  double following_warning_deg = 3.0;    ///< warning threshold (UG default warning)
  double packet_loss_probability = 0.0;  ///< each Refresh lost with this probability
  std::uint64_t seed = 1;                ///< of the packet loss draws
  std::size_t call_capacity = 1 << 16;   ///< calls recorded at most
};

/// A communication fault the emulator injects by itself once its plant's clock reaches at_s
/// (`phri run --backend kortex-emulator --emulate-fault`).
struct ScheduledKortexFault {
  enum class Kind { kNone, kPacketLoss, kStall, kDroppedSession };
  Kind kind = Kind::kNone;
  double value = 0.0;  ///< kPacketLoss: the probability; kStall: the stall [s]
  double at_s = 0.0;   ///< plant time [s]

  /// "packet-loss:P@T" (0 < P <= 1), "stall:MS@T" (1..1000 ms) or "drop-session@T" (T >= 0 s);
  /// a ConfigError naming `option` otherwise.
  static ScheduledKortexFault parse(const std::string& text, const std::string& option);
};

class KortexEmulator final : public KortexClient {
public:
  enum class CallKind : std::uint8_t {
    kCreateSessions, kCloseSessions, kActuatorCount, kArmState, kServoingMode, kSetServoingMode,
    kClearFaults, kStop, kEmergencyStop, kSetControlMode, kRefreshFeedback,
  };
  /// A configuration call (Refresh calls are counted, not recorded): its kind, the actuator
  /// (-1: none), the mode asked (ServoingMode or ControlMode value), the plant time [s].
  struct Call {
    CallKind kind;
    int actuator = -1;
    std::uint32_t value = 0;
    double time_s = 0.0;
  };
  struct Counters {
    std::uint64_t refreshes = 0, commands_applied = 0, lost_packets = 0, stalls = 0, refused_refreshes = 0;
    std::uint64_t watchdog_trips = 0, following_errors = 0, session_timeouts = 0;
  };

  /// `plant_initial` is the plant's state before its first read() (SimRobot::state()).
  KortexEmulator(RobotInterface& plant, const RobotState& plant_initial, KortexEmulatorSettings settings = {});

  // ---- KortexClient
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
  double clock_s() const noexcept override { return plant_state_->time_s; }
  std::string describe() const override { return "kortex emulator"; }

  // ---- fault injection
  void set_packet_loss(double probability, std::uint64_t seed);
  /// One fault injected by the emulator itself at its time (replaces any earlier schedule).
  void schedule(const ScheduledKortexFault& fault) { scheduled_ = fault; }
  /// The next Refresh takes `seconds` of plant time (the arm on its last command), then times out.
  void stall_next_refresh(double seconds) { stall_periods_ = periods(seconds); }
  /// The arm closes the sessions (as on a network drop); calls fail with INVALID_SESSION.
  void drop_session() { sessions_open_ = false; }
  void inject_fault(int actuator, std::uint32_t fault_bank_a);
  void inject_warning(int actuator, std::uint32_t warning_bank_a) { warning_a_[index(actuator)] = warning_bank_a; }
  /// GetActuatorCount answers this (default: the plant's joint count).
  void set_reported_actuator_count(int count) { reported_count_ = count; }
  /// Plant time passes with no call at all (the client is gone or stalled).
  void run_idle(double seconds);

  // ---- observation
  const std::vector<Call>& calls() const { return calls_; }
  const Counters& counters() const { return counters_; }
  const RobotState& plant_state() const { return *plant_state_; }
  const RobotCommand& plant_command() const { return plant_command_; }
  kortex::ControlMode control_mode(int actuator) const { return modes_[index(actuator)]; }
  kortex::ServoingMode servoing() const { return servoing_; }
  kortex::ArmState arm_state() const;
  bool sessions_open() const { return sessions_open_; }
  bool holding() const { return holding_; }
  std::uint32_t fault_bank_a(int actuator) const { return fault_a_[index(actuator)]; }
  const kortex::CyclicCommand& last_command() const { return last_command_; }
  const KortexEmulatorSettings& settings() const { return settings_; }

private:
  std::size_t index(int actuator) const { return static_cast<std::size_t>(actuator); }
  long periods(double seconds) const;
  void record(CallKind kind, int actuator = -1, std::uint32_t value = 0);
  kortex::CallStatus session_check();
  bool any_fault() const;
  kortex::CallStatus apply(const kortex::CyclicCommand& command);
  bool check_following_error(const kortex::CyclicCommand& command);
  void step(bool command_arrived);
  void hold();
  void fill(kortex::CyclicFeedback& feedback) const;

  RobotInterface& plant_;
  const RobotState* plant_state_;
  KortexEmulatorSettings settings_;
  int n_;
  double period_;
  int reported_count_;
  std::mt19937_64 random_;
  std::vector<Call> calls_;
  Counters counters_;
  RobotCommand plant_command_;
  kortex::CyclicCommand last_command_;
  std::vector<kortex::ControlMode> modes_;
  std::vector<std::uint32_t> fault_a_, warning_a_;
  kortex::ServoingMode servoing_ = kortex::ServoingMode::kSingleLevel;
  bool sessions_open_ = false, estop_ = false, holding_ = false;
  ScheduledKortexFault scheduled_;
  kortex::SessionSettings session_;
  double last_command_s_ = 0.0, last_activity_s_ = 0.0;
  long stall_periods_ = 0;
};

}  // namespace phri
