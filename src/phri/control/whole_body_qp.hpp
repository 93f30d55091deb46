#pragma once
// phri::WholeBodyQp: the paper's second-order compliant QP (section "Compliance Tasks", eq.
// compliantQP) with its stiff safety constraints (section "Safety Features"), and the inverse
// dynamics that turns the optimal acceleration into the desired joint torque.
//
//   min_qdd  w_EE || J qdd + J̇ qd - ë* - gamma_EE J qdd_ext ||^2 + w_0 || qdd - qdd* - gamma_0 qdd_ext ||^2
//   s.t.     joint limits:   second-order velocity damper on q (eq. sec-order-vel-damp)
//            velocity:       qdd bounded so that qd converges to within the velocity limits
//            torque:         tau_min <= M qdd + h - tau_ext <= tau_max
//            self-collision: the same damper on each capsule-pair distance d (J_d qdd + J̇_d qd)
//   with qdd_ext = M^-1 tau_ext (tau_ext from the momentum observer).
//
// Output convention: tau_d = M(q) qdd_d + h(q, qd) - tau_ext. This is the torque the link side of
// the joints (the torque sensors) must carry so that, with the external torque tau_ext acting as
// well, the arm accelerates at qdd_d: M qdd = tau_d + tau_ext - h. M and h here are link-side
// (no rotor inertia); the low-level loop adds I_r qdd_d on the motor side.
//
// Tasks and constraints are objects in two lists (task.hpp, constraint.hpp), reserved at
// start-up; H and g are assembled in one loop over the tasks, the bounds and rows in one loop over
// the constraints. The paper's two tasks are always there: the main task (a pose task on the end
// effector, role kMain) and the posture (role kNullSpace); more can be added (task_registry.hpp).
// Constraints carry no gamma: they hold the *real* acceleration (push included) within bounds,
// so a push toward a limit is negated. The built-in ones, in this order: VelocityLimitConstraint,
// JointLimitConstraint (the second-order velocity damper, velocity_damper.hpp),
// TorqueLimitConstraint, SelfCollisionConstraint (the same damper on capsule distances).
#include <phri/control/end_effector_task.hpp>
#include <phri/control/joint_limit_constraint.hpp>
#include <phri/control/posture_task.hpp>
#include <phri/control/power_force_limit.hpp>
#include <phri/control/self_collision_constraint.hpp>
#include <phri/control/singular_direction_weight.hpp>
#include <phri/control/torque_limit_constraint.hpp>
#include <phri/control/velocity_damper.hpp>
#include <phri/control/velocity_limit_constraint.hpp>
#include <phri/model/collision_model.hpp>
#include <phri/model/data.hpp>
#include <phri/model/model.hpp>
#include <phri/qp/qp_problem.hpp>
#include <phri/qp/qp_solver.hpp>

#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

