#pragma once
// phri::CustomTorqueController: the paper's low-level torque loop (section "Low-level Control",
// Fig. global-system), which drives motor current to track the QP's desired joint torque:
//
//   tau_cmd = tau_d + I_r G_r^2 qdd_d + tau_f(qd, qdd_d) + lambda H(z) e + I,   e = tau_d - tau_s
//   i       = tau_cmd / (K_T G_r), saturated at the drive's current limit
//
// * feed-forward: the desired (link-side) torque, the rotor inertia it must also accelerate, and
//   the friction pre-compensation (friction_compensation.hpp) — all on the motor side of the
//   torque sensor;
// * feedback on the sensor's torque error: Kinova's own 3rd-order filter H(z) (the paper's
//   coefficients, at 1 kHz) with gain lambda, plus a leaky integrator K_I / (s + theta).
//
// The leaky integrator is discretised by zero-order hold (exact for an error held over each
// period), with the newest error sample: x[k] = a x[k-1] + K_I (1 - a) / theta e[k],
// a = exp(-theta T), so a constant error gives the continuous step response's samples
// (K_I / theta) e (1 - e^{-theta k T}). Its leak time constant
// is 1 / theta; its output is clamped (a fraction of the joint's torque limit, 5 % in the paper's
// code) and it stops integrating toward a saturated current (anti-windup).
//
// Entering the loop from another mode is bumpless: reset() starts H(z) at rest and sets the
// integrator so that the first current equals the current the drive was carrying (even beyond the
// integrator's clamp: that entry offset then only leaks away, with time constant 1 / theta). Part
// of that offset is torque spent between motor and sensor, up to the static friction level: at
// rest, the friction the previous loop was pushing against (the entry hold). When the joint starts
// to slide, the friction compensation supplies that torque, so the entry hold leaves the
// integrator then; carried on, it would add to the compensation and drive the joint on.
#include <phri/core/discrete_transfer_function.hpp>
#include <phri/lowlevel/friction_compensation.hpp>
#include <phri/robot/actuator_table.hpp>

#include <Eigen/Core>

#include <vector>

namespace phri {

struct CustomTorqueSettings {
  double period_s = 1e-3;             ///< control period (H(z) is designed for 1 kHz)
  double transfer_gain = 5.0;         ///< lambda on H(z) (paper demo: 5 on every joint)
  double integral_gain = 20.0;        ///< K_I [1/s]: DC gain K_I / theta
  double integral_leak = 1.0;         ///< theta [1/s]: leak time constant 1 / theta
  double integral_limit_fraction = 0.05;  ///< |I| <= fraction * torque limit (paper code: 5 %)
  bool friction_compensation = true;
  bool rotor_inertia_compensation = true;
  /// H(z) on the torque error, b / a in powers of z^-1 (a robot bundle's custom_loop_filter);
  /// both empty: Kinova's, the paper's (DiscreteTransferFunction::kinova_high_velocity()).
  std::vector<double> filter_numerator;
  std::vector<double> filter_denominator;
};

class CustomTorqueController {
public:
  /// Throws ConfigError on bad settings (non-positive period, negative gains, H(z) period != 1 ms
  /// is allowed but documented as outside the identified design).
  CustomTorqueController(const ActuatorTable& actuators, const CustomTorqueSettings& settings = {});

  int dof() const { return static_cast<int>(actuators_.size()); }

  /// Bumpless entry: the loop's first output equals `current_now` for these inputs.
  void reset(const Eigen::VectorXd& current_now, const Eigen::VectorXd& tau_desired, const Eigen::VectorXd& qdd_desired,
             const Eigen::VectorXd& tau_sensor, const Eigen::VectorXd& qd);
  /// One period: returns the motor current command [A].
  const Eigen::VectorXd& update(const Eigen::VectorXd& tau_desired, const Eigen::VectorXd& qdd_desired,
                                const Eigen::VectorXd& tau_sensor, const Eigen::VectorXd& qd);

  const Eigen::VectorXd& current() const { return current_; }
  /// Terms of the last update, joint side [N.m], for logs.
  const Eigen::VectorXd& friction_term() const { return friction_; }
  const Eigen::VectorXd& rotor_term() const { return rotor_; }
  const Eigen::VectorXd& filter_term() const { return filtered_; }
  const Eigen::VectorXd& integral_term() const { return integral_; }
  /// What is left of the entry's motor-to-sensor share (see the header comment) [N.m].
  const Eigen::VectorXd& entry_hold() const { return entry_hold_; }
  const Eigen::VectorXd& torque_command() const { return tau_command_; }
  const std::vector<FrictionCase>& friction_cases() const { return cases_; }
  /// Joints whose current saturated in the last update.
  int saturated_count() const { return saturated_; }
  const CustomTorqueSettings& settings() const { return settings_; }

private:
  std::vector<ActuatorParameters> actuators_;
  CustomTorqueSettings settings_;
  std::vector<DiscreteTransferFunction> filters_;
  double leak_factor_ = 0.0;   // a = exp(-theta T)
  double input_factor_ = 0.0;  // K_I (1 - a) / theta
  Eigen::VectorXd integral_limit_;
  Eigen::VectorXd friction_, rotor_, filtered_, integral_, tau_command_, current_;
  Eigen::VectorXd entry_hold_;  // the integrator's share that friction explains (see the header) [N.m]
  std::vector<FrictionCase> cases_;
  int saturated_ = 0;
};

}  // namespace phri
