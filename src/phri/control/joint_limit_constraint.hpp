#pragma once
// Joint-limit constraint of the QP (paper, "Safety Features"): a second-order velocity damper
// (velocity_damper.hpp) on each limited joint's distance to its lower and upper limits, written
// as bounds on qdd. d_i and d_s are fractions of the joint's range (paper: 0.1 and 0.01); xi is
// the joint's (scaled) velocity limit, so the damper lets it arrive at full speed at d_i.
// Continuous joints have no bound here. Stiff: no gamma, so a push toward a limit is negated.
#include <phri/control/constraint.hpp>
#include <phri/control/velocity_damper.hpp>
#include <phri/model/model.hpp>

#include <Eigen/Core>
#include <vector>

namespace phri {

struct JointLimitSettings {
  double influence_fraction = 0.1;  ///< d_i / range
  double safety_fraction = 0.01;    ///< d_s / range
  double amortization = 1.8;        ///< M
};

class JointLimitConstraint final : public Constraint {
public:
  /// velocity_limit: per joint, the xi of its damper.
  JointLimitConstraint(const Model& model, const JointLimitSettings& settings, const Eigen::VectorXd& velocity_limit);

  /// Tightens the acceleration bounds: lower = max(lower, damper on q - q_min), upper = min(upper,
  /// damper on q_max - q), for the joints that have limits.
  void tighten(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, Eigen::Ref<Eigen::VectorXd> lower,
               Eigen::Ref<Eigen::VectorXd> upper) const;
  std::string_view type() const override { return "joint_limit"; }
  void bound(const ConstraintContext& context, Eigen::Ref<Eigen::VectorXd> lower,
             Eigen::Ref<Eigen::VectorXd> upper) override {
    tighten(context.q, context.qd, lower, upper);
  }

  bool limited(int joint) const { return limited_[static_cast<std::size_t>(joint)]; }
  /// The damper's gain lambda of a limited joint.
  double lambda(int joint) const { return dampers_[static_cast<std::size_t>(joint)].lambda(); }
  /// Joint position bounds the dampers keep: limit -+ d_s (infinite for continuous joints).
  const Eigen::VectorXd& safe_lower() const { return safe_lower_; }
  const Eigen::VectorXd& safe_upper() const { return safe_upper_; }

private:
  std::vector<VelocityDamper> dampers_;
  std::vector<bool> limited_;
  Eigen::VectorXd lower_, upper_, safe_lower_, safe_upper_;
};

}  // namespace phri