namespace phri {

struct WholeBodyQpSettings {
  /// The end-effector task's frame: no default, every arm names its own (the Controller sets it
  /// from ControllerSettings::end_effector_frame, i.e. the robot bundle's frames.end_effector).
  std::string end_effector_frame;
  Eigen::VectorXd torque_limit;    ///< |tau_d| bound per joint (N.m); empty: the URDF effort limits
  Eigen::VectorXd velocity_limit;  ///< per joint (rad/s), before the fraction; empty: URDF limits
  double velocity_limit_fraction = 0.9;  ///< paper: 0.9 of the robot's limits
  /// Joint limits: d_i and d_s as fractions of the joint range (paper: 0.1 and 0.01); xi per
  /// joint = its (scaled) velocity limit, so the damper lets the joint arrive at full speed at d_i.
  double joint_influence_fraction = 0.1;
  double joint_safety_fraction = 0.01;
  double joint_damper_amortization = 1.8;
  /// lambda of the velocity-limit constraint for continuous joints (limited joints use their damper's).
  double velocity_limit_gain = 50.0;
  /// The velocity limit lowered where little torque is left to brake (velocity_limit_constraint.hpp).
  BrakingReserveSettings braking_reserve;
  /// Self-collision damper (paper: d_i 0.03 m, d_s 0.015 m, M 1.8; xi 0.08 m/s gives its lambda ~ 70).
  VelocityDamperSettings collision{0.03, 0.015, 0.08, 1.8};
  /// The approach speed bounded by a braking distance ahead of that damper (self_collision_constraint.hpp).
  CollisionBrakingSettings collision_braking;
  /// Soft dead band on tau_ext before it enters the compliant tasks (gamma terms) only, per joint
  /// [N.m]; empty: none. The observer's estimate carries the model's errors (a 5 % mass error is
  /// ~1 N.m on the shoulder) and the torque sensors' offsets as a constant "push"; through
  /// gamma = 1 they would bend the posture or drift a soft end effector. Inverse dynamics and the
  /// constraints keep the full estimate. The dead band is continuous: x -> sign(x) max(|x| - b, 0).
  Eigen::VectorXd compliance_deadband;
  double regularization = 1e-9;   ///< added to the Hessian's diagonal
  /// Singular value of the end-effector Jacobian below which the task's direction fades out
  /// (singular_direction_weight.hpp; not in the paper) [m/rad, rad/rad]; 0: off. The Gen3's demo
  /// stays above 0.05, so its figures are the paper's; the outstretched elbow (q4 = 0) is below.
  double singular_value_threshold = 0.03;
  double brake_damping = 20.0;    ///< 1/s, the fallback's joint damping brake
  /// When the QP is infeasible: the largest common share of the bounds' braking demands the torque
  /// rows allow (kBrakingScaled) before the fallback brake; false: the fallback at once.
  bool scale_braking = true;
  /// Power and force limiting (power_force_limit.hpp; not in the paper): empty, off. Needs the
  /// collision capsules (their end points are the points it bounds).
  std::optional<PowerForceLimitSettings> power_force_limit;
  /// Reflected rotor inertia per joint, for the power-and-force limit's reflected masses; empty: none.
  Eigen::VectorXd rotor_inertia;
  double smoothing_time_constant = 0.1;  ///< s, of the tasks' gain filters
};

enum class WholeBodyQpStatus {
  kOk,
  kQpInfeasible,       ///< fallback brake used
  kQpIterationLimit,   ///< fallback brake used
  kQpFailed,           ///< invalid QP data (NaN) or numerical error: fallback brake used
  kInvalidInput,       ///< non-finite state or tau_ext: last finite command held
  /// The dampers asked for more braking than the torque limits leave (a push that takes most of a
  /// joint's torque while it runs toward a limit): the QP's solution with the largest common share
  /// of those demands the limits allow (WholeBodyQp::braking_share()), no fallback.
  kBrakingScaled,
};
constexpr std::string_view to_string(WholeBodyQpStatus status) {
  switch (status) {
    case WholeBodyQpStatus::kOk: return "ok";
    case WholeBodyQpStatus::kQpInfeasible: return "qp_infeasible";
    case WholeBodyQpStatus::kQpIterationLimit: return "qp_iteration_limit";
    case WholeBodyQpStatus::kQpFailed: return "qp_failed";
    case WholeBodyQpStatus::kInvalidInput: return "invalid_input";
    case WholeBodyQpStatus::kBrakingScaled: return "braking_scaled";
  }
  return "unknown";
}
/// Whether the QP gave the command (in full, or with its braking scaled), i.e. no fallback.
constexpr bool solved(WholeBodyQpStatus status) {
  return status == WholeBodyQpStatus::kOk || status == WholeBodyQpStatus::kBrakingScaled;
}

class WholeBodyQp {
public:
  /// collision may be null (no self-collision constraint). Throws ConfigError on bad settings.
  WholeBodyQp(const Model& model, const CollisionModel* collision, const WholeBodyQpSettings& settings);

  /// The paper's main task (the end effector's pose) and its posture task.
  EndEffectorTask& end_effector() { return *end_effector_; }
  PostureTask& posture() { return *posture_; }
  const EndEffectorTask& end_effector() const { return *end_effector_; }
  const PostureTask& posture() const { return *posture_; }

  /// Adds a task (at start-up, before the first update); its name must be new (ConfigError).
  Task& add_task(std::unique_ptr<Task> task);
  /// Adds a constraint after the built-in ones (at start-up); its rows are appended.
  Constraint& add_constraint(std::unique_ptr<Constraint> constraint);
  const std::vector<std::unique_ptr<Task>>& tasks() const { return tasks_; }
  const std::vector<std::unique_ptr<Constraint>>& constraints() const { return constraints_; }
  /// Every task holds where the arm is (Task::start), at the controller's start.
  void start_tasks(const Model& model, const Data& data) {
    for (const auto& task : tasks_) task->start(model, data);
  }
  /// The task of that name, or null.
  Task* find_task(std::string_view name);
  const Task* find_task(std::string_view name) const;

  /// One control cycle. `data`: after compute_all_terms(q, qd) on the controller's (link-side)
  /// model; tau_ext: estimated external torque; ee_wrench_world: the F/T wrench at the end effector
  /// (TaskContext), or null; uncancelled_acceleration: what the push does to the arm beyond what
  /// the command cancels (UncancelledPush), or null: the bounds on qdd and the rows on the motion
  /// (Constraint::rows_bound_the_motion) hold for it too;
  /// release_acceleration: what the arm would get if the push ended now (UncancelledPush), or null:
  /// the velocity limits bound the speed it would reach (velocity_limit_constraint.hpp). Returns the status;
  /// results below.
  WholeBodyQpStatus update(const Model& model, const Data& data, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                          const Eigen::VectorXd& tau_ext, double dt, const Vector6d* ee_wrench_world = nullptr,
                          const Eigen::VectorXd* uncancelled_acceleration = nullptr,
                          const Eigen::VectorXd* release_acceleration = nullptr);

