#pragma once
// phri::StateSupervisor: the safety stage between the robot and the controller. Every sample the
// robot reports is checked for plausibility before anything estimates from it:
//
//   sizes; finite; valid flags; fresh (the sequence advanced, the stamp advanced and did not jump);
//   q within the sensor's range (the URDF limits plus a margin: the hard stops are not further);
//   |Δq| since the last good sample consistent with the velocity limit; |q̇| within a physical
//   bound; τ_s and the current within what the drives can produce; values not frozen while the
//   sequence advances (real sensors always carry noise).
//
// An implausible sample is treated as a missing one: the controller keeps the last good state and
// does not feed its estimators (a single spike must never read as a push). A sample whose joint
// part (q, q̇) passed while its torque or current did not still updates the kinematics the safe
// stop brakes on. A gap is not a permanent invalid state: a sample whose sequence or stamp jumped
// is missing, and the next one that follows on from it (sequence +1.., stamp consistent, its
// motion consistent with it) re-synchronises; a gap longer than max_degraded_s (in both the
// sequence and the stamps: a stall, not a garbled counter) is a safe stop that brakes on the
// samples after it. States:
//
//   kNormal   --implausible or missing sample-->  kDegraded (last good state held)
//   kDegraded --`recovery_samples` good samples in a row--> kNormal
//   kDegraded --longer than max_degraded_s, or too many bad samples lately--> kSafeStop
//   any       --report(fault): a fault found elsewhere (refused write, QP failing, robot fault)--> kSafeStop
//
// kSafeStop latches until reset(): the controller brakes and hands over to the robot's position
// hold (Controller::step). Every transition is counted and the latest kept with its reason, its
// joint and its time, for the log and `phri run`. check() allocates nothing and never throws.
#include <phri/robot/robot_command.hpp>
#include <phri/robot/robot_state.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <string_view>

