#pragma once
// Pose task of the compliant QP on a frame (paper eq. compliantQP, task k; the end effector's is
// the main task):
//
//   w || S W (J qdd + J̇ qd - ë* - gamma J M^-1 tau_ext) ||^2,   ë* = a_ff + K e + D (v* - v)
//
// with e = (p* - p, log(R* R^T)) and J the local-world-aligned Jacobian (linear rows first). The
// rows are in world axes, or in the frame's own axes (TaskAxes::kFrame: the residual rotated by
// R^T, so a diagonal K, D, gamma or selection S acts along the tool's axes, e.g. compliant along the
// tool's z and stiff in the other five). W is the singular-direction weight
// (singular_direction_weight.hpp). Stiffness K and damping D per axis, gamma per axis in [0, 1],
// selection per axis in [0, 1] (0: the axis is left to other tasks), one weight. Gains, weight and
// gamma follow their set values through a first-order filter (SmoothedVector) so that changing
// them never steps the torque. Targets: a streamed trajectory (pose, velocity, feed-forward
// acceleration moving continuously) is tracked as given; a target that jumps is approached by a
// reference governor with bounded speed and acceleration (TargetLimits), so a new far target
// never steps the torque either.
#include <phri/control/singular_direction_weight.hpp>
#include <phri/control/task.hpp>
#include <phri/core/smoothed_vector.hpp>
#include <phri/model/data.hpp>
#include <phri/model/model.hpp>
#include <phri/model/spatial.hpp>

namespace phri {

/// Stiction term of the task (not in the paper; see EndEffectorTask::set_integral). Gain 0: off.
struct TaskIntegralSettings {
  double gain = 0.0;            ///< K_I [1/s^3]
  double linear_limit = 0.0;    ///< clamp of the linear term [m/s^2]
  double angular_limit = 0.0;   ///< clamp of the angular term [rad/s^2]
  double linear_zone = 0.0;     ///< acts while |e_i| is below [m]
  double angular_zone = 0.0;    ///< [rad]
};

/// Bounds of the reference governor that moves the task's target toward a target that jumped.
struct TargetLimits {
  double linear_speed = 0.25;          ///< m/s
  double linear_acceleration = 0.5;    ///< m/s^2
  double angular_speed = 0.8;          ///< rad/s
  double angular_acceleration = 1.6;   ///< rad/s^2
};

/// The axes of a pose task's rows: the world's, or the task frame's own.
enum class TaskAxes { kWorld, kFrame };

class EndEffectorTask final : public Task {
public:
  /// singular_value_threshold: sigma_0 of the singular-direction weight (0: off).
  EndEffectorTask(const Model& model, int frame_id, double smoothing_time_constant = 0.1,
                  const TargetLimits& limits = {}, double singular_value_threshold = 0.0,
                  std::string name = "end_effector", ComplianceRole role = ComplianceRole::kMain);

  std::string_view type() const override { return "pose"; }
  void start(const Model& /*model*/, const Data& data) override { hold_current_pose(data); }
  int frame_id() const { return frame_id_; }

  // ---- task interface
  void update(const TaskContext& context) override { update(context.model, context.data, context.qdd_external, context.dt); }
  void add_objective(ObjectiveTerms& objective) const override;
  void set_role_gamma(double gamma) override {
    if (!fixed_gamma_) set_gamma(Vector6d::Constant(gamma));
  }
  bool fixed_gamma() const override { return fixed_gamma_; }
  /// A gamma of its own per axis (in the rows' axes): the compliance modes leave it alone.
  void set_fixed_gamma(const Vector6d& gamma);
  /// Axes of the rows (and so of K, D, gamma and the selection). Set at start-up.
  void set_axes(TaskAxes axes) { axes_ = axes; }
  TaskAxes axes() const { return axes_; }
  /// Per-axis factor of the weight in [0, 1] (default all 1): 0 leaves that axis to other tasks.
  void set_selection(const Vector6d& selection);
  const Vector6d& selection() const { return selection_; }

  // ---- gains (smoothed)
  void set_stiffness(const Vector6d& stiffness);
  void set_damping(const Vector6d& damping);
  /// Damping 2 sqrt(K) per axis, for the stiffness just set.
  void set_critical_damping();
  void set_weight(double weight);
  void set_gamma(const Vector6d& gamma);
  void reset_gains(const Vector6d& stiffness, const Vector6d& damping, double weight, const Vector6d& gamma);
  Vector6d stiffness() const { return stiffness_.value(); }
  Vector6d damping() const { return damping_.value(); }
  double weight() const { return weight_.value()[0]; }
  Vector6d gamma() const { return gamma_.value(); }
  Vector6d stiffness_target() const { return stiffness_.target(); }
  Vector6d damping_target() const { return damping_.target(); }

  /// Stiction term, the end effector's counterpart of PostureTask's: with a soft spring (full-body
  /// compliance, K 30) the pose error left when the joints stick (a few centimetres) is a few
  /// tenths of a m/s^2 of demand, below what the drives' static friction lets through. While the
  /// target is held (no commanded velocity, the governor arrived), the end effector creeps (below
  /// 0.02 m/s and 0.1 rad/s) and an axis's error is within its zone, K_I times the integrated error
  /// is added to ë*, clamped; otherwise it bleeds off (0.1 s). It restarts from zero when an axis
  /// crosses its target and when a new target is set. Resets the term.
  void set_integral(const TaskIntegralSettings& settings);
  /// Off: the term bleeds off (the controller turns it on in the torque loops, off in dual compliance).
  void enable_integral(bool on) { integral_enabled_ = on; }
  const Vector6d& integral_term() const { return integral_term_; }

