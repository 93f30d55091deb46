#pragma once
// phri::StickSlipFriction: dry friction of one joint, elasto-plastic ("reset integrator") model
// (Haessig & Friedland 1991; Dupont et al. 2002): while sticking, the joint is held by a stiff
// presliding spring-damper anchored where it stuck; it breaks away when the spring torque exceeds
// the static level, then slides with the Coulomb level (or the form below) opposing the motion; it sticks
// again when it slows below the breakaway speed after having exceeded it, or reverses. Viscous
// friction is separate.
//
//   at rest, |net torque| < static  -> no motion beyond the presliding deflection (torque / k)
//   at rest, |net torque| > static  -> breakaway, then kinetic friction = coulomb * sign(qd)
//
// Integration in the simulator (semi-implicit Euler at the physics rate):
// * update() gives the explicit part, the spring torque (or +-coulomb when sliding). Its stiffness
//   k = I w^2 with w dt = 0.5 and I = the reflected rotor inertia, a lower bound of the joint's
//   apparent inertia (M >= diag(I_r G_r^2)), so every presliding mode of the arm stays inside the
//   stability region of the explicit step. At 4 kHz with I = 0.03 kg.m^2: k = 1.2e5 N.m/rad, i.e.
//   1.8e-5 rad of deflection at 2.15 N.m, below the encoder quantum.
// * damping() is the presliding damper c (0 while sliding), applied implicitly by MuJoCo (joint
//   damping in its Euler step), so it can be large: c = 2 sqrt(k I_ref) makes the presliding
//   motion critically damped up to I_ref = 5 kg.m^2 of apparent inertia. An underdamped presliding
//   spring would overshoot a sudden load by up to 2x and break away below the static level.
//
// Sliding-friction form (off by default: the levels above are exact): a Stribeck curve and a
// position-dependent ripple, for a plant whose friction differs in form from the identified model
// c0 + tau_c sign(v) + tau_v v (experiments/friction_identification.hpp). Sliding at speed |v|:
//
//   level(q, v) = tau_c + (tau_s - tau_c) exp(-(|v| / v_s)^delta) + a_r tau_c sin(n_r q + phi)
//
// (Stribeck curve as in Armstrong-Helouvry, Dupont & Canudas de Wit 1994; the ripple is the harmonic
// drive's cyclic friction variation, Taghirad & Belanger 1998), and at rest the breakaway level is
// tau_s + a_r tau_c sin(n_r q + phi), so the curve is continuous at breakaway. Both terms are explicit,
// bounded between tau_c (1 - a_r) and tau_s + a_r tau_c, and add no stiffness the step must resolve:
// the Stribeck slope is a negative damping of at most 0.86 (tau_s - tau_c) / v_s (delta = 2), which
// the explicit step follows no faster than the physics grows (1 + c dt / I <= exp(c dt / I)); the
// ripple's position gradient a_r tau_c n_r (~40 N.m/rad) is far below the presliding stiffness.
//
// Why not MuJoCo's own dry friction (dof frictionloss)? It is a soft constraint: with MuJoCo's
// defaults a Gen3 joint loaded at 70 % of the friction level creeps ~1 rad in 2 s; made as stiff as
// MuJoCo allows (solimp 0.9999, solref 2 dt) it still creeps ~2e-5 rad/s, has a single level
// (static = Coulomb), and its 7-row constraint solve costs ~40 % of each physics step.
#include <algorithm>
#include <cmath>

namespace phri {

class StickSlipFriction {
public:
  struct Parameters {
    double coulomb_Nm = 0.0;                 ///< kinetic level
    double static_Nm = 0.0;                  ///< breakaway level (>= coulomb)
    double stiffness_Nm_per_rad = 1.0;       ///< presliding stiffness k (> 0)
    double damping_Nms_per_rad = 0.0;        ///< presliding damping c (applied implicitly)
    double breakaway_velocity_rad_s = 1e-3;  ///< a sliding joint slower than this sticks again
    double stribeck_velocity_rad_s = 0.0;    ///< v_s; 0: no Stribeck curve (sliding level = Coulomb)
    double stribeck_exponent = 2.0;          ///< delta
    double ripple_Nm = 0.0;                  ///< a_r tau_c: amplitude of the position-dependent ripple
    double ripple_cycles_per_rev = 0.0;      ///< n_r: ripple periods per joint revolution
    double ripple_phase_rad = 0.0;           ///< phi
  };