namespace phri {

enum class SupervisorState : std::uint8_t { kNormal = 0, kDegraded, kSafeStop };

enum class SafetyFault : std::uint8_t {
  kNone = 0,
  kSize,            ///< a vector with the wrong number of joints
  kNotFinite,       ///< NaN or infinite value
  kInvalid,         ///< the robot marked the joint or torque signal invalid
  kStale,           ///< the joint sequence did not advance (or went back)
  kStampFrozen,     ///< the sequence advanced but the stamp did not
  kStampJump,       ///< the stamp went back or jumped further than the degraded budget
  kPositionRange,   ///< q beyond the joint's range by more than the sensor margin
  kPositionJump,    ///< |Δq| faster than the velocity bound allows since the last good sample
  kVelocityRange,   ///< |q̇| beyond the physical bound
  kTorqueRange,     ///< |τ_s| beyond what the drive can carry
  kCurrentRange,    ///< |i| beyond the drive's current range
  kFrozenValues,    ///< q̇, τ_s and current bit-identical for frozen_s while the sequence advances
  kDegradedTooLong, ///< no good sample for max_degraded_s
  kTooManyFaults,   ///< implausible samples keep coming (the debounce budget ran out)
  kRobotFault,      ///< the robot reports a fault
  kWriteRefused,    ///< the robot refused a command
  kQpFailure,       ///< the QP kept failing (brake fallback for longer than allowed)
  kFollowingError,  ///< the position loop could not follow its reference (re-synced too often)
  kVelocityMismatch,///< q̇ disagrees with the rate of q between consecutive samples
  kTorqueCurrentMismatch,  ///< τ_s disagrees with the motor torque K_T G_r i beyond friction and rotor inertia
  kRobotStopRequest,///< the robot asks for a safe stop while its samples are good (a degraded link)
  kHoldRefused,     ///< during the safe stop the robot refused its hold for several cycles in a row
  kMissedAtSpeed,   ///< a sample missing while a joint ran where the velocity guard brakes (torque loops)
  kLast = kMissedAtSpeed,
};

constexpr std::string_view to_string(SupervisorState s) {
  switch (s) {
    case SupervisorState::kNormal: return "normal";
    case SupervisorState::kDegraded: return "degraded";
    case SupervisorState::kSafeStop: return "safe_stop";
  }
  return "unknown";
}

constexpr std::string_view to_string(SafetyFault f) {
  switch (f) {
    case SafetyFault::kNone: return "none";
    case SafetyFault::kSize: return "wrong_size";
    case SafetyFault::kNotFinite: return "not_finite";
    case SafetyFault::kInvalid: return "invalid_signal";
    case SafetyFault::kStale: return "stale_sequence";
    case SafetyFault::kStampFrozen: return "frozen_stamp";
    case SafetyFault::kStampJump: return "stamp_jump";
    case SafetyFault::kPositionRange: return "position_out_of_range";
    case SafetyFault::kPositionJump: return "position_jump";
    case SafetyFault::kVelocityRange: return "velocity_out_of_range";
    case SafetyFault::kVelocityMismatch: return "velocity_mismatch";
    case SafetyFault::kTorqueCurrentMismatch: return "torque_current_mismatch";
    case SafetyFault::kRobotStopRequest: return "robot_stop_request";
    case SafetyFault::kHoldRefused: return "hold_refused";
    case SafetyFault::kMissedAtSpeed: return "missed_at_speed";
    case SafetyFault::kTorqueRange: return "torque_out_of_range";
    case SafetyFault::kCurrentRange: return "current_out_of_range";
    case SafetyFault::kFrozenValues: return "frozen_values";
    case SafetyFault::kDegradedTooLong: return "degraded_too_long";
    case SafetyFault::kTooManyFaults: return "too_many_faults";
    case SafetyFault::kRobotFault: return "robot_fault";
    case SafetyFault::kWriteRefused: return "write_refused";
    case SafetyFault::kQpFailure: return "qp_failure";
    case SafetyFault::kFollowingError: return "following_error";
  }
  return "unknown";
}

/// What the drives and sensors can physically report, per joint.
struct SensorRanges {
  Eigen::VectorXd q_lower, q_upper;  ///< joint range [rad] (±inf: continuous joint)
  Eigen::VectorXd velocity_limit;    ///< the drive's velocity limit [rad/s]
  Eigen::VectorXd torque_range;      ///< |τ_s| the drive can carry [N.m] (its peak motor torque)
  Eigen::VectorXd current_range;     ///< |i| the drive can carry [A]
  /// τ_s against the motor current (torque_per_amp left empty: not compared). K_T G_r [N.m/A];
  /// the reflected rotor inertia I_r G_r^2 [kg.m^2]; the friction between motor and torque sensor
  /// (static and Coulomb [N.m], viscous [N.m.s/rad]); the transmission's compliance 1 / K
  /// [rad/N.m] (0: rigid), by which the rotor's acceleration leads the link's: τ̈_s / K.
  Eigen::VectorXd torque_per_amp, reflected_inertia, friction_static, friction_coulomb, friction_viscous,
      transmission_compliance;
};

struct SupervisorSettings {
  double period_s = 1e-3;
  /// [rad] a reading beyond the joint range by more is not a reading: the Gen3's hard stops sit
  /// within a few degrees of its software limits (kinova_gen3.md), so 0.2 rad is generous.
  double position_margin_rad = 0.2;
  /// |q̇| above factor x the velocity limit is not physical: the drives' own guard stops the arm
  /// near 1x; a hard push can overshoot, but never by 2.5x.
  double velocity_bound_factor = 2.5;
  /// |Δq| over the time since the last good sample above factor x the velocity limit (plus
  /// position_step_slack_rad for encoder quanta and jitter) is a jump, not a motion.
  double position_step_factor = 3.0;
  double position_step_slack_rad = 1e-3;
  /// [rad/s] |mean q̇ - Δq/Δt| allowed between the sample and the last good one, besides two
  /// encoder quanta over Δt: a 3 rad/s offset on q̇ is caught at its first sample.
  double velocity_consistency_rad_s = 0.5;
  /// [rad] the joint encoders' quantum or noise (Gen3: far below 2 pi / 2^16 = 9.6e-5).
  double encoder_quantum_rad = 1e-4;
  /// |τ_s| above factor x the drive's peak motor torque (and |i| above factor x its current
  /// limit) is not a reading: the link side can briefly see more than the motor gives (a hard
  /// stop, an impact), but not several times more.
  double torque_range_factor = 2.0;
  double current_range_factor = 1.5;
  /// τ_s against the motor current: a push loads motor and sensor alike, and the drive's balance
  /// K_T G_r i = τ_s + I_r G_r^2 a_r + τ_f, with the rotor's acceleration a_r = q̈ + τ̈_s / K and
  /// the kinetic friction τ_f as modelled (moving faster than moving_rad_s), leaves only stiction,
  /// the friction model's error, K_T's spread and the rotor inertia's. The residual, median of
  /// three (impacts alias into one or two samples) then low-passed over torque_current_filter_s
  /// (the custom loop's ripple and the harmonic drive's ringing average out), beyond
  ///   static + friction_relative |τ_f| + relative min(|τ_s|, |K_T G_r i|)
  ///     + inertia_relative I_r G_r^2 LP(|a_r|) + margin
  /// both for a rigid transmission (a_r = q̈) and for the catalogue's stiffness K, with one sign
  /// (the true compliance lies in between and the residual is linear in it), means a sensor is
  /// wrong (an offset or spike within range): an observer fed with it reports a push nobody
  /// makes, and the controller drives the joint to cancel it. Kinova's actuators make the same
  /// check (MOTOR_CURRENT_MISMATCH fault, kinova_gen3_actuators.md). I_r is known within a factor
  /// of two at best (the paper authors' tuned values differ 13x); a_r is clamped so that one bad
  /// sample cannot poison the filter. The margin (4 N.m, the size of a sensor offset the controller
  /// tolerates) keeps the custom loop's ringing on the elastic drop-test plant (phri experiment
  /// drop-test) below this tolerance. A mismatch is a safe stop at once: it has lasted the filter's
  /// time, and holding the previous torque command would repeat the phantom push it cancelled.
  double torque_current_filter_s = 0.01;
  double torque_current_moving_rad_s = 0.05;
  double torque_current_friction_relative = 0.5;
  double torque_current_relative = 0.15;
  double torque_current_inertia_relative = 0.5;
  double torque_current_margin_Nm = 4.0;
  double motor_acceleration_clamp_rad_s2 = 2000.0;
  /// [s] how long the last good state may stand in for missing ones before a safe stop. Kortex's
  /// low-level servoing faults after a few missed 1 kHz frames; 20 ms is the same order.
  double max_degraded_s = 0.02;
  /// good samples in a row that end a degraded spell (debounce)
  int recovery_samples = 3;
  /// Debounce budget: each implausible sample adds 1, each good one removes decay_per_good;
  /// above max_fault_budget (intermittent faults, e.g. one spike in every few samples) -> safe stop.
  double max_fault_budget = 20.0;
  double fault_budget_decay_per_good = 0.05;
  /// [s] q̇, τ_s and current bit-identical for this long while the sequence advances: frozen
  /// values (0: not checked, for noise-free fakes).
  double frozen_s = 0.05;
  /// The quicker test of frozen values in a torque loop, whose τ_s follows its command: the values
  /// bit-identical for frozen_command_samples samples while the torque given to the drives moved by
  /// more than frozen_command_Nm from its value when they stopped changing (a live sensor shows
  /// such a change; one sample repeated by a slow drive does not trip it). Off with frozen_s = 0.
  int frozen_command_samples = 3;
  double frozen_command_Nm = 1.0;
};

struct SafetyTransition {
  double time_s = 0.0;
  SupervisorState from = SupervisorState::kNormal, to = SupervisorState::kNormal;
  SafetyFault reason = SafetyFault::kNone;
  int joint = -1;  ///< joint the fault was seen on (-1: not a joint's)
};

class StateSupervisor {
public:
  /// Sizes everything for ranges.velocity_limit.size() joints; ConfigError on inconsistent input.
  StateSupervisor(const SensorRanges& ranges, const SupervisorSettings& settings);

