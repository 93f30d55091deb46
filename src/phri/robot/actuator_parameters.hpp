#pragma once
// phri::ActuatorParameters: the drive model of one joint (motor, gearbox, limits, friction), as
// read from robots/<robot>/actuators.yaml by phri::ActuatorTable. Joint side unless stated.
#include <phri/robot/friction_parameters.hpp>

#include <string>

namespace phri {

enum class ActuatorSize { kLarge, kSmall };

struct ActuatorParameters {
  std::string joint_name;
  ActuatorSize size = ActuatorSize::kLarge;
  double gear_ratio = 1.0;                ///< G_r, motor turns per joint turn
  double torque_constant_Nm_per_A = 0.0;  ///< K_T, motor side
  double rotor_inertia_kgm2 = 0.0;        ///< I_r, motor side
  double reflected_inertia_kgm2 = 0.0;    ///< I_r G_r^2, seen at the joint
  double current_limit_A = 0.0;           ///< motor current saturation
  double torque_limit_Nm = 0.0;           ///< joint torque bound for the controller (QP)
  double velocity_limit_rad_s = 0.0;      ///< joint velocity bound for the controller (QP)
  /// Torsional stiffness between rotor and torque sensor (harmonic drive) [N.m/rad]; 0: rigid.
  double transmission_stiffness_Nm_per_rad = 0.0;
  FrictionParameters friction;

  /// Joint torque per motor ampere, K_T G_r [N.m/A]: tau_joint = K_T G_r i.
  double torque_per_amp() const { return torque_constant_Nm_per_A * gear_ratio; }
  /// Largest joint torque the motor can produce, K_T G_r i_max [N.m].
  double max_motor_torque_Nm() const { return current_limit_A * torque_per_amp(); }
};

}  // namespace phri
