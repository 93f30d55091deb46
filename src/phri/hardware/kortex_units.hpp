#pragma once
// Unit and angle conventions between phri (SI, radians, continuous joints unwrapped) and the
// Kortex low-level API (degrees; positions in [0, 360); the measured torque's sign reversed).
// Sources (kortex_lowlevel.md section 6): Kinova's example 200 wraps position commands with
// fmod 360; ros2_kortex sends [0, 360) and maps feedback to [-pi, pi]; mc_kortex maps feedback
// deg < 180 ? deg : deg - 360. Kinova's example 108: "Torque measure is reversed compared to
// actuator direction" (mc_kortex: tau = -torque).
#include <cmath>
#include <numbers>

namespace phri::kortex {

inline constexpr double kDegPerRad = 180.0 / std::numbers::pi;
inline constexpr double kRadPerDeg = std::numbers::pi / 180.0;

/// An angle [deg] in [0, 360), as the actuators take position commands.
inline double wrap_degrees_0_360(double deg) {
  double w = std::fmod(deg, 360.0);
  if (w < 0.0) w += 360.0;
  return w >= 360.0 ? 0.0 : w;  // fmod of a tiny negative can round up to 360
}

/// A command angle [rad] as the float [deg] in [0, 360) the actuator receives.
inline float command_degrees(double q_rad) {
  const float deg = static_cast<float>(wrap_degrees_0_360(q_rad * kDegPerRad));
  return deg >= 360.0f ? 0.0f : deg;  // rounding to float can reach 360
}

/// A feedback angle [deg] (any turn, [0, 360) from the arm) as radians in (-pi, pi].
inline double feedback_radians(double deg) {
  double w = wrap_degrees_0_360(deg);  // [0, 360)
  if (w > 180.0) w -= 360.0;           // (-180, 180]
  return w * kRadPerDeg;
}

/// The angle equal to `wrapped` modulo 2 pi nearest to `previous` [rad]: a continuous joint's
/// reading followed across turns, so q never jumps by 2 pi.
inline double unwrap_near(double previous, double wrapped) {
  const double two_pi = 2.0 * std::numbers::pi;
  return previous + std::remainder(wrapped - previous, two_pi);
}

/// The shortest signed difference a - b between two angles [deg], in [-180, 180].
inline double degrees_between(double a, double b) { return std::remainder(a - b, 360.0); }

/// The measured joint torque in phri's convention (the direction of positive q, as commanded).
inline double joint_torque_from_feedback(float feedback_torque_Nm) { return -static_cast<double>(feedback_torque_Nm); }
inline float feedback_torque_from_joint(double tau_Nm) { return static_cast<float>(-tau_Nm); }

/// Motor current for a joint torque: i = tau / (K_T G_r) (kinova_gen3_actuators.md: K_T 0.11 /
/// 0.076 N.m/A, G_r 100; mc_kortex i = tau / (100 K_T)). `torque_per_amp` = K_T G_r [N.m/A].
inline double motor_current_for_torque(double tau_Nm, double torque_per_amp) {
  return torque_per_amp > 0.0 ? tau_Nm / torque_per_amp : 0.0;
}

}  // namespace phri::kortex
