#pragma once
// Everything Controller needs, with the defaults of the paper's demo where it gives them (gains,
// thresholds); nothing in it describes one arm: the robot's files, frames and end of arm come from
// its bundle (robots/<robot>/robot.yaml, app/RobotBundle::apply_to) or a run YAML (app/Config).
// Tests and experiments may also build it in code.
#include <phri/control/compliance_controller.hpp>
#include <phri/control/compliance_mode.hpp>
#include <phri/control/task_spec.hpp>
#include <phri/control/whole_body_qp.hpp>
#include <phri/control/wrench_estimator.hpp>
#include <phri/core/enum_names.hpp>
#include <phri/lowlevel/custom_torque_controller.hpp>
#include <phri/lowlevel/low_level_controller.hpp>

#include <phri/model/model.hpp>
#include <phri/robot/end_of_arm.hpp>
#include <phri/safety/state_supervisor.hpp>
#include <phri/safety/wrench_supervisor.hpp>

#include <Eigen/Geometry>

#include <array>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace phri {

/// Where the external joint torque of the QP (and of tau_d = M qdd + h - tau_ext) comes from.
enum class ExternalTorqueSource {
  kObserver,          ///< the momentum observer on the joint torque sensors (default)
  kForceTorqueSensor, ///< J_ee^T of the F/T sensor's operator wrench only (the paper's static
                      ///< torque-tracking experiment: "the weight measured by the F/T sensor is compensated")
  kFused,             ///< the paper's code: observer + high-pass of J^T F/T (complementary filter, pole K_O)
};
inline constexpr int kExternalTorqueSourceCount = 3;
/// The names of the run YAML's controller.external_torque_source and of the reports.
inline constexpr std::array<std::string_view, kExternalTorqueSourceCount> kExternalTorqueSourceNames = {"observer", "ft",
                                                                                                      "fused"};
constexpr std::string_view to_string(ExternalTorqueSource s) { return enum_name(s, kExternalTorqueSourceNames); }
constexpr std::optional<ExternalTorqueSource> external_torque_source_from_string(std::string_view name) {
  return enum_from_string<ExternalTorqueSource, kExternalTorqueSourceCount>(name);
}

/// What the controller does after the supervisor's plausibility checks: the guards behind the QP
/// and the safe stop (Controller::step).
struct SafetySettings {
  SupervisorSettings supervisor;  ///< plausibility of every sample (period_s: the controller's)
  /// Plausibility of the F/T wrench; a failed check drops the F/T source for the run (the
  /// observer alone, the dual-compliance trigger released): WrenchSupervisor.
  WrenchSupervisorSettings wrench;
  /// [s] the QP may fall back to its brake this long in a row before a safe stop (a QP that stays
  /// infeasible, e.g. a posture in collision, must not leave the arm on a fallback for ever).
  double max_qp_fallback_s = 0.05;
  /// [1/s] safe-stop brake: tau = g(q) - rate (M_ii + I_r) qd per joint, from the last good
  /// velocity (decaying at this rate while no good sample comes).
  double brake_rate = 20.0;
  /// [rad/s] every joint slower than this: the brake hands over to the robot's position hold.
  double handover_speed_rad_s = 0.02;
  /// [s] longest brake before the hand-over, whatever the speed.
  double max_brake_s = 1.0;
  /// [s] a stop the robot asks for while it still obeys (RobotState::stop_requested: a degraded
  /// link) is no emergency: the brake blends in from the last torque command over this time, with
  /// no step in the motor torque (a 0.6 rad/s joint met the full brake with a 13.6 N.m step).
  double requested_stop_blend_s = 0.05;
  /// A hold the robot refuses this many cycles in a row, although re-targeted at the measured pose
  /// each time, is the stop's own fault (SafetyFault::kHoldRefused): Kortex's low-level servoing
  /// faults after a few missed 1 kHz frames, so a few cycles is all the robot gives.
  int max_hold_refusals = 5;
  /// A missing sample in a torque loop where the last velocity, carried on at the recent
  /// acceleration over max_degraded_s, reaches the velocity guard (velocity_guard_fraction of the
  /// drive's limit): a safe stop at once (missed_at_speed) instead of the previous command for the
  /// degraded budget. Off by default: on a Kinova arm the hold's entry at speed goes through the
  /// actuators' mode switch, a torque step (107 N.m at 1.9 rad/s through the Kortex emulator,
  /// KortexSession.PacketLossOfOnePercent...), and a damping brake instead lets a hand pull the arm
  /// to 3.4x (safety fuzz, seed 90210). On, the five overspeeds of that seed were gone (replays, with
  /// a hold that also re-seeded from the first plausible sample, since removed: docs/safety.md).
  /// (A sample whose joints are plausible, only its torque or current not, always stops so: the
  /// hold brakes from the measured state, Controller::missing_sample.)
  bool stop_missed_at_speed = false;
  /// Velocity guard of the torque loops, the last line behind the QP's velocity constraint: above
  /// guard_fraction x the drive's velocity limit, damping rate x (M_ii + I_r) x the excess, scaled
  /// down where coupled joints would ring (torque_guards.hpp).
  double velocity_guard_fraction = 0.9;
  /// [1/s] A gain margin of 2 below where the custom loop's torque chatters (600).
  double velocity_guard_rate = 300.0;
  /// Limit guard: beyond the damper's safety distance d_s, an outward torque of the joint's static
  /// friction plus stiffness x the depth, so that a joint leaves the band against its stiction and
  /// a hand pressing it in meets a growing answer: ~50 N.m at the URDF limit (d_s 0.05 rad on the
  /// Gen3) (replayed: SafetyFuzz.FormerFailuresReplayedPass, seed 8642).
  double limit_guard_stiffness_Nm_per_rad = 1000.0;
  /// Collision guard: a capsule pair closer than the damper's safety distance d_s is pushed apart
  /// through its distance Jacobian, J_d^T (stiffness x depth + damping x approach speed)
  /// (torque_guards.hpp). 6000 N/m answers 90 N at contact (d_s 15 mm); 150 N.s/m is critical
  /// damping (2 sqrt(k m)) for 1 kg along the pair's normal.
  double collision_guard_stiffness_N_per_m = 6000.0;
  double collision_guard_damping_Ns_per_m = 150.0;
  /// |tau_ext| used by the QP is bounded by this factor x the joint's torque limit: more than the
  /// arm can resist is not a push the controller can act on (a spike, a stop).
  double external_torque_bound_factor = 1.5;
};

