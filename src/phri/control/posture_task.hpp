#pragma once
// Posture task of the compliant QP (paper eq. compliantQP, the w_0 term):
//
//   w_0 || qdd - qdd* - gamma_0 M^-1 tau_ext ||^2,   qdd* = qdd_ff + K (q* - q) + D (qd* - qd)
//
// The error of a continuous joint is wrapped to (-pi, pi] so the posture never asks for a full
// turn. Gains, weight and gamma are smoothed like the end-effector task's.
//
// Stiction term (not in the paper): a weak spring at rest near its target cannot beat the drive's
// static friction (2.15 N.m on the Gen3's large actuators), so a pushed elbow would stop a few
// hundredths of a radian short for good. While a joint is stuck or creeping (|qd| < 0.1 rad/s)
// within integral_zone of its target, K_I times the integrated error is added to qdd*, clamped to
// integral_limit; when the joint moves faster or leaves the zone the term bleeds off (time
// constant 0.1 s), and it restarts from zero when the joint crosses its target, so it neither
// winds up during a push or a motion nor drives an overshoot. The controller enables it in the
// torque loops, not in dual compliance (see enable_integral); EndEffectorTask has the same term.
#include <phri/control/task.hpp>
#include <phri/core/smoothed_vector.hpp>
#include <phri/model/model.hpp>

namespace phri {

class PostureTask final : public Task {
public:
  PostureTask(const Model& model, double smoothing_time_constant = 0.1, std::string name = "posture",
              ComplianceRole role = ComplianceRole::kNullSpace);

  // ---- task interface: rows A = I (nv rows)
  std::string_view type() const override { return "posture"; }
  void update(const TaskContext& context) override { update(context.q, context.qd, context.qdd_external, context.dt); }
  void add_objective(ObjectiveTerms& objective) const override;
  void set_role_gamma(double gamma) override {
    if (!fixed_gamma_) set_gamma(gamma);
  }
  bool fixed_gamma() const override { return fixed_gamma_; }
  /// A gamma of its own (the compliance modes leave it alone).
  void set_fixed_gamma(double gamma);

  void set_stiffness(const Eigen::VectorXd& stiffness);
  void set_stiffness(double stiffness) { stiffness_.set_target_constant(stiffness); }
  void set_damping(const Eigen::VectorXd& damping);
  void set_damping(double damping) { damping_.set_target_constant(damping); }
  void set_weight(double weight);
  /// Stiction term: K_I [1/s^3] (0: off); clamp [rad/s^2]; zone [rad]. Resets the integral.
  void set_integral(double gain, double limit, double zone);
  const Eigen::VectorXd& integral_term() const { return integral_term_; }
  /// Off: the term bleeds off (the controller keeps it for the custom loop, whose friction
  /// pre-compensation turns its acceleration into torque at rest).
  void enable_integral(bool on) { integral_enabled_ = on; }
  void set_gamma(double gamma);
  void reset_gains(double stiffness, double damping, double weight, double gamma);
  double weight() const { return weight_.value()[0]; }
  double gamma() const { return gamma_.value()[0]; }
  const Eigen::VectorXd& stiffness() const { return stiffness_.value(); }
  const Eigen::VectorXd& damping() const { return damping_.value(); }

  void set_target(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd);
  void set_target(const Eigen::VectorXd& q);
  const Eigen::VectorXd& target() const { return target_q_; }
  const Eigen::VectorXd& target_velocity() const { return target_qd_; }
  /// Added to the target (ReturnLeash's way back; its velocity is not fed forward); zero: none.
  /// The stiction term acts on the error to the offset target (it helps the arm follow the walk
  /// back; the controller turns it off while a hand carries the arm).
  void set_target_offset(const Eigen::VectorXd& offset);

  void update(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd_external, double dt);
  /// What qdd should equal: qdd* + gamma_0 M^-1 tau_ext.
  const Eigen::VectorXd& reference() const { return reference_; }
  const Eigen::VectorXd& error() const { return error_; }

private:
  void update_integral(const Eigen::VectorXd& qd, double dt);
  /// Below: the joint is stuck or creeping against friction (the paper's friction velocity threshold).
  static constexpr double kCreepSpeed_rad_s = 0.1;
  static constexpr double kIntegralBleed_s = 0.1;

  int nv_;
  bool fixed_gamma_ = false;
  std::vector<bool> continuous_;
  SmoothedVector stiffness_;
  SmoothedVector damping_;
  SmoothedVector weight_;
  SmoothedVector gamma_;
  Eigen::VectorXd target_q_, target_qd_, target_qdd_;
  Eigen::VectorXd offset_q_;
  Eigen::VectorXd error_;
  Eigen::VectorXd reference_;
  double integral_gain_ = 0.0, integral_limit_ = 0.0, integral_zone_ = 0.0;
  bool integral_enabled_ = true;
  Eigen::VectorXd integral_term_;  ///< K_I * integral of the error [rad/s^2]
};

}  // namespace phri
