#pragma once
// phri::Controller: one control period of the paper's framework, data flowing one way
// (DESIGN.md section 2):
//
//   RobotState -> model terms (M, h, g, J, J̇q̇) -> momentum observer tau_ext, F/T wrench
//              -> compliance mode (dual-compliance trigger) -> WholeBodyQp (qdd_d, tau_d)
//              -> LowLevelController -> RobotCommand
//
// Built from loaded objects (Model, ActuatorTable, CollisionModel) or from the files named in
// ControllerSettings (ConfigError on bad input). step() allocates nothing and never throws.
//
// Safety (DESIGN.md: safe behaviour instead of a crash). Every sample passes the StateSupervisor
// (safety/) first. An implausible or missing sample is never estimated from: the previous command
// is kept for at most SupervisorSettings::max_degraded_s (status kInvalidState / kStaleState).
// Beyond that, or on a fault found elsewhere (the QP failing for max_qp_fallback_s, a refused
// write answered through answer_refused_write(), a robot fault), a latched safe stop: the robot's
// position hold, its reference braking from the arm's measured state (a bounded prediction while
// no plausible sample comes); after a QP failure under a push or a stop the robot asked for, in the
// torque loops, a joint-damping brake on gravity compensation first (after a QP failure also
// resisting the push the observer sees), then the hold at rest. Behind the QP: tau_ext bounded (and a hard stop's reaction never read as a push), a
// velocity guard, a limit guard and a collision guard on the torque (torque_guards.hpp).
// Everything that changes the controller at run time arrives in ControllerTargets: the FSM, the
// gamepad, a dashboard or a script never reach into its stages.
#include <phri/control/controller_settings.hpp>
#include <phri/control/controller_targets.hpp>
#include <phri/control/compliance_controller.hpp>
#include <phri/control/return_leash.hpp>
#include <phri/control/uncancelled_push.hpp>
#include <phri/control/momentum_observer.hpp>
#include <phri/control/whole_body_qp.hpp>
#include <phri/control/wrench_estimator.hpp>
#include <phri/core/filters.hpp>
#include <phri/lowlevel/low_level_controller.hpp>
#include <phri/model/collision_model.hpp>
#include <phri/model/model.hpp>
#include <phri/model/small_cholesky.hpp>
#include <phri/robot/actuator_table.hpp>
#include <phri/robot/robot_command.hpp>
#include <phri/robot/robot_state.hpp>

#include <optional>
#include <string_view>

namespace phri {

enum class CycleStatus {
  kOk,
  kQpFallback,     ///< the QP failed; the brake of WholeBodyQp::fallback ran
  kInvalidState,   ///< non-finite or invalid joint/torque data: previous command held
  kStaleState,     ///< the joint data did not advance since the last cycle: previous command held
  kTargetsRejected,  ///< the cycle ran, but a target was of the wrong size, non-finite or out of
                     ///< range: that one was ignored, the previous one kept (rejected_targets())
  kSafeStop,       ///< latched safe stop: braking, then holding (supervisor().safe_stop_transition())
};
constexpr std::string_view to_string(CycleStatus s) {
  switch (s) {
    case CycleStatus::kOk: return "ok";
    case CycleStatus::kQpFallback: return "qp_fallback";
    case CycleStatus::kInvalidState: return "invalid_state";
    case CycleStatus::kStaleState: return "stale_state";
    case CycleStatus::kTargetsRejected: return "targets_rejected";
    case CycleStatus::kSafeStop: return "safe_stop";
  }
  return "unknown";
}

class Controller {
public:
  /// Loads settings.urdf_path (with model_options(settings)), actuators_path and collision_path.
  explicit Controller(const ControllerSettings& settings);
  /// From loaded objects. `model` must have the settings' end-effector frame and the "ft_sensor"
  /// frame (build it with model_options(settings)); `actuators` one entry per joint, in order;
  /// `collision` built on the same model, or none. The settings' file paths are not used.
  Controller(Model model, ActuatorTable actuators, std::optional<CollisionModel> collision,
             const ControllerSettings& settings);
  /// The model options the controller needs: the F/T sensor frame and the payloads.
  static ModelOptions model_options(const ControllerSettings& settings);
  /// The settings' collision model on `model`: collision_yaml, else collision_path, else none.
  static std::optional<CollisionModel> collision_model(const ControllerSettings& settings, const Model& model);

