#pragma once
// phri::LowLevelController: the last stage of the control cycle. It turns the QP's desired
// acceleration qdd_d and torque tau_d into a RobotCommand for the selected loop, and switches
// between loops at any cycle without a jump (paper: position control, Kinova's torque loops and
// the custom torque loop, switched live from the gamepad):
//
//   kPosition                 q_ref += T qd_ref, qd_ref += T qdd_d (the robot's position servo
//                             tracks q_ref); entered at the measured q, qd; kept within
//                             following_error_rad of the measured q when the servo cannot
//                             follow (a push it cannot resist), so q_ref never runs away
//   kKinovaTorque             tau_d to the vendor's torque loop
//   kKinovaTorqueHighVelocity tau_d to the vendor's high-velocity torque loop
//   kTorque                   tau_d to a generic drive's plain torque mode, plus the custom loop's
//                             friction and rotor-inertia feed-forward (no loop in the drive does it)
//                             (all three entered at the torque the motors produce: the set-point
//                             starts at the measured current x K_T G_r, or at tau_s without a
//                             current reading, and blends into tau_d, time constant 50 ms)
//   kCustom                   CustomTorqueController: motor current (reset bumplessly on entry
//                             from the current the drives carry)
//
// "The current the drives carry" is the measured current averaged over the cycles before the
// switch (first order, kEntryCurrentTime_s), not its last sample: the custom loop keeps its entry
// offset for its integrator's leak time (1 s), and one sample's noise would be a torque offset held
// that long (0.01 A of noise is 0.1 N.m through a generic drive's default K_T G_r, enough to spin a
// light wrist whose rotor inertia is a default too).
//
// A requested switch takes effect at the next update(); every switch is counted and its torque
// step (the change of the robot's measured motor torque across the switch is what a test checks)
// can be logged from switch_count() and last_switch_time().
#include <phri/lowlevel/custom_torque_controller.hpp>
#include <phri/robot/robot_command.hpp>
#include <phri/robot/robot_state.hpp>


namespace phri {

class LowLevelController {
public:
  /// following_error_rad: the position loop's re-sync bound, below Kinova's own following-error
  /// fault (5 degrees, kortex_lowlevel.md) so that the robot never faults on our reference.
  LowLevelController(const ActuatorTable& actuators, const CustomTorqueSettings& custom, LowLevelMode initial,
                     double following_error_rad = 0.05);

  /// Switch to `loop` at the next update (no effect if it is already running).
  void request(LowLevelMode loop) { requested_ = loop; }
  LowLevelMode loop() const { return loop_; }
  LowLevelMode requested() const { return requested_; }
  int switch_count() const { return switches_; }

  /// One control period: the command for the running loop, in `command` (sized for the robot).
  void update(const RobotState& state, const Eigen::VectorXd& tau_desired, const Eigen::VectorXd& qdd_desired,
              RobotCommand& command);

  /// Safe stop, torque side: `tau` [N.m] in the running torque or current loop's units (current:
  /// tau / K_T G_r, clipped to the current limit). In the position loop: nothing (use hold()).
  void command_torque(const Eigen::VectorXd& tau, RobotCommand& command);
  /// Safe stop, position side: the robot's position servo holds q from now on (the loop becomes
  /// kPosition; a later request() takes effect at the next update()).
  void hold(const Eigen::VectorXd& q, RobotCommand& command);

  /// Position-loop reference clamps so far (joint-cycles where the servo could not follow).
  long resync_count() const { return resyncs_; }
  /// The plain torque mode's feed-forward of this cycle (friction and rotor inertia) [N.m].
  const Eigen::VectorXd& plain_torque_feedforward() const { return feedforward_; }
  /// Vendor torque loops: the share of static friction added to tau_d at breakaway (stuck joint,
  /// desired acceleration beyond the friction model's threshold). Kinova's torque loop rejects only
  /// part of the gear friction through its torque-sensor feedback; without this a soft spring
  /// (posture, full-body end effector) stops short. 0: off (the paper's Kinova modes).
  static constexpr double kVendorBreakawayShare = 0.5;
  /// [s] Time constant of the measured current's average that loops are entered from: the noise
  /// of one sample divided by sqrt(2 tau / T) ~ 6; a current that changes across the switch lags by it.
  static constexpr double kEntryCurrentTime_s = 0.02;
  /// While the same joint stays stuck and asked the same way, its share grows by this per second,
  /// up to 1 (the whole modelled static friction).
  static constexpr double kBreakawayShareRate_per_s = 1.0;
  /// The assist goes on while a joint slides slower than this many times the friction model's
  /// velocity threshold (see update_friction_assist).
  static constexpr double kSlowSlideFactor = 3.0;
  /// Off: the share stays at kVendorBreakawayShare and slow slides get nothing (the controller
  /// turns it off while a hand carries the arm in full-body compliance, and in dual compliance
  /// once a hand has placed the end effector, where a joint held by friction is meant to stay put).
  void enable_breakaway_ramp(bool on) { breakaway_ramp_ = on; }
  const Eigen::VectorXd& breakaway() const { return breakaway_; }
  const CustomTorqueController& custom() const { return custom_; }
  const Eigen::VectorXd& position_reference() const { return q_ref_; }
  /// The position loop's re-sync bound [rad] (below the robot's following-error fault).
  double following_error() const { return following_error_rad_; }
  const Eigen::VectorXd& velocity_reference() const { return qd_ref_; }
  /// True once the position loop runs and stays requested: its reference is the integrated state.
  bool integrating_position() const {
    return started_ && loop_ == LowLevelMode::kPosition && requested_ == LowLevelMode::kPosition;
  }

private:
  void update_friction_assist(const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd_desired);
  void plain_torque_feedforward(const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd_desired);
  void saturate_to_drive_range(Eigen::VectorXd& tau) const;
  // The torque the motors produce now, as the torque loops' entry reads it: the averaged measured
  // current x K_T G_r (nominal), else tau_s.
  const Eigen::VectorXd& entry_torque(const RobotState& state);
  // Averages the measured current into measured_current_ (a running mean over the first samples
  // after a gap, then first order); false without a usable reading.
  bool track_current(const RobotState& state);
  CustomTorqueController custom_;
  double period_s_;
  LowLevelMode loop_;
  LowLevelMode requested_;
  bool started_ = false;
  int switches_ = 0;
  long resyncs_ = 0;
  double following_error_rad_;
  Eigen::VectorXd q_ref_, qd_ref_;
  Eigen::VectorXd torque_offset_;  // motor minus desired torque at a torque-loop entry, fading
  Eigen::VectorXd torque_per_amp_; // nominal K_T G_r per joint
  Eigen::VectorXd current_limit_;  // A
  std::vector<FrictionParameters> friction_;  // per joint, for the breakaway feed-forward
  Eigen::VectorXd entry_current_;  // the current the custom loop starts from
  Eigen::VectorXd breakaway_;      // the vendor loops' breakaway feed-forward of this cycle [N.m]
  Eigen::VectorXd breakaway_share_;  // its share of the static friction, per joint
  Eigen::VectorXd reflected_inertia_;  // I_r per joint [kg.m^2]
  Eigen::VectorXd feedforward_;        // the plain torque mode's friction + rotor torque [N.m]
  Eigen::VectorXd entry_torque_;
  Eigen::VectorXd measured_current_;  // the measured current, averaged (track_current) [A]
  long current_samples_ = 0;          // readings averaged since the last gap
  bool breakaway_ramp_ = true;
  double offset_decay_ = 0.0;
};

}  // namespace phri
