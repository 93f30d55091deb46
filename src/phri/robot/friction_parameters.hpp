#pragma once
// phri::FrictionParameters: the joint friction of one actuator, between the motor and the joint
// torque sensor (in the harmonic drive), on the joint side. The same numbers serve two readers:
// the simulated plant (robot/SimRobot: the friction the joint really has) and the low-level torque
// controller (its friction pre-compensation, the paper's friction model, section "Low-level
// Control"):
//   |qd| >= velocity_threshold                          : tau_f = coulomb sign(qd) + viscous qd
//   |qd| <  velocity_threshold, |qdd_d| >= acc_threshold : tau_f = static  sign(qdd_d)
//   otherwise                                           : tau_f = 0
// The thresholds belong to the compensation only; the plant uses coulomb/viscous/static.
namespace phri {

struct FrictionParameters {
  double coulomb_Nm = 0.0;                     ///< kinetic (Coulomb) friction level [N.m]
  double viscous_Nms_per_rad = 0.0;            ///< viscous coefficient [N.m.s/rad]
  double static_Nm = 0.0;                      ///< breakaway (static) friction level [N.m], >= coulomb
  double velocity_threshold_rad_s = 0.0;       ///< compensation: "moving" above this speed [rad/s]
  double acceleration_threshold_rad_s2 = 0.0;  ///< compensation: stiction pre-compensation [rad/s^2]
};

}  // namespace phri
