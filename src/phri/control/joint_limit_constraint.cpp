#include <phri/control/joint_limit_constraint.hpp>

#include <algorithm>
#include <limits>

namespace phri {

JointLimitConstraint::JointLimitConstraint(const Model& model, const JointLimitSettings& settings,
                                           const Eigen::VectorXd& velocity_limit)
    : dampers_(static_cast<std::size_t>(model.nv())),
      limited_(static_cast<std::size_t>(model.nv()), false),
      lower_(model.lower_limits()),
      upper_(model.upper_limits()),
      safe_lower_(Eigen::VectorXd::Constant(model.nv(), -std::numeric_limits<double>::infinity())),
      safe_upper_(Eigen::VectorXd::Constant(model.nv(), std::numeric_limits<double>::infinity())) {
  for (int i = 0; i < model.nv(); ++i) {
    if (!model.joint(i).has_position_limits()) continue;
    const double range = upper_[i] - lower_[i];
    const VelocityDamperSettings damper{settings.influence_fraction * range, settings.safety_fraction * range,
                                        velocity_limit[i], settings.amortization};
    dampers_[static_cast<std::size_t>(i)] = VelocityDamper(damper);
    limited_[static_cast<std::size_t>(i)] = true;
    safe_lower_[i] = lower_[i] + damper.safety_distance;
    safe_upper_[i] = upper_[i] - damper.safety_distance;
  }
}

void JointLimitConstraint::tighten(const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                                   Eigen::Ref<Eigen::VectorXd> lower, Eigen::Ref<Eigen::VectorXd> upper) const {
  for (int i = 0; i < q.size(); ++i) {
    if (!limited_[static_cast<std::size_t>(i)]) continue;
    const VelocityDamper& damper = dampers_[static_cast<std::size_t>(i)];
    // Upper limit: e = q_max - q, ė = -qd, ë = -qdd >= damper  =>  qdd <= -damper.
    upper[i] = std::min(upper[i], -damper.min_acceleration(upper_[i] - q[i], -qd[i]));
    // Lower limit: e = q - q_min, ė = qd, ë = qdd >= damper.
    lower[i] = std::max(lower[i], damper.min_acceleration(q[i] - lower_[i], qd[i]));
  }
}

}  // namespace phri