  /// Checks one sample; true: it is plausible and fresh (last_good() is now this sample). In
  /// kSafeStop the check still runs (the brake uses plausible measurements) but the state stays.
  bool check(const RobotState& state);
  /// A fault found outside the state: safe stop, latched, at robot time t. In the safe stop, a
  /// fault of the stop itself (kHoldRefused) is kept as its escalation().
  void report(SafetyFault fault, double t, int joint = -1);
  /// Back to kNormal with no good sample yet (after the operator cleared the cause).
  void reset();
  /// The command the drives were given, for the next samples (frozen values): its joint torque in
  /// the torque loops, K_T G_r i in the current loop; none in the robot's position loop.
  void note_command(const RobotCommand& command);

  SupervisorState state() const { return state_; }
  bool safe_stop() const { return state_ == SupervisorState::kSafeStop; }
  /// Whether a good sample has been seen (last_good() is meaningful).
  bool has_good() const { return has_good_; }
  const RobotState& last_good() const { return last_good_; }
  /// Robot time of the last good sample (its stamp) [s].
  double last_good_time() const { return last_good_.joints.stamp_s; }
  /// The latest plausible joint positions and velocities, and their stamp: the last good sample's,
  /// or a later one whose torque or current alone was implausible. kinematics_fresh(): from the
  /// latest sample checked.
  const Eigen::VectorXd& kinematic_q() const { return kinematic_q_; }
  const Eigen::VectorXd& kinematic_qd() const { return kinematic_qd_; }
  double kinematic_stamp() const { return kinematic_stamp_; }
  std::uint32_t kinematic_sequence() const { return kinematic_sequence_; }
  bool has_kinematics() const { return has_kinematics_; }
  bool kinematics_fresh() const { return kinematics_fresh_; }
  /// Samples re-synchronised after a gap or a jumped counter.
  long resyncs() const { return resyncs_; }
  /// A fault of the safe stop itself (reason kNone: none).
  const SafetyTransition& escalation() const { return escalation_; }
  /// The fault of the last implausible sample (kNone if the last one was good), its joint.
  SafetyFault sample_fault() const { return sample_fault_; }
  int sample_fault_joint() const { return sample_fault_joint_; }
  long implausible_samples() const { return implausible_; }
  std::uint64_t transition_count() const { return transitions_; }
  const SafetyTransition& last_transition() const { return last_transition_; }
  /// The transition into kSafeStop (reason kNone before any).
  const SafetyTransition& safe_stop_transition() const { return safe_stop_transition_; }
  const SupervisorSettings& settings() const { return settings_; }
  const SensorRanges& ranges() const { return ranges_; }

private:
  SafetyFault classify(const RobotState& s, int& joint);
  SafetyFault check_freshness(const RobotState& s);
  SafetyFault freshness_against(const RobotState& s, std::uint32_t sequence, double stamp, bool stamp_known) const;
  SafetyFault check_kinematics(const RobotState& s, int& joint) const;
  SafetyFault check_drive_ranges(const RobotState& s, int& joint) const;
  void keep_candidate(const RobotState& s);
  void check_gap(const RobotState& s);
  bool frozen(const RobotState& s);
  int first_torque_current_mismatch(const RobotState& s);
  void accept(const RobotState& s);
  void reject(const RobotState& s, SafetyFault fault, int joint);
  void transition(SupervisorState to, SafetyFault reason, int joint, double t);

