#pragma once
// The paper's friction pre-compensation (section "Low-level Control", eq. friction model), per
// joint, with the parameters of phri::FrictionParameters:
//
//   |qd| >= qd_th                      : tau_f = tau_c sign(qd) + tau_v qd     (sliding)
//   |qd| <  qd_th and |qdd_d| >= qdd_th : tau_f = tau_s sign(qdd_d)             (breakaway in the
//                                                                                 direction asked)
//   otherwise                          : tau_f = 0
//
// The desired acceleration qdd_d already contains the push of a human (the QP's compliant tasks),
// so static friction is pre-compensated in the direction the operator moves the arm.
#include <phri/robot/friction_parameters.hpp>

#include <cmath>

namespace phri {

enum class FrictionCase { kNone = 0, kStatic = 1, kSliding = 2 };

inline double friction_compensation(const FrictionParameters& p, double qd, double qdd_desired,
                                    FrictionCase* which = nullptr) {
  if (std::abs(qd) >= p.velocity_threshold_rad_s) {
    if (which) *which = FrictionCase::kSliding;
    return std::copysign(p.coulomb_Nm, qd) + p.viscous_Nms_per_rad * qd;
  }
  if (std::abs(qdd_desired) >= p.acceleration_threshold_rad_s2) {
    if (which) *which = FrictionCase::kStatic;
    return std::copysign(p.static_Nm, qdd_desired);
  }
  if (which) *which = FrictionCase::kNone;
  return 0.0;
}

}  // namespace phri
