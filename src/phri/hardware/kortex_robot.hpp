#pragma once
// phri::KortexRobot: the Kinova Gen3 in Kortex low-level servoing behind phri::RobotInterface,
// over a phri::KortexClient (Kinova's SDK, or the in-process KortexEmulator).
//
//   phri::KortexEmulator arm(plant, plant.state());         // or phri::KortexSdkClient arm("192.168.1.10")
//   phri::KortexRobot robot(arm, settings);                 // start-up sequence and checks (may throw)
//   ... the control loop: robot.read(), robot.write(cmd) ... // allocation-free, never throws
//   // destructor: every actuator back to POSITION, SINGLE_LEVEL_SERVOING, sessions closed
//
// Start-up (kortex_lowlevel.md section 5, Kinova's example 108 and ros2_kortex): sessions;
// actuator count == dof; the arm not in fault; SINGLE_LEVEL_SERVOING then LOW_LEVEL_SERVOING;
// the first feedback: arm state ARMSTATE_SERVOING_LOW_LEVEL, no actuator or base fault, every
// bounded joint within its limits; one Refresh holding the measured pose; every actuator
// SetControlMode(POSITION). A refusal is a phri::HardwareError with one line naming the reason,
// after the arm is put back (POSITION, SINGLE_LEVEL, sessions closed).
//
// The cycle. read() sends the command stored by the last write() in one BaseCyclic Refresh
// (frame_id +1 with the 16-bit wrap, every actuator's command_id = frame_id) and converts the
// feedback: degrees in [0, 360) -> radians in (-pi, pi], continuous joints (infinite limits)
// unwrapped so q never jumps; deg/s -> rad/s; the torque's sign flipped (Kinova reports it
// reversed); the motor current as it is. A change of LowLevelMode switches every actuator's
// ControlMode (ActuatorConfig.SetControlMode, as mc_kortex does from its cyclic thread) before the
// Refresh that carries the new set-point:
//   kPosition -> POSITION                 position = q_des [deg, 0..360)
//   kKinovaTorque -> TORQUE               torque_joint = tau_des, position = the measured position
//   kKinovaTorqueHighVelocity -> TORQUE_HIGH_VELOCITY   (same fields as TORQUE)
//   kCurrent -> CURRENT                   current_motor = i_des, position = the measured position
// In the torque and current modes the actuators compare `position` with their reading (following
// error beyond 5 deg, Kinova issue #26): the measured position is echoed. Both torque fields are
// filled in every torque/current mode, the other through K_T G_r (i = tau / (K_T G_r)), so a field
// the actuator reads is never stale. kTorque (a generic drive's plain torque) is not a Kortex mode:
// refused with kInvalidMode.
//
// Faults: any actuator or base fault bit, or the arm in ARMSTATE_IN_FAULT, sets RobotState::fault
// (the supervisor's robot_fault: a safe stop); the banks and warnings are in health(). A write
// while the arm is in fault, or after the link was lost, is refused (kFault).
//
// Communication loss: `max_failed_refreshes` failed Refresh calls in a row, or none good for
// `max_silence_s`, and the robot stops commanding torque for good: every actuator back to
// POSITION holding the last measured pose (the arm's own position hold; it keeps being sent if
// the link comes back), RobotState::fault set, one line written to `log`. Without a link at all
// the arm's watchdog brakes it.
//
// A degraded link: more than `max_loss_fraction` of the Refresh calls of the last `loss_window_s`
// failed (at 1 kHz each loss leaves the arm on a 2 ms old set-point; 1 % is ten a second). The
// link still carries commands, so the robot asks for a safe stop (RobotState::stop_requested,
// latched; one line logged): the controller brakes on good samples, then commands the position
// hold, bumplessly; from that hold on, torque and current commands are refused (kFault).
//
// Dry run: the arm is only read; every Refresh holds the measured pose in POSITION, whatever is
// written (writes are accepted and ignored).
#include <phri/hardware/hardware_error.hpp>
#include <phri/hardware/kortex_client.hpp>
#include <phri/robot/robot_description.hpp>
#include <phri/robot/robot_interface.hpp>

#include <Eigen/Core>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <vector>

