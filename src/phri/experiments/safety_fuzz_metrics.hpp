#pragma once
// What the safety-fuzz experiment (safety_fuzz.hpp) measures on every push and every injected
// fault, and how it judges it:
//
// * SafetyMonitor: per control cycle, on the plant's TRUE joint state (SimRobot::truth(), never
//   the sensors): the speed ratio max_i |q̇_i| / v_limit_i, the joint-limit margin (distance inside
//   the URDF range, negative beyond it), the smallest self-collision capsule distance (the
//   controller's CollisionModel on the true q); during a push, the torque the actuators would need
//   to hold the arm against it, |g(q) - J_p(q)^T F|_i / τ_limit_i (g: the torque that holds the arm
//   against gravity in M q̈ + h = τ + J^T F; the issue writes it |J_p^T F + g|_i with g the
//   gravity torque acting on the links, the same number).
// * RecoveryTracker: after the push or fault ends, is the arm back within tolerance_rad of its
//   reference (the held pose, or the fault-free run's path) within recovery_time_s, or in a
//   logged safe stop at rest (max |q̇| < rest_speed) within safe_stop_rest_time_s of the stop?
//   It also says when the window may close (recovered and settled, or decided).
// * classify(): the violation categories of a window, and whether they are operator-possible (the
//   push asked more than the actuators can resist: required torque ratio > 1 on some joint) or a
//   controller failure (anything else; every violation under an injected sensor fault).
#include <phri/control/return_leash.hpp>
#include <phri/model/collision_model.hpp>
#include <phri/model/data.hpp>
#include <phri/model/model.hpp>

#include <Eigen/Core>

#include <limits>
#include <string_view>

namespace phri {

/// Violation categories, one bit each (FuzzVerdict::violations).
enum FuzzViolation : unsigned {
  kViolationJointLimit = 1u << 0,        ///< a joint beyond its URDF limit (plant truth)
  kViolationOverspeed = 1u << 1,         ///< |q̇| above speed_factor x the velocity limit
  kViolationCollision = 1u << 2,         ///< a capsule pair closer than collision_distance_m (0: touching)
  kViolationNanCommand = 1u << 3,        ///< a non-finite set-point in a command the controller produced
  kViolationCrash = 1u << 4,             ///< an exception, or the plant's physics diverged
  kViolationUnhandledRefusal = 1u << 5,  ///< a refused write not followed by a safe stop the next cycle
  kViolationRefusedWrite = 1u << 6,      ///< the robot refused a command the controller sent (not injected)
  kViolationNoRecovery = 1u << 7,        ///< neither back on its path in time nor in a safe stop
  kViolationSafeStopMoving = 1u << 8,    ///< a safe stop still moving safe_stop_rest_time_s after it began
};
inline constexpr int kFuzzViolationCount = 9;

/// Short name of violation bit `index` (0 .. kFuzzViolationCount - 1), for CSV columns and reports.
std::string_view violation_name(int index);

struct SafetyFuzzThresholds {
  double speed_factor = 1.05;            ///< |q̇| / velocity limit above this: overspeed
  double collision_distance_m = 0.0;     ///< capsule distance below this: collision
  double recovery_tolerance_rad = 0.05;  ///< max_i |q_i - reference_i| to count as back
  double recovery_time_s = 3.0;          ///< after the end of the push or fault, plus the walk back:
  /// a carried arm walks back at the controller's ReturnLeash speed, so a window that ended d rad
  /// away (the largest deviation seen after the end) gets d / return_speed_rad_s more.
  double return_speed_rad_s = ReturnLeashSettings{}.return_speed_rad_s;
  double rest_speed_rad_s = 0.01;        ///< max |q̇| at rest (safe stop)
  double safe_stop_rest_time_s = 1.0;    ///< from the safe stop's transition
  double settle_speed_rad_s = 0.05;      ///< max |q̇| for the next push to start
};

/// What one window (a push or a fault, up to its decision) measured.
struct WindowMetrics {
  double max_speed_ratio = 0.0;                                            ///< max_i |q̇_i| / v_limit_i
  /// max_speed_ratio split by who commanded the arm (HeldCommandTracker): held, the plant periods
  /// run on a command the controller could not renew (its thread stalled, its writes refused: the
  /// robot keeps its last command) and the period after, in which the renewed command starts to
  /// act; inherited, the periods after those while the speed is still above the threshold; the
  /// controlled periods, all others.
  double max_held_speed_ratio = 0.0;
  double max_inherited_speed_ratio = 0.0;
  double max_controlled_speed_ratio = 0.0;
  double min_limit_margin_rad = std::numeric_limits<double>::infinity();   ///< < 0: beyond a limit
  double min_capsule_distance_m = std::numeric_limits<double>::infinity();
  double max_required_torque_ratio = 0.0;  ///< push: max over time and joints of |g - J^T F|_i / τ_limit_i
  double max_deviation_rad = 0.0;          ///< from the reference, after the push / from the fault on
  double final_deviation_rad = 0.0;        ///< from the reference when the window closed
  int final_deviation_joint = -1;          ///< the joint of final_deviation_rad (0-based; -1: none)
  double final_speed_rad_s = 0.0;          ///< max_i |q̇_i| when the window closed
  bool nan_command = false;
  bool crashed = false;
  long refused_writes = 0;                 ///< not injected
  long unhandled_refusals = 0;
  double recovery_time_s = -1.0;           ///< after the end; -1: not back (or not applicable)
  bool safe_stop = false;
  double safe_stop_time_s = -1.0;          ///< robot time of the safe stop's transition
  double safe_stop_rest_time_s = -1.0;     ///< from the transition to rest; -1: never at rest
  /// Cycles (before any safe stop) where the loop or compliance mode under test was not the one
  /// running (Controller::low_level().loop(), compliance().mode()): e.g. a loop the drive does
  /// not offer, its target rejected. Any: the window is invalid, never a pass.
  long off_intent_cycles = 0;
  int ran_loop = -1;  ///< the first off-intent cycle's running loop and mode (LowLevelMode, ComplianceMode)
  int ran_mode = -1;
};

struct FuzzVerdict {
  unsigned violations = 0;         ///< FuzzViolation bits
  bool operator_possible = false;  ///< the push exceeded what the actuators can resist
  /// The only violation is an overspeed reached while the robot ran on a command the controller
  /// could not renew, never exceeded once it could act again, and back within the threshold
  /// before any later excess (WindowMetrics::max_held_speed_ratio): no controller acts in a stall
  /// of its own thread. Reported apart, never a pass.
  bool held_command = false;
  /// The loop or mode under test did not run (WindowMetrics::off_intent_cycles): the window tested
  /// something else, so it is reported as invalid and never counted as a pass.
  bool invalid = false;
  bool controller_failure() const { return violations != 0 && !operator_possible && !held_command; }
  bool passed() const { return !invalid && violations == 0; }
};

/// max_i |gravity_i - push_torque_i| / torque_limit_i: above 1, no actuator torque within the
/// limits holds the arm still against the push (push_torque = J_p^T F).
double required_torque_ratio(const Eigen::VectorXd& gravity, const Eigen::VectorXd& push_torque,
                             const Eigen::VectorXd& torque_limit);

/// The categories of `m` (thresholds `t`); operator-possible when `m.max_required_torque_ratio` > 1.
FuzzVerdict classify(const WindowMetrics& m, const SafetyFuzzThresholds& t);

/// Per-cycle checks on the plant's true state with the controller's model (see the file comment).
/// Sized at construction; update() and push_torque_ratio() allocate nothing.
class SafetyMonitor {
public:
  /// `collision` may be null (no capsule check); limits one entry per joint.
  SafetyMonitor(const Model& model, const CollisionModel* collision, const Eigen::VectorXd& velocity_limit,
                const Eigen::VectorXd& torque_limit);