  /// One cycle: apply the targets, then estimate, QP, inverse dynamics, low level. The first
  /// usable state becomes the targets (hold where the arm is) before the given ones apply.
  CycleStatus step(const RobotState& state, const ControllerTargets& targets, RobotCommand& command);
  /// A fault the caller found (e.g. a robot fault): safe stop from the next step.
  void report_fault(SafetyFault fault, double time_s) { supervisor_.report(fault, time_s); }
  /// The robot refused `command` (WriteStatus != kOk): a fault, answered in the same cycle. Writes
  /// into `command` what to send in its place (the safe stop's command; a refused hold re-targeted
  /// at the measured pose, the closest one the robot accepts) and returns true; false: nothing
  /// better to send. A hold refused max_hold_refusals cycles in a row is the stop's own fault
  /// (SafetyFault::kHoldRefused, supervisor().escalation()). Allocates nothing.
  bool answer_refused_write(const RobotState& state, RobotCommand& command);
  /// One cycle with no new targets.
  CycleStatus step(const RobotState& state, RobotCommand& command) { return step(state, no_targets_, command); }

  // ---- access (read only)
  const Model& model() const { return model_; }
  const Data& data() const { return data_; }
  const WholeBodyQp& qp() const { return qp_; }
  const ComplianceController& compliance() const { return compliance_; }
  const ReturnLeash& leash() const { return leash_; }
  const MomentumObserver& observer() const { return observer_; }
  /// The external joint torque the QP used in the last step (see ExternalTorqueSource).
  const Eigen::VectorXd& external_torque() const { return tau_ext_; }
  const WrenchEstimator& wrench() const { return wrench_; }
  const LowLevelController& low_level() const { return low_level_; }
  const ActuatorTable& actuators() const { return actuators_; }
  /// The self-collision capsules, or null when the robot has none.
  const CollisionModel* collision() const { return collision_ ? &*collision_ : nullptr; }
  const StateSupervisor& supervisor() const { return supervisor_; }
  /// The F/T wrench's plausibility; once dropped() the F/T is not used for the rest of the run.
  const WrenchSupervisor& wrench_supervisor() const { return wrench_supervisor_; }
  /// Whether the safe stop has handed over to the position hold (false: braking, or no safe stop).
  bool holding() const { return holding_; }
  int end_effector_frame() const { return end_effector_frame_; }
  int sensor_frame() const { return sensor_frame_; }
  CycleStatus status() const { return status_; }
  long held_cycles() const { return held_cycles_; }
  /// Targets ignored so far (wrong size, non-finite, stiffness scale not > 0).
  long rejected_targets() const { return rejected_targets_; }
  const ControllerSettings& settings() const { return settings_; }
  bool started() const { return started_; }
  /// The wrench norm the dual-compliance trigger sees (low-passed).
  double trigger_wrench_norm() const { return trigger_filter_.value(); }
  /// Where the dual-compliance trigger's wrench comes from. kForceTorque once the robot has
  /// delivered a valid F/T sample (RobotState::wrench.valid); before that, and for
  /// the whole run on an arm without an F/T sensor, kEstimated: the end-effector wrench estimated
  /// from the momentum observer's tau_ext (estimated_wrench()).
  enum class TouchSource { kForceTorque, kEstimated };
  TouchSource touch_source() const { return ft_seen_ ? TouchSource::kForceTorque : TouchSource::kEstimated; }
  /// The end-effector wrench (world axes, about the end effector) estimated from the observer's
  /// external torque beyond the compliance dead band, by least squares through the end-effector
  /// Jacobian: F = (J J^T)^-1 J tau_ext (computed while touch_source() is kEstimated).
  const Vector6d& estimated_wrench() const { return estimated_wrench_; }
  /// The 2-norm condition number of that J (sqrt of cond(J J^T)) at the last estimate; its
  /// eigenvalues below 1e-6 of the largest are left out (a singular direction gives no wrench).
  double estimated_wrench_condition() const { return estimated_condition_; }

private:
  struct LoadedRobot {
    Model model;
    ActuatorTable actuators;
    std::optional<CollisionModel> collision;
    std::string actuators_source;  // for error messages
  };
  static LoadedRobot load(const ControllerSettings& settings);
  Controller(LoadedRobot robot, const ControllerSettings& settings);
  static WholeBodyQpSettings qp_settings(const ControllerSettings& settings, const ActuatorTable& actuators);
  static ComplianceSettings with_main_task_stiffness(ComplianceSettings compliance, const std::vector<TaskSpec>& specs);
  void add_declared_tasks(const std::vector<TaskSpec>& specs);
  void add_declared_constraints(const std::vector<TaskSpec>& specs);
  bool apply(const ControllerTargets& targets);
  void hold_previous(const RobotState& state, RobotCommand& command);
  void safe_stop(bool sample_good, RobotCommand& command);
  void brake_state();
  double kinematics_age_s() const;
  void missing_sample(const RobotState& state, RobotCommand& command);
  void track_acceleration(const Eigen::VectorXd& qd, double dt);
  void keep_hold_acceptable();
  // Model terms, observer, wrench from the measured state; then, in the open-loop position mode,
  // the model terms of the integrated state the cycle runs on.
  void estimate(const RobotState& state, double dt);
  void estimate_wrench(const RobotState& state);
  void estimate_wrench_from_observer();
  void select_external_torque();
  void bound_external_torque(Eigen::VectorXd& tau) const;
  bool estimate_uncancelled_push(bool torque_loop, bool commanded_last, double dt);
  void note_sent_acceleration();
  void update_modes_and_targets();
  void shape_tasks();
  void guard_torque(Eigen::VectorXd& tau);
  void brake_reference();
  void hold_from_brake_speed();
  void check_qp(WholeBodyQpStatus qp_status, double t);