namespace phri {

struct KortexRobotSettings {
  int dof = 7;
  double period_s = 1e-3;
  /// Joint limits [rad]; an infinite pair marks a continuous joint (unwrapped). Empty: all continuous.
  Eigen::VectorXd position_lower_rad, position_upper_rad;
  /// A continuous joint's first reading is taken on the turn nearest to this (the run's home
  /// posture: the Gen3's joint 3 rests at pi, where the reading flips between +-180 deg). Empty: (-pi, pi].
  Eigen::VectorXd reference_q_rad;
  /// K_T G_r per joint [N.m/A] (actuators.yaml; Gen3: 11 large, 7.6 small).
  Eigen::VectorXd torque_per_amp_Nm_per_A;
  kortex::SessionSettings session;
  /// Communication loss: this many failed Refresh calls in a row...
  int max_failed_refreshes = 3;
  /// ...or no good feedback for this long [s]...
  double max_silence_s = 0.005;
  /// ...or more than this fraction of the Refresh calls of the last loss_window_s failed (0: any
  /// loss). 0.5 % of 5 s is 25: the 26th loss within 5 s stops. A 1 % loss stops within about
  /// 2.5 s; a 0.3 % one, 15 expected in 5 s, goes on (over 25 once in ~250 windows).
  double max_loss_fraction = 0.005;
  double loss_window_s = 5.0;  ///< [s], at least one period
  bool dry_run = false;
  /// Where the one line on a communication loss or an arm fault goes (null: nowhere).
  std::FILE* log = stderr;
  /// Fills the F/T fields of the state each read() (the Bota driver, the emulator's plant); may be empty.
  std::function<void(RobotState&)> wrench_source;
};

/// The settings a robot's description gives (robot/robot_description.hpp): joints, torque per amp
/// from its actuators, its home posture as the continuous joints' reference; the period is the
/// controller's. Joint limits are the caller's (the controller's model).
KortexRobotSettings kortex_robot_settings(const RobotDescription& robot, double period_s);

/// The arm's own report and the link's counters, refreshed by read().
struct KortexHealth {
  kortex::ArmState arm_state = kortex::ArmState::kUnspecified;
  kortex::BaseFeedback base;
  std::vector<std::uint32_t> fault_bank_a, fault_bank_b, warning_bank_a, warning_bank_b;  ///< per actuator
  bool arm_fault = false;  ///< a fault bit or ARMSTATE_IN_FAULT in the latest feedback (latched until a clean one)
  bool warning = false;    ///< a warning bit in the latest feedback
  bool link_lost = false;  ///< latched: communication loss handled (position hold)
  double link_lost_at_s = 0.0;
  bool link_degraded = false;  ///< latched: the loss rate asked for a safe stop
  double link_degraded_at_s = 0.0;
  std::uint64_t refreshes = 0, failed_refreshes = 0, mode_switches = 0, failed_mode_switches = 0;
  int consecutive_failures = 0, longest_failure_run = 0;
  int losses_in_window = 0, most_losses_in_window = 0;  ///< failed Refresh calls in the last loss_window_s
  kortex::CallStatus last_failure;
};

class KortexRobot final : public RobotInterface {
public:
  /// Runs the start-up sequence; throws HardwareError (one line) when the arm cannot be used,
  /// ConfigError on inconsistent settings.
  KortexRobot(KortexClient& client, KortexRobotSettings settings);
  ~KortexRobot() override;

  int dof() const override { return n_; }
  double period_s() const override { return settings_.period_s; }
  const RobotState& read() override;
  WriteStatus write(const RobotCommand& command) override;

  const KortexHealth& health() const { return health_; }
  const RobotState& state() const { return state_; }
  /// What the next (or, after read(), the last) Refresh carries / what it returned.
  const kortex::CyclicCommand& command() const { return command_; }
  const kortex::CyclicFeedback& feedback() const { return feedback_; }
  /// The ControlMode the actuators were last switched to.
  kortex::ControlMode control_mode() const { return active_mode_; }
  const KortexRobotSettings& settings() const { return settings_; }
  /// The client clock at robot time 0 [s] (RobotState::time_s = client clock - this).
  double clock_start_s() const { return clock_start_s_; }
  /// The exit sequence now (POSITION, SINGLE_LEVEL_SERVOING, sessions closed); idempotent, no throw.
  void shutdown() noexcept;

  static kortex::ControlMode control_mode_for(LowLevelMode mode);

private:
  void check_settings() const;
  void start_up();
  void check_first_feedback();
  [[noreturn]] void refuse(const std::string& reason);
  void check(kortex::CallStatus status, const char* what);
  bool switch_control_mode(kortex::ControlMode mode) noexcept;
  void publish_feedback() noexcept;
  void note_failure(kortex::CallStatus status) noexcept;
  void note_outcome(bool lost) noexcept;
  void enter_link_loss(const char* why) noexcept;
  void request_stop(const char* why) noexcept;
  void hold_measured_pose() noexcept;
  void update_health() noexcept;
  void log_line(const char* text) noexcept;
  WriteStatus validate(const RobotCommand& command) const noexcept;
  bool continuous(int i) const { return !std::isfinite(lower_[i]) || !std::isfinite(upper_[i]); }

  KortexClient& client_;
  KortexRobotSettings settings_;
  int n_;
  Eigen::VectorXd lower_, upper_, torque_per_amp_, reference_;
  kortex::CyclicCommand command_;
  kortex::CyclicFeedback feedback_;
  kortex::ControlMode active_mode_ = kortex::ControlMode::kPosition;
  kortex::ControlMode requested_mode_ = kortex::ControlMode::kPosition;
  LowLevelMode active_low_level_ = LowLevelMode::kPosition;
  LowLevelMode requested_low_level_ = LowLevelMode::kPosition;
  std::uint32_t frame_id_ = 0;
  double clock_start_s_ = 0.0;
  double last_good_s_ = 0.0;  // client clock of the last good feedback
  bool sessions_open_ = false, low_level_ = false, have_feedback_ = false;
  bool fault_logged_ = false;
  bool position_only_ = false;  // a degraded link's safe stop reached the position hold
  RobotState state_;
  KortexHealth health_;
  std::vector<std::uint8_t> loss_ring_;  // 1: that Refresh failed; the last loss_window_s of them
  std::size_t loss_next_ = 0;
  int max_losses_ = 0;                    // in the window; one more is a degraded link
  char line_[320] = {};
  char reason_[128] = {};
};

}  // namespace phri
