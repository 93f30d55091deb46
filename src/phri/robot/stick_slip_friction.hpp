#pragma once
// phri::StickSlipFriction: dry friction of one joint, elasto-plastic ("reset integrator") model
// (Haessig & Friedland 1991; Dupont et al. 2002): while sticking, the joint is held by a stiff
// presliding spring-damper anchored where it stuck; it breaks away when the spring force exceeds
// the static level, then slides with exactly the Coulomb level opposing the motion; it sticks again
// when it slows below the breakaway speed (or reverses). Viscous friction is separate.
//
//   at rest, |net torque| < static  -> no motion beyond the presliding deflection (static / k)
//   at rest, |net torque| > static  -> breakaway, then kinetic friction = coulomb * sign(qd)
//
// The simulator integrates it explicitly at the physics rate: with stiffness k = I w^2 and
// damping c = 2 zeta I w for an inertia I that bounds the joint's apparent inertia from below
// (the reflected rotor inertia does: M >= diag(I_r G_r^2)), and w dt = 0.5, every presliding mode
// stays within the stability region of the semi-implicit Euler step. At 4 kHz with I = 0.03 kg.m^2
// (the Gen3's reflected rotor inertia): k = 1.2e5 N.m/rad, deflection at 2.15 N.m = 1.8e-5 rad,
// below the encoder quantum.
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
    double stiffness_Nm_per_rad = 0.0;       ///< presliding stiffness k (> 0)
    double damping_Nms_per_rad = 0.0;        ///< presliding damping c
    double breakaway_velocity_rad_s = 1e-3;  ///< below this speed a sliding joint sticks again
  };

  StickSlipFriction() = default;
  explicit StickSlipFriction(const Parameters& p) : p_(p) {}

  /// Stuck at q with no deflection.
  void reset(double q) {
    anchor_ = q;
    direction_ = 0;
    reached_speed_ = false;
  }

  /// Friction torque on the joint for the coming step, from the joint state at its start.
  double update(double q, double qd) {
    if (direction_ != 0) {
      const bool reversed = qd * direction_ < 0.0;
      const bool fast = std::abs(qd) >= p_.breakaway_velocity_rad_s;
      reached_speed_ = reached_speed_ || fast;
      if (reversed || (reached_speed_ && !fast)) {
        // Stick again, keeping the current (Coulomb-level) deflection: the spring takes over.
        direction_ = 0;
        reached_speed_ = false;
      } else {
        anchor_ = q - direction_ * p_.coulomb_Nm / p_.stiffness_Nm_per_rad;
        return -direction_ * p_.coulomb_Nm;
      }
    }
    const double spring = p_.stiffness_Nm_per_rad * (q - anchor_);
    if (std::abs(spring) > p_.static_Nm) {
      direction_ = spring > 0.0 ? 1 : -1;
      reached_speed_ = std::abs(qd) >= p_.breakaway_velocity_rad_s;
      anchor_ = q - direction_ * p_.coulomb_Nm / p_.stiffness_Nm_per_rad;
      return -direction_ * p_.coulomb_Nm;
    }
    return std::clamp(-spring - p_.damping_Nms_per_rad * qd, -p_.static_Nm, p_.static_Nm);
  }

  bool sliding() const { return direction_ != 0; }
  /// Presliding deflection q - anchor at the last update [rad].
  double anchor() const { return anchor_; }
  const Parameters& parameters() const { return p_; }

private:
  Parameters p_;
  double anchor_ = 0.0;
  int direction_ = 0;  ///< 0 sticking, +-1 sliding in that direction
  bool reached_speed_ = false;
};

}  // namespace phri