  /// Kinematics of the true (q, q̇), then speed ratio, limit margin and capsule distance into `m`.
  void update(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, WindowMetrics& m);
  /// During a push, after update() with the same q: the required torque ratio for `force_N` at
  /// `point_local` of model body `body` (world axes, or body axes when `local_frame`); folded into
  /// `m` and returned.
  double push_torque_ratio(int body, const Eigen::Vector3d& point_local, const Eigen::Vector3d& force_N, bool local_frame,
                           WindowMetrics& m);

  /// How far q is from `reference`: max_i |q_i - reference_i|, a continuous joint's difference taken
  /// modulo 2 pi (a full turn is the same pose); `joint` gets the i of the maximum.
  double deviation(const Eigen::VectorXd& q, const Eigen::Ref<const Eigen::VectorXd>& reference, int& joint) const;

  /// The latest update()'s values.
  double speed_ratio() const { return speed_ratio_; }
  double limit_margin() const { return limit_margin_; }
  double capsule_distance() const { return capsule_distance_; }
  /// Body placements of the latest update() (for push directions).
  const Data& data() const { return data_; }
  const Model& model() const { return model_; }

private:
  const Model& model_;
  const CollisionModel* collision_;
  Data data_;
  CollisionData collision_data_;
  Eigen::VectorXd velocity_limit_, torque_limit_, lower_, upper_, push_torque_;
  Eigen::VectorXd q_;
  Eigen::MatrixXd jacobian_;
  double speed_ratio_ = 0.0, limit_margin_ = 0.0, capsule_distance_ = 0.0;
};

/// Files each plant period's speed ratio into WindowMetrics' held, inherited or controlled maximum.
class HeldCommandTracker {
public:
  explicit HeldCommandTracker(double speed_factor) : speed_factor_(speed_factor) {}
  /// One plant period; held: it ran on a command the controller could not renew, or is the period
  /// after such a one.
  void sample(double speed_ratio, bool held, WindowMetrics& m);

private:
  double speed_factor_;
  bool inheriting_ = false;  // the last held period ended above the threshold, not yet back within it
};

/// The decision after a push or a fault (see the file comment). Feed it every cycle from the start
/// of the disturbance; done() says when the window may close.
class RecoveryTracker {
public:
  RecoveryTracker(const SafetyFuzzThresholds& thresholds, double end_time_s, double min_observation_s);

  /// One cycle at robot time t: deviation max_i |q_i - reference_i| (+inf: not at the reference),
  /// speed max_i |q̇_i|, safe_stop_time_s: the safe stop's transition time, < 0 while none.
  void sample(double t, double deviation, double speed, double safe_stop_time_s);
  /// A carried arm at robot time t (the push over), `rest_distance_rad` (max_i) from where the
  /// reference comes to rest, walks back at the return leash's speed: the window stays open until it
  /// can be there (the deviation from the reference's path alone underestimates a walk that starts
  /// further out). Only the first call at or after the end counts: one deadline, not a moving one.
  void allow_walk_back(double t, double rest_distance_rad);
  bool done() const { return done_; }
  /// Writes recovery_time_s and the safe-stop fields into `m`.
  void finish(WindowMetrics& m) const;

private:
  SafetyFuzzThresholds t_;
  double end_, min_observation_;
  double recovered_at_ = -1.0;  // since the end
  double allowed_s_ = 0.0;      // recovery_time_s plus the walk back
  bool walk_back_allowed_ = false;
  double safe_stop_time_ = -1.0, rest_after_ = -1.0;
  bool done_ = false;
};

}  // namespace phri
