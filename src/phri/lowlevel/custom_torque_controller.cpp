#include <phri/lowlevel/custom_torque_controller.hpp>

#include <phri/core/error.hpp>

#include <algorithm>
#include <cmath>

namespace phri {

CustomTorqueController::CustomTorqueController(const ActuatorTable& actuators, const CustomTorqueSettings& settings)
    : actuators_(actuators.joints()), settings_(settings) {
  auto fail = [](const std::string& key, const std::string& reason) {
    throw ConfigError("CustomTorqueSettings", key, reason);
  };
  if (!(settings.period_s > 0)) fail("period_s", "must be > 0");
  if (!(settings.transfer_gain >= 0) || !std::isfinite(settings.transfer_gain)) fail("transfer_gain", "must be >= 0");
  if (!(settings.integral_gain >= 0) || !std::isfinite(settings.integral_gain)) fail("integral_gain", "must be >= 0");
  if (!(settings.integral_leak > 0) || !std::isfinite(settings.integral_leak)) fail("integral_leak", "must be > 0");
  if (!(settings.integral_limit_fraction >= 0 && settings.integral_limit_fraction <= 1)) {
    fail("integral_limit_fraction", "must be in [0, 1]");
  }
  const int n = static_cast<int>(actuators_.size());
  if (settings.filter_numerator.empty() != settings.filter_denominator.empty()) {
    fail("filter_numerator", "give both the numerator and the denominator of H(z), or neither");
  }
  const DiscreteTransferFunction filter = settings.filter_numerator.empty()
                                              ? DiscreteTransferFunction::kinova_high_velocity()
                                              : DiscreteTransferFunction(settings.filter_numerator, settings.filter_denominator);
  filters_.assign(static_cast<std::size_t>(n), filter);
  leak_factor_ = std::exp(-settings.integral_leak * settings.period_s);
  input_factor_ = settings.integral_gain * (1.0 - leak_factor_) / settings.integral_leak;
  integral_limit_.resize(n);
  for (int i = 0; i < n; ++i) integral_limit_[i] = settings.integral_limit_fraction * actuators_[static_cast<std::size_t>(i)].torque_limit_Nm;
  friction_ = rotor_ = filtered_ = integral_ = tau_command_ = current_ = entry_hold_ = Eigen::VectorXd::Zero(n);
  cases_.assign(static_cast<std::size_t>(n), FrictionCase::kNone);
}

void CustomTorqueController::reset(const Eigen::VectorXd& current_now, const Eigen::VectorXd& tau_desired,
                                   const Eigen::VectorXd& qdd_desired, const Eigen::VectorXd& tau_sensor,
                                   const Eigen::VectorXd& qd) {
  for (auto& f : filters_) f.reset();
  integral_.setZero();
  entry_hold_.setZero();
  update(tau_desired, qdd_desired, tau_sensor, qd);
  // The integrator takes the difference to the present current, so that this first current is
  // the present one; the share of it that friction explains is remembered as the entry hold.
  for (int i = 0; i < dof(); ++i) {
    const ActuatorParameters& a = actuators_[static_cast<std::size_t>(i)];
    const double limit = a.max_motor_torque_Nm();
    // The whole gap, even beyond the integrator's clamp: it leaks away with time constant 1/theta.
    const double gap = current_now[i] * a.torque_per_amp() - tau_command_[i];
    integral_[i] = std::clamp(gap, -limit, limit);
    // Spent between motor and sensor (what the sensor does not see), up to the static friction
    // level: beyond it, a drive constant off its nominal value or a load the model misses.
    const double friction = a.friction.static_Nm;
    entry_hold_[i] = std::clamp(integral_[i] - (tau_sensor[i] - tau_desired[i]), -friction, friction);
    tau_command_[i] += integral_[i];
    current_[i] = std::clamp(tau_command_[i] / a.torque_per_amp(), -a.current_limit_A, a.current_limit_A);
  }
  // The filters keep their first sample; the integrator carries the offset.
}

const Eigen::VectorXd& CustomTorqueController::update(const Eigen::VectorXd& tau_desired,
                                                      const Eigen::VectorXd& qdd_desired,
                                                      const Eigen::VectorXd& tau_sensor, const Eigen::VectorXd& qd) {
  saturated_ = 0;
  for (int i = 0; i < dof(); ++i) {
    const std::size_t j = static_cast<std::size_t>(i);
    const ActuatorParameters& a = actuators_[j];
    const double error = tau_desired[i] - tau_sensor[i];
    FrictionCase which = FrictionCase::kNone;
    friction_[i] = settings_.friction_compensation ? friction_compensation(a.friction, qd[i], qdd_desired[i], &which) : 0.0;
    cases_[j] = which;
    rotor_[i] = settings_.rotor_inertia_compensation ? a.reflected_inertia_kgm2 * qdd_desired[i] : 0.0;
    filtered_[i] = settings_.transfer_gain * filters_[j].step(error);
    // The joint slides: the friction compensation now supplies what the entry's friction hold did.
    if (which == FrictionCase::kSliding && entry_hold_[i] != 0.0) {
      integral_[i] -= entry_hold_[i];
      entry_hold_[i] = 0.0;
    }
    entry_hold_[i] *= leak_factor_;  // a share of the integrator: it leaks with it
    const double without_integral = tau_desired[i] + rotor_[i] + friction_[i] + filtered_[i];
    // Leaky integrator, with anti-windup: no integration pushing further into saturation.
    // Above the clamp only after a bumpless entry (reset): then the integral may only leak down.
    const double bound = std::max(integral_limit_[i], std::abs(leak_factor_ * integral_[i]));
    const double candidate = std::clamp(leak_factor_ * integral_[i] + input_factor_ * error, -bound, bound);
    const double max_torque = a.max_motor_torque_Nm();
    const double unsaturated = without_integral + candidate;
    const bool pushes_into_limit = (unsaturated > max_torque && candidate > integral_[i]) ||
                                   (unsaturated < -max_torque && candidate < integral_[i]);
    if (!pushes_into_limit) integral_[i] = candidate;
    tau_command_[i] = without_integral + integral_[i];
    const double current = tau_command_[i] / a.torque_per_amp();
    current_[i] = std::clamp(current, -a.current_limit_A, a.current_limit_A);
    if (current_[i] != current) ++saturated_;
    if (!std::isfinite(current_[i])) current_[i] = 0.0;  // never a NaN command
  }
  return current_;
}

}  // namespace phri