  /// Position-dependent part of the dry friction level (0 when the ripple is off).
  static double ripple(const Parameters& p, double q) {
    return p.ripple_Nm != 0.0 ? p.ripple_Nm * std::sin(p.ripple_cycles_per_rev * q + p.ripple_phase_rad) : 0.0;
  }
  /// Dry friction level sliding at `speed` (>= 0) at position q: exactly coulomb_Nm with both terms off.
  static double sliding_level(const Parameters& p, double q, double speed) {
    double level = p.coulomb_Nm;
    if (p.stribeck_velocity_rad_s > 0.0) {
      level += (p.static_Nm - p.coulomb_Nm) * std::exp(-std::pow(speed / p.stribeck_velocity_rad_s, p.stribeck_exponent));
    }
    return level + ripple(p, q);
  }
  /// Breakaway level at rest at position q: exactly static_Nm with the ripple off.
  static double breakaway_level(const Parameters& p, double q) { return p.static_Nm + ripple(p, q); }

  /// Presliding stiffness and damping for a physics step `dt` and a reflected inertia (see above).
  static Parameters presliding(double coulomb, double stat, double reflected_inertia, double dt,
                               double breakaway_velocity) {
    Parameters p;
    const double w = 0.5 / dt;
    p.coulomb_Nm = coulomb;
    p.static_Nm = stat;
    p.stiffness_Nm_per_rad = reflected_inertia * w * w;
    p.damping_Nms_per_rad = 2.0 * std::sqrt(p.stiffness_Nm_per_rad * 5.0);
    p.breakaway_velocity_rad_s = breakaway_velocity;
    return p;
  }

  StickSlipFriction() = default;
  explicit StickSlipFriction(const Parameters& p) : p_(p) {}

  /// Stuck at q with no deflection.
  void reset(double q) {
    anchor_ = q;
    direction_ = 0;
    reached_speed_ = false;
  }

  /// Explicit friction torque on the joint for the coming step, from the state at its start;
  /// afterwards damping() tells the implicit presliding damping of that step.
  double update(double q, double qd) {
    if (direction_ != 0) {
      const bool reversed = qd * direction_ < 0.0;
      const bool fast = std::abs(qd) >= p_.breakaway_velocity_rad_s;
      reached_speed_ = reached_speed_ || fast;
      if (reversed || (reached_speed_ && !fast)) {
        // Stick again at the current (Coulomb-level) deflection: the spring takes over.
        direction_ = 0;
        reached_speed_ = false;
      } else {
        const double level = sliding_level(p_, q, std::abs(qd));
        anchor_ = q - direction_ * level / p_.stiffness_Nm_per_rad;
        return -direction_ * level;
      }
    }
    const double spring = p_.stiffness_Nm_per_rad * (q - anchor_);
    if (std::abs(spring) > breakaway_level(p_, q)) {
      direction_ = spring > 0.0 ? 1 : -1;
      reached_speed_ = std::abs(qd) >= p_.breakaway_velocity_rad_s;
      const double level = sliding_level(p_, q, std::abs(qd));
      anchor_ = q - direction_ * level / p_.stiffness_Nm_per_rad;
      return -direction_ * level;
    }
    return -spring;
  }

  /// Presliding damping of the step prepared by update() (0 while sliding) [N.m.s/rad].
  double damping() const { return direction_ == 0 ? p_.damping_Nms_per_rad : 0.0; }
  bool sliding() const { return direction_ != 0; }
  double anchor() const { return anchor_; }
  const Parameters& parameters() const { return p_; }

private:
  Parameters p_;
  double anchor_ = 0.0;
  int direction_ = 0;  ///< 0 sticking, +-1 sliding in that direction
  bool reached_speed_ = false;
};

}  // namespace phri