  ControllerSettings settings_;
  Model model_;
  Data data_;
  ActuatorTable actuators_;
  std::optional<CollisionModel> collision_;
  WholeBodyQp qp_;
  ComplianceController compliance_;
  ReturnLeash leash_;
  MomentumObserver observer_;
  WrenchEstimator wrench_;
  LowLevelController low_level_;
  StateSupervisor supervisor_;
  WrenchSupervisor wrench_supervisor_;
  bool wrench_cleared_ = false;  // the estimate and the trigger cleared after a drop
  int end_effector_frame_ = 0;
  int sensor_frame_ = 0;
  Eigen::VectorXd q_, qd_;
  std::uint32_t last_joint_sequence_ = 0;
  bool started_ = false;
  bool have_command_ = false;
  std::optional<ComplianceMode> pending_mode_;
  CycleStatus status_ = CycleStatus::kOk;
  long held_cycles_ = 0;
  long rejected_targets_ = 0;
  Eigen::MatrixXd ee_jacobian_;              // 6 x nv, for J^T F
  Eigen::VectorXd ft_torque_, tau_ext_;
  Eigen::VectorXd tau_ext_fast_;             // the observer's fast estimate, bounded as tau_ext_
  UncancelledPush uncancelled_;
  bool qp_commanded_ = false;                // the last cycle sent the QP's command
  Eigen::VectorXd qdd_sent_;                 // what that command asks of the arm, the guards' change included
  Eigen::VectorXd sent_change_;              // its part from the guards: (M + B)^-1 (guarded - QP torque)
  bool ft_torque_current_ = false;           // ft_torque_ is J^T F on this cycle's model terms
  Eigen::Matrix<double, 6, 2> wrench_history_ = Eigen::Matrix<double, 6, 2>::Zero();  // the two previous samples
  Vector6d wrench_median_ = Vector6d::Zero();
  long wrench_samples_ = 0;
  LowPassFilter trigger_filter_;       // the wrench norm the dual-compliance trigger sees
  bool ft_seen_ = false;               // an F/T sample ever arrived: the trigger reads the F/T
  Vector6d estimated_wrench_ = Vector6d::Zero();  // least squares of J^T F = tau_ext beyond the dead band
  double estimated_condition_ = 1.0;
  Eigen::VectorXd estimate_torque_;    // tau_ext beyond the dead band (nv)
  ComplementaryFilter ft_fusion_;      // observer (low) + J^T F/T (high), ExternalTorqueSource::kFused
  ControllerTargets no_targets_;
  long qp_fallbacks_in_row_ = 0;
  long cycles_since_good_ = 0;
  long safe_stop_cycles_ = 0;
  long steps_ = 0;                    // step() calls
  double stop_stamp_s_ = 0.0;         // the latest finite joint stamp and sequence (the brake's prediction age)
  std::uint32_t stop_sequence_ = 0;
  double coast_s_ = 0.0;              // of the brake's prediction age: the arm on the previous command
  long refused_step_ = -2;            // the step of the latest refused write
  long refusals_in_row_ = 0;          // refused writes in consecutive steps
  bool holding_ = false;
  bool brake_against_push_ = false;  // the safe stop's brake resists tau_ext (after a QP failure)
  Eigen::VectorXd hold_q_, hold_qd_;  // the safe stop's held reference, braking to rest (position loop)
  Eigen::VectorXd acceleration_;      // q̈ of the latest good samples, low-passed [rad/s^2]
  Eigen::VectorXd filtered_qd_;       // q̇ low-passed for acceleration_
  Eigen::VectorXd brake_q_, brake_qd_, brake_tau_;
  Eigen::VectorXd stop_entry_tau_;  // the last torque command before the safe stop
  Eigen::VectorXd guarded_tau_;
  Eigen::VectorXd limit_lower_, limit_upper_;       // URDF limits (±inf: continuous)
  Eigen::VectorXd torque_limit_, drive_velocity_limit_, reflected_inertia_, static_friction_;
  Eigen::VectorXd drive_torque_;  // the drives' peak motor torque
  // The guards' working memory (guard_torque): excess speed, damping, collision torque, M + I_r and its inverse
  Eigen::VectorXd guard_excess_, guard_damping_, collision_guard_;
  Eigen::MatrixXd guard_inertia_, guard_mobility_;
  SmallCholesky guard_llt_;
};

}  // namespace phri