  // ---- targets
  /// A trajectory point: pose, twist (linear; angular, world axes) and acceleration feed-forward.
  void set_target(const Eigen::Isometry3d& pose, const Vector6d& velocity = Vector6d::Zero(),
                  const Vector6d& acceleration = Vector6d::Zero());
  /// Holds the current pose (after update or compute_all_terms), zero velocity, immediately.
  void hold_current_pose(const Data& data);
  /// The target the task tracks now (the governor's, equal to the set one once reached).
  const Eigen::Isometry3d& target_pose() const { return target_pose_; }
  /// The target last set.
  const Eigen::Isometry3d& commanded_pose() const { return commanded_pose_; }
  /// Velocity of the tracked target (world axes, linear first).
  const Vector6d& target_velocity() const { return target_velocity_; }
  /// True when the tracked target is the one last set (the governor has arrived).
  bool target_reached() const;
  /// An offset applied on the left of the governed target, T_offset T* (ReturnLeash's way back;
  /// its velocity is not fed forward). Identity: none. The stiction term acts on the error to T_offset T*.
  void set_target_offset(const Eigen::Isometry3d& offset);
  /// What the task tracks: T_offset T* (T* itself without an offset).
  const Eigen::Isometry3d& tracked_pose() const { return tracked_pose_; }

  // ---- per cycle
  /// data after compute_all_terms; qdd_external = M^-1 tau_ext; advances the gain filters by dt.
  void update(const Model& model, const Data& data, const Eigen::VectorXd& qdd_external, double dt);
  /// The frame's Jacobian (world axes).
  const Eigen::MatrixXd& jacobian() const { return jacobian_; }
  /// The task's rows A: the Jacobian in the rows' axes (jacobian() itself in world axes).
  const Eigen::MatrixXd& rows() const { return axes_ == TaskAxes::kWorld ? jacobian_ : frame_jacobian_; }
  /// What A qdd should equal: ë* - J̇ qd + gamma J qdd_external, in the rows' axes.
  const Vector6d& reference() const { return reference_; }
  /// Whether the singular-direction weight is active this cycle (it is then singular_weight().weight()).
  const SingularDirectionWeight& singular_weight() const { return singular_weight_; }
  /// Pose error (p* - p; log(R* R^T)) and velocity (v; w) of the last update.
  const Vector6d& error() const { return error_; }
  const Vector6d& velocity() const { return velocity_; }
  const Eigen::Isometry3d& pose() const { return pose_; }

private:
  struct GovernorMove;
  static GovernorMove govern_channel(const Eigen::Vector3d& gap, double commanded_speed, double max_speed,
                                     double max_acceleration, double dt, const Eigen::Vector3d& direction_at_zero,
                                     bool& tracking, double& speed_state);
  void govern_target(double dt);
  void set_governed_motion(const GovernorMove& move, Eigen::Index offset);
  void update_integral(double dt);
  /// A world-axes vector (linear; angular) in the rows' axes.
  Vector6d in_task_axes(const Vector6d& world) const;
  void weigh_rows();
  void apply_target_offset();
  static constexpr double kCreepLinear_m_s = 0.02;
  static constexpr double kCreepAngular_rad_s = 0.1;
  static constexpr double kIntegralBleed_s = 0.1;

  int frame_id_;
  TargetLimits limits_;
  Eigen::Isometry3d commanded_pose_ = Eigen::Isometry3d::Identity();
  Vector6d commanded_velocity_ = Vector6d::Zero();
  Vector6d commanded_acceleration_ = Vector6d::Zero();
  bool tracking_position_ = true;
  bool tracking_rotation_ = true;
  double governor_linear_speed_ = 0.0;
  double governor_angular_speed_ = 0.0;
  SmoothedVector stiffness_;
  SmoothedVector damping_;
  SmoothedVector weight_;
  SmoothedVector gamma_;
  Eigen::Isometry3d target_pose_ = Eigen::Isometry3d::Identity();
  Vector6d target_velocity_ = Vector6d::Zero();
  Vector6d target_acceleration_ = Vector6d::Zero();
  Eigen::MatrixXd jacobian_;
  Vector6d reference_ = Vector6d::Zero();
  Eigen::Isometry3d target_offset_ = Eigen::Isometry3d::Identity();
  bool offset_on_ = false;
  Eigen::Isometry3d tracked_pose_ = Eigen::Isometry3d::Identity();
  Vector6d tracked_velocity_ = Vector6d::Zero();
  Vector6d tracked_acceleration_ = Vector6d::Zero();
  TaskIntegralSettings integral_;
  bool integral_enabled_ = true;
  Vector6d integral_term_ = Vector6d::Zero();
  Vector6d external_task_acceleration_ = Vector6d::Zero();  // J M^-1 tau_ext
  Vector6d error_ = Vector6d::Zero();
  Vector6d task_error_ = Vector6d::Zero();  // error_ in the rows' axes
  TaskAxes axes_ = TaskAxes::kWorld;
  bool fixed_gamma_ = false;
  Vector6d selection_ = Vector6d::Ones();
  bool selecting_ = false;  // some selection below 1
  SingularDirectionWeight singular_weight_;
  bool weighted_ = false;                 // weighted_rows_ holds S W A (else A itself)
  Eigen::MatrixXd frame_jacobian_;        // A in the frame's axes, 6 x nv
  Eigen::MatrixXd weighted_rows_;         // S W A, 6 x nv
  Eigen::MatrixXd selected_rows_;         // S^1/2 A, 6 x nv scratch
  Vector6d velocity_ = Vector6d::Zero();
  Eigen::Isometry3d pose_ = Eigen::Isometry3d::Identity();
};

/// log(R) as a rotation vector (angle * axis), angle in [0, pi].
Eigen::Vector3d rotation_log(const Eigen::Matrix3d& rotation);

}  // namespace phri
