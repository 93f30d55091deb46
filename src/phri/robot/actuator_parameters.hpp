#pragma once
// phri::ActuatorParameters: the drive model of one joint (motor, gearbox, limits, friction), as
// read from robots/<robot>/actuators.yaml by phri::ActuatorTable. Joint side unless stated.
#include <phri/robot/friction_parameters.hpp>

#include <optional>
#include <string>

namespace phri {

/// Kinova's two actuator classes (the Gen3's joints 1-4 and 5-7); actuators.yaml's optional `size`.
enum class ActuatorSize { kLarge, kSmall };

/// What `size` selects when an actuators.yaml leaves it out, derived from the drive's own data:
/// - the compliance dead band: kDeadbandPerTorqueLimit x torque_limit_Nm (the Gen3's drives would
///   get 0.95 N.m on joints 1-4, 0.26 / 0.45 N.m on 5-7, against the 1.0 / 0.4 their sizes give);
/// - the class of a Kinova drive's emulated loops (the plant's vendor gains): large when the drive
///   can produce at least kLargeActuatorMinTorque_Nm (current_limit_A x K_T x G_r; the Gen3's
///   large 105 N.m, small 52 N.m), small below.
inline constexpr double kDeadbandPerTorqueLimit = 0.01;

/// What a maker publishes for a joint is its torque and speed limits; everything else in
/// actuators.yaml is optional, with these defaults (docs/robots.md; a notice for each one used,
/// ActuatorTable::notices()). A Kinova drive needs them all stated (its emulated loops run on them).
inline constexpr double kDefaultGearRatio = 100.0;              ///< a harmonic drive's typical ratio
inline constexpr double kDefaultTorqueConstant_Nm_per_A = 0.1;  ///< K_T G_r = 10 N.m/A with the ratio above
inline constexpr double kDefaultCurrentHeadroom = 1.1;          ///< current limit: 1.1 x torque_limit / (K_T G_r)
inline constexpr double kDefaultVelocityThreshold_rad_s = 0.1;  ///< friction model's thresholds (the Gen3's)
inline constexpr double kDefaultAccelerationThreshold_rad_s2 = 1.0;

/// The actuators.yaml keys a joint left out (bits of ActuatorParameters::defaulted).
enum ActuatorDefault : unsigned {
  kDefaultedGearRatio = 1u << 0,
  kDefaultedTorqueConstant = 1u << 1,
  kDefaultedRotorInertia = 1u << 2,
  kDefaultedReflectedInertia = 1u << 3,
  kDefaultedCurrentLimit = 1u << 4,
  kDefaultedFriction = 1u << 5,  ///< any key of the friction model
};
inline constexpr int kActuatorDefaultCount = 6;
inline constexpr double kLargeActuatorMinTorque_Nm = 75.0;

struct ActuatorParameters {
  std::string joint_name;
  /// actuators.yaml's `size` when stated (a Kinova actuator); nullopt: derived where needed (above).
  std::optional<ActuatorSize> size;
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
  /// The optional keys this joint left out (ActuatorDefault bits): their defaults are in use.
  unsigned defaulted = 0;

  /// Joint torque per motor ampere, K_T G_r [N.m/A]: tau_joint = K_T G_r i.
  double torque_per_amp() const { return torque_constant_Nm_per_A * gear_ratio; }
  /// Largest joint torque the motor can produce, K_T G_r i_max [N.m].
  double max_motor_torque_Nm() const { return current_limit_A * torque_per_amp(); }
  /// The Kinova class: `size` when stated, else by the drive's maximum torque (kLargeActuatorMinTorque_Nm).
  ActuatorSize size_class() const {
    if (size) return *size;
    return max_motor_torque_Nm() >= kLargeActuatorMinTorque_Nm ? ActuatorSize::kLarge : ActuatorSize::kSmall;
  }
  /// The compliance dead band by default [N.m]: by `size` when stated (large_Nm, small_Nm), else
  /// kDeadbandPerTorqueLimit x torque_limit_Nm.
  double default_compliance_deadband_Nm(double large_Nm, double small_Nm) const {
    if (size) return *size == ActuatorSize::kLarge ? large_Nm : small_Nm;
    return kDeadbandPerTorqueLimit * torque_limit_Nm;
  }
};

}  // namespace phri