struct ControllerSettings {
  std::string urdf_path;       ///< the controller's (link-side) model
  std::string actuators_path;  ///< actuators.yaml: limits, rotor inertia, friction model
  std::string collision_path;  ///< collision.yaml; empty: no self-collision constraint
  /// A collision model's text (capsules fitted from the URDF, model/capsule_fit.hpp), used in
  /// place of collision_path when not empty.
  std::string collision_yaml;
  /// The frame of the end-effector task (and where the end of arm mounts); a link or fixed frame
  /// of the URDF. No default: every arm names its own.
  std::string end_effector_frame;
  /// The controlled chain (ModelOptions): base and tip links ('' : the URDF's root, the end of its
  /// only moving branch) and the URDF joints held at 0 (e.g. a gripper's fingers).
  std::string base_link;
  std::string tip_link;
  std::vector<std::string> locked_joints;
  /// [m/s^2] gravity in the world frame, and where the base link sits in the world (ModelOptions):
  /// a robot bundle's `gravity_m_s2` and `base` keys; the plant is given the same.
  Eigen::Vector3d gravity_m_s2 = Eigen::Vector3d(0.0, 0.0, -9.81);
  Eigen::Isometry3d base_placement = Eigen::Isometry3d::Identity();
  /// F/T sensor measuring frame in the end-effector frame (EndOfArm::sensor_mount; the identity
  /// without a sensor): the model's "ft_sensor" frame, where the wrench estimator reads from.
  Eigen::Isometry3d ft_sensor_mount = Eigen::Isometry3d::Identity();
  /// What the arm carries beyond its URDF (frame '' : the end-effector frame). None by default:
  /// set_end_of_arm, a bundle's end_of_arm or a run YAML's robot.payloads add them.
  std::vector<Payload> payloads;
  /// A body carried on the end-effector frame, given in a frame `placed` there (the tool: in the
  /// F/T sensor's frame, so its COM and principal axes turn and move with the sensor's mount).
  static Payload end_of_arm_payload(const char* name, const RigidBodyData& body,
                                    const Eigen::Isometry3d& placed = Eigen::Isometry3d::Identity()) {
    Payload p{name, "", {}};
    p.inertia.mass = body.mass_kg;
    p.inertia.com = placed.linear() * body.com_m + placed.translation();
    p.inertia.inertia_com = placed.linear() * body.principal_inertia_kgm2.asDiagonal() * placed.linear().transpose();
    return p;
  }
  /// The controller's view of an end of arm (none: a bare flange): the F/T frame's offset, the
  /// adapter and the tool as payloads on the end-effector frame, the tool's weight removed from
  /// the F/T reading; a tool without a sensor: the tool alone, on the end-effector frame.
  void set_end_of_arm(const std::optional<EndOfArm>& end_of_arm) {
    const EndOfArm none;
    const EndOfArm& e = end_of_arm ? *end_of_arm : none;
    const bool sensor = end_of_arm && e.has_ft_sensor;
    ft_sensor_mount = sensor ? e.sensor_mount : Eigen::Isometry3d::Identity();
    payloads.clear();
    if (sensor) {
      // The tool is given in the sensor's frame: placed by the sensor's mount.
      payloads = {end_of_arm_payload("ft_adapter_and_sensor", e.flange_side),
                  end_of_arm_payload("tool", e.tool, e.sensor_mount)};
    } else if (end_of_arm) {
      payloads = {end_of_arm_payload("tool", e.tool)};  // on the flange, nothing between
    }
    // What the F/T reading carries below the sensor: nothing to remove without a sensor.
    wrench.tool_mass_kg = sensor ? e.tool.mass_kg : 0.0;
    wrench.tool_com_m = sensor ? e.tool.com_m : Eigen::Vector3d::Zero();
  }
  double period_s = 1e-3;
  /// Momentum observer bandwidth K_O [rad/s]. The paper's code uses 10; 50 follows a push 5x
  /// faster, which the stiff tasks need to hold the end effector within millimetres, at the cost
  /// of 5x more torque-sensor noise in tau_ext (about 0.05 N.m rms with the plant's sensor noise).
  double observer_gain = 50.0;
  /// The observer's release path (MomentumObserver): a push that ends is followed at this gain
  /// [rad/s] (0: off; x period_s < 1) while the kick -M^-1 tau_ext would drive a joint faster than
  /// release_speed_fraction x the drive's velocity limit along its motion, once the fast estimate
  /// is below the slow one by more than the threshold [N.m] (above its noise).
  double observer_release_gain = 500.0;
  double observer_release_speed_fraction = 0.5;
  double observer_release_threshold_Nm = 5.0;
  ExternalTorqueSource external_torque_source = ExternalTorqueSource::kObserver;
  /// Under the robot's position loop, the QP runs on the measured state (false: what the servo
  /// cannot follow comes back as task error and is corrected) or, as the paper's mc_rtc controller
  /// in position mode ("OpenLoop", reference notes paper_parameters section 1.1), on the state the
  /// low level integrates from its own accelerations (true: the servo alone rejects disturbances).
  bool position_mode_open_loop = false;
  WholeBodyQpSettings qp;  ///< torque/velocity limits default to actuators.yaml's
  /// Dead band of tau_ext in the compliant tasks when qp.compliance_deadband is empty, by actuator
  /// size [N.m]: above the estimate's bias (5 % mismatch, sensor offsets), far below a push. An
  /// actuator without `size` gets 1 % of its torque limit instead (robot/actuator_parameters.hpp).
  double deadband_large_Nm = 1.0;
  double deadband_small_Nm = 0.4;
  ComplianceSettings compliance;
  /// The run YAML's `controller.tasks:` (control/task_registry.hpp): "end_effector" and "posture"
  /// configure the paper's two tasks, any other name adds a task. Empty: the paper's two as they are.
  std::vector<TaskSpec> tasks;
  /// The run YAML's `controller.constraints:` (control/constraint_registry.hpp): constraints added
  /// to the paper's safety constraints, which are always on.
  std::vector<TaskSpec> constraints;
  /// Time constant of the low-pass on the wrench norm that drives the dual-compliance trigger [s]
  /// (0: none). A hand's push builds up over tens of milliseconds; 10 ms rejects one-sample spikes.
  double wrench_trigger_filter_s = 0.01;
  WrenchEstimatorSettings wrench;
  CustomTorqueSettings custom_torque;
  SafetySettings safety;
  ComplianceMode initial_compliance = ComplianceMode::kNullSpace;
  LowLevelMode initial_loop = LowLevelMode::kCurrent;
  /// The loops the robot's drives offer (a robot bundle's `drive:`, robot/drive_kind.hpp); a target
  /// asking for another is rejected, an initial_loop outside it is a ConfigError. Default: every
  /// loop (settings built in code, no bundle).
  LowLevelModeSet offered_loops = LowLevelModeSet::all();
};

}  // namespace phri