  SensorRanges ranges_;
  SupervisorSettings settings_;
  int n_ = 0;
  SupervisorState state_ = SupervisorState::kNormal;
  RobotState last_good_;
  RobotState previous_;  // the latest sample with the right sizes, good or not (frozen values)
  bool has_good_ = false;
  bool has_previous_ = false;
  // Freshness reference: the latest sample whose sequence and stamp passed.
  std::uint32_t last_sequence_ = 0;
  double last_stamp_ = 0.0;
  bool has_sequence_ = false;
  std::uint32_t seen_sequence_ = 0;  // of the latest sample with a readable header (a repeat is stale)
  bool has_seen_ = false;
  // The latest sample whose sequence or stamp jumped: the next one may follow on from it (re-sync).
  std::uint32_t candidate_sequence_ = 0;
  double candidate_stamp_ = 0.0;
  Eigen::VectorXd candidate_q_, candidate_qd_;
  bool has_candidate_ = false;
  bool resync_ = false;              // this sample follows on from the candidate
  long resyncs_ = 0;
  // The kinematics the safe stop brakes on (see kinematic_q()).
  Eigen::VectorXd kinematic_q_, kinematic_qd_;
  double kinematic_stamp_ = 0.0;
  std::uint32_t kinematic_sequence_ = 0;
  bool has_kinematics_ = false;
  bool kinematics_fresh_ = false;
  bool kinematics_passed_ = false;   // classify(): the joint part of this sample passed
  bool header_passed_ = false;       // classify(): its sequence and stamp passed
  SafetyTransition escalation_;
  double frozen_since_s_ = -1.0;     // stamp at which the values stopped changing (-1: changing)
  int frozen_samples_ = 0;           // identical samples in a row
  double previous_stamp_ = 0.0;      // of previous_: the last sample before a freeze was live
  std::uint32_t previous_sequence_ = 0;
  double freeze_stamp_ = 0.0;        // previous_'s stamp and sequence when the freeze began
  std::uint32_t freeze_sequence_ = 0;
  Eigen::VectorXd torque_command_, freeze_command_;  // note_command()'s torque; its value at the freeze
  bool has_torque_command_ = false, freeze_command_known_ = false;
  // The residual K_T G_r i - τ_s - I_r G_r^2 a_r - τ_f under one hypothesis on the transmission.
  struct ResidualTrack {
    Eigen::VectorXd filtered;           // median of three, then low-passed [N.m]
    Eigen::VectorXd acceleration_size;  // low-passed |a_r| [rad/s^2]
    Eigen::VectorXd raw[2];             // the last two unfiltered residuals
    void resize(int n);
    /// Feeds joint i's raw residual; returns the filtered one (unchanged until started: three samples).
    double update(int i, double residual, double acceleration, double alpha, bool started);
  };
  // [0]: rigid (a_r = q̈); [1]: the catalogue's compliance (a_r = q̈ + τ̈_s / K).
  ResidualTrack residual_track_[2];
  Eigen::VectorXd residual_qd_;      // q̇ of the residual's last update (for q̈)
  Eigen::VectorXd residual_tau_[2];  // τ_s of the residual's last two updates (for τ̈_s)
  double residual_stamp_s_ = 0.0;
  int residual_updates_ = 0;         // updates since the filter (re)started
  int good_in_row_ = 0;
  long bad_in_row_ = 0;
  double fault_budget_ = 0.0;
  SafetyFault sample_fault_ = SafetyFault::kNone;
  int sample_fault_joint_ = -1;
  long implausible_ = 0;
  std::uint64_t transitions_ = 0;
  SafetyTransition last_transition_;
  SafetyTransition safe_stop_transition_;
};

}  // namespace phri
