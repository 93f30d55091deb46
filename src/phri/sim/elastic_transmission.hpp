#pragma once
// phri::ElasticTransmission: one joint's motor side behind a torsional spring, for a plant with
// joint elasticity (SimRobotConfig::Elasticity). The reducer (a harmonic drive) and the torque
// sensor's flexure sit between the rotor and the link; the torque sensor measures the spring:
//
//   B theta_dd = tau_m + f_dry(theta, theta_d) - b theta_d - tau_spring     (rotor, link-side units)
//   tau_spring = K (theta - q) + D (theta_d - q_d)                           (on the link)
//
// B = I_r G_r^2 (the reflected rotor inertia, no longer on the link), b the viscous friction and
// f_dry the stick-slip friction of the drive (StickSlipFriction), all on the motor side: the paper
// places the friction "between the motor and torque sensor, usually in the harmonic drive".
// Semi-implicit Euler at the physics rate: step() advances the rotor from the state at the start
// of the step (the link's q, q_d there too, the spring torque applied to the link over the same
// step), with the viscous, presliding and spring damping implicit. The explicit spring is stable
// for sqrt(K / min(B, link inertia)) dt < 2: 1.3e4 N.m/rad on 0.03 kg.m^2 at 4 kHz gives 0.16.
#include <phri/sim/stick_slip_friction.hpp>

namespace phri {

class ElasticTransmission {
public:
  struct Parameters {
    double stiffness_Nm_per_rad = 1.0e4;  ///< K
    double damping_Nms_per_rad = 0.0;     ///< D, in parallel with K
    double rotor_inertia_kgm2 = 0.03;     ///< B, reflected
    double viscous_Nms_per_rad = 0.0;     ///< b
  };

  ElasticTransmission() = default;
  ElasticTransmission(const Parameters& p, const StickSlipFriction::Parameters& friction) : p_(p), dry_(friction) {}

  /// At rest with the link at q, the spring carrying `spring_torque` (wound by spring_torque / K).
  void reset(double q, double spring_torque) {
    theta_ = q + spring_torque / p_.stiffness_Nm_per_rad;
    theta_d_ = 0.0;
    dry_.reset(theta_);
    friction_ = 0.0;
  }

  /// The spring's torque on the link for link state (q, q_d).
  double spring_torque(double q, double q_d) const {
    return p_.stiffness_Nm_per_rad * (theta_ - q) + p_.damping_Nms_per_rad * (theta_d_ - q_d);
  }

  /// One physics step of the rotor under motor torque tau_m, the link at (q, q_d) at the step's start.
  void step(double tau_m, double q, double q_d, double dt) {
    const double f = dry_.update(theta_, theta_d_);
    const double c = p_.viscous_Nms_per_rad + dry_.damping() + p_.damping_Nms_per_rad;
    const double explicit_torque = tau_m + f - p_.stiffness_Nm_per_rad * (theta_ - q) + p_.damping_Nms_per_rad * q_d;
    const double b = p_.rotor_inertia_kgm2;
    const double v1 = (b * theta_d_ + dt * explicit_torque) / (b + dt * c);
    // Friction as it acted: the explicit part and the presliding damper on the new velocity.
    friction_ = f - dry_.damping() * v1 - p_.viscous_Nms_per_rad * v1;
    theta_d_ = v1;
    theta_ += dt * v1;
  }

  double position() const { return theta_; }   ///< theta [rad] (motor-side encoder / G_r)
  double velocity() const { return theta_d_; }  ///< [rad/s]
  /// Friction (dry + viscous) on the rotor over the last step [N.m].
  double friction_torque() const { return friction_; }
  const Parameters& parameters() const { return p_; }
  const StickSlipFriction& dry_friction() const { return dry_; }

private:
  Parameters p_;
  StickSlipFriction dry_;
  double theta_ = 0.0, theta_d_ = 0.0, friction_ = 0.0;
};

}  // namespace phri
