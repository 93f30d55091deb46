#pragma once
// Applies a compliance mode to the QP's tasks (gamma per task role: task.hpp's ComplianceRole;
// gains of the main task and the posture) and runs dual compliance: a Schmitt
// trigger on the end-effector wrench norm (paper: "touched" above the high threshold, released
// below the low one). While touched the end-effector task has zero stiffness, low damping and
// gamma 1, so the hand drags it; on release the pose at release becomes the target and the mode is
// null-space compliance again. Every gain change goes through the tasks' smoothing filters: on a
// touch the spring fades out (time constant 0.1 s) with its target unchanged, so the torque never
// steps; a touch shorter than a few time constants releases onto a spring not yet fully faded,
// which is the bounded step of K(t) times the distance dragged.
#include <phri/control/compliance_mode.hpp>
#include <phri/control/return_leash.hpp>
#include <phri/control/whole_body_qp.hpp>
#include <phri/model/spatial.hpp>

#include <algorithm>
#include <optional>

namespace phri {

struct ComplianceSettings {
  // End-effector task when it holds its pose (paper demo, NS mode: K 400, W 1e4).
  double ee_position_stiffness = 400.0;     ///< 1/s^2
  double ee_orientation_stiffness = 400.0;  ///< 1/s^2
  double ee_weight = 1e4;
  /// Full-body compliance: a softer end effector (paper demo, Compliance state: K 30).
  double full_body_ee_stiffness = 30.0;
  /// Posture task (weight 1): a weak spring so that a pushed elbow comes back.
  double posture_stiffness = 20.0;
  double posture_damping = 9.0;
  double posture_weight = 1.0;
  /// Posture stiction term (posture_task.hpp; not in the paper): K_I [1/s^3], its clamp [rad/s^2]
  /// and the zone around the target where it acts [rad]. 0 turns it off (the paper's behaviour).
  double posture_integral_gain = 200.0;
  double posture_integral_limit = 40.0;
  double posture_integral_zone = 0.3;
  /// End-effector stiction term (end_effector_task.hpp; not in the paper). Gain 0 turns it off.
  TaskIntegralSettings ee_integral{.gain = 200.0, .linear_limit = 10.0, .angular_limit = 40.0,
                                   .linear_zone = 0.05, .angular_zone = 0.3};
  /// The way back after a hand carried the arm in full-body compliance (return_leash.hpp).
  ReturnLeashSettings return_leash;
  // Dual compliance (paper: 8 up, 4 down on the 6-D wrench norm; touched EE damping 15,
  // posture damping 2).
  double touch_threshold = 8.0;
  double release_threshold = 4.0;
  double touched_ee_damping = 15.0;
  double touched_posture_damping = 2.0;
  /// The main task's stiffness per axis of its rows (EndEffectorTask::axes()), in place of the
  /// mode's (ee_*_stiffness, full_body_ee_stiffness; 0 while touched in dual compliance); empty:
  /// the mode's. An axis with no stiffness gets touched_ee_damping, the others 2 sqrt(K).
  std::optional<Vector6d> ee_axis_stiffness;
};

class ComplianceController {
public:
  /// Throws ConfigError on inconsistent settings (release >= touch, negative gains).
  explicit ComplianceController(const ComplianceSettings& settings);

  /// Initial gains, no smoothing (before the first cycle).
  void initialise(ComplianceMode mode, WholeBodyQp& qp, const Data& data);
  /// Changes mode (smoothly, from the next cycle on).
  void set_mode(ComplianceMode mode, WholeBodyQp& qp, const Data& data);
  /// Once per cycle before qp.update: wrench_norm is the end-effector wrench's norm (F/T).
  /// Returns true on the cycle a hand lets go of the end effector in dual compliance (its pose
  /// is then the task's new target; the caller re-anchors what depends on the configuration).
  bool update(double wrench_norm, WholeBodyQp& qp, const Data& data);

  ComplianceMode mode() const { return mode_; }
  bool touched() const { return touched_; }
  /// How many times dual compliance entered and left the touched state.
  int touch_count() const { return touch_count_; }
  const ComplianceSettings& settings() const { return settings_; }
  void set_stiffness_scale(double scale, WholeBodyQp& qp);  ///< live stiffness up/down (gamepad)
  /// The scale set_stiffness_scale keeps: clamped to [0.1, 4].
  static double clamped_stiffness_scale(double scale) { return std::clamp(scale, 0.1, 4.0); }
  double stiffness_scale() const { return stiffness_scale_; }
  /// Live gains (ControllerTargets: ee_gamma, posture_gamma, posture_stiffness); an empty optional
  /// leaves that gain as it is. A gamma in [0, 1] overrides the mode's, a negative one ends the
  /// override; the posture stiffness is clamped to [0, kMaxPostureStiffness].
  void set_live_gains(std::optional<double> ee_gamma, std::optional<double> posture_gamma,
                      std::optional<double> posture_stiffness, WholeBodyQp& qp);
  static constexpr double kMaxPostureStiffness = 400.0;
  /// The gamma override of each task, negative when the mode decides.
  double ee_gamma_override() const { return ee_gamma_override_; }
  double posture_gamma_override() const { return posture_gamma_override_; }
  double posture_stiffness() const { return posture_stiffness_; }

private:
  void apply(WholeBodyQp& qp);

  ComplianceSettings settings_;
  ComplianceMode mode_ = ComplianceMode::kNullSpace;
  bool touched_ = false;
  int touch_count_ = 0;
  double stiffness_scale_ = 1.0;
  double ee_gamma_override_ = -1.0;
  double posture_gamma_override_ = -1.0;
  double posture_stiffness_;
};

}  // namespace phri