  const Eigen::VectorXd& desired_acceleration() const { return qdd_desired_; }
  /// The soft dead band of tau_ext in the compliant terms, per joint [N.m].
  const Eigen::VectorXd& compliance_deadband() const { return deadband_; }
  const Eigen::VectorXd& desired_torque() const { return tau_desired_; }
  const Eigen::VectorXd& external_acceleration() const { return qdd_external_; }
  WholeBodyQpStatus status() const { return status_; }
  QpStatus qp_status() const { return solver_.status(); }
  int qp_iterations() const { return solver_.iterations(); }
  /// The share of the bounds' braking demands the last update held: 1, except under kBrakingScaled.
  double braking_share() const { return braking_share_; }
  /// For recorders outside the cycle (bench/record_qps.cpp): the QP as last solved (H, g, rows and
  /// bounds of the last update; after a relaxation, the relaxed one), the solver (its results, and
  /// the active set the next warm start begins from), the options of the last solve and the number
  /// of solves so far (an update that relaxed a constraint solves more than once).
  const QpProblem& qp_problem() const { return problem_; }
  const QpSolver& qp_solver() const { return solver_; }
  const QpSolveOptions& last_solve_options() const { return last_solve_options_; }
  std::uint64_t solve_count() const { return solve_count_; }
  /// The power-and-force limit, or null when it is off.
  const PowerForceLimitConstraint* power_force_limit() const { return power_force_limit_; }
  const CollisionData* collision_data() const { return self_collision_ ? &self_collision_->data() : nullptr; }
  const Eigen::VectorXd& torque_limit() const { return torque_limit_->torque_limit(); }
  /// h - tau_ext of the last update: the torque that holds the arm still against the estimated
  /// load; beyond torque_limit() on a joint, no command within the limits holds it.
  const Eigen::VectorXd& hold_torque() const { return hold_torque_; }
  /// Per joint, after velocity_limit_fraction.
  const Eigen::VectorXd& velocity_limit() const { return velocity_limit_->velocity_limit(); }
  /// Joint position bounds the dampers keep: limit -+ d_s (infinite for continuous joints).
  const Eigen::VectorXd& safe_lower() const { return joint_limits_->safe_lower(); }
  const Eigen::VectorXd& safe_upper() const { return joint_limits_->safe_upper(); }
  const WholeBodyQpSettings& settings() const { return settings_; }

private:
  Task* task_named(std::string_view name) const;  // both find_task()s
  struct Limits {
    Eigen::VectorXd torque, velocity;  // velocity after the fraction
  };
  static Limits checked_limits(const Model& model, const WholeBodyQpSettings& settings);
  WholeBodyQp(const Model& model, const CollisionModel* collision, const WholeBodyQpSettings& settings,
              const Limits& limits);
  void assemble_objective();
  void fill_constraints(const ConstraintContext& context);
  void bound_uncancelled_push();
  void shift_rows_by_uncancelled_push(Eigen::Index row, int n);
  bool relax_a_constraint();
  bool scale_braking();
  void set_braking_share(double share);
  void resize_problem();
  void fallback_brake(const Data& data, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau_ext);

  WholeBodyQpSettings settings_;
  int nv_;
  std::vector<std::unique_ptr<Task>> tasks_;
  std::vector<std::unique_ptr<Constraint>> constraints_;
  EndEffectorTask* end_effector_ = nullptr;
  PostureTask* posture_ = nullptr;
  VelocityLimitConstraint* velocity_limit_ = nullptr;
  JointLimitConstraint* joint_limits_ = nullptr;
  TorqueLimitConstraint* torque_limit_ = nullptr;
  SelfCollisionConstraint* self_collision_ = nullptr;
  PowerForceLimitConstraint* power_force_limit_ = nullptr;
  QpProblem problem_;
  QpSolver solver_;
  Eigen::VectorXd deadband_;
  Eigen::VectorXd qdd_external_, qdd_desired_, tau_desired_, last_good_tau_;
  const Eigen::VectorXd* qdd_uncancelled_ = nullptr;  // this update's; null: none, or dropped as infeasible
  double uncancelled_share_ = 1.0;                     // the share of it the bounds hold (halved when infeasible)
  Eigen::VectorXd row_shift_;                          // a a_u of one constraint's rows (scratch)
  Eigen::VectorXd braking_lb_, braking_ub_;            // the bounds before scale_braking()
  double braking_share_ = 1.0;
  Eigen::VectorXd hold_torque_, inertia_diagonal_;  // the constraints' context
  Eigen::VectorXd hessian_diagonal_;                // the tasks' diagonal Hessian terms (ObjectiveTerms)
  WholeBodyQpStatus status_ = WholeBodyQpStatus::kOk;
  bool warm_ = false;
  QpSolveOptions last_solve_options_;
  std::uint64_t solve_count_ = 0;
};

}  // namespace phri
