#pragma once
// phri::ExternalForce: one scripted disturbance on the simulated arm: a force (and optional
// moment) applied at a point of a body, in the world frame or in the body's own frame, with a
// time profile. A timeline of them lives in the plant configuration (SimRobotConfig::disturbances).
//
// Profiles (t0 = start_s, T = duration_s; 0 outside [t0, t0 + T)):
//   kStep     : 1
//   kRamp     : min(1, (t - t0) / rise_s)   (rise_s <= T; a ramp up, hold, then release at t0 + T)
//   kHalfSine : sin(pi (t - t0) / T)        (a push with a smooth rise and fall, e.g. a hand)
#include <Eigen/Core>

#include <cmath>
#include <numbers>
#include <string>

namespace phri {

struct ExternalForce {
  enum class Profile { kStep, kRamp, kHalfSine };
  enum class Frame { kWorld, kLocal };

  std::string body;                                     ///< MJCF body name (arm link, "tool", "drop_mass")
  Eigen::Vector3d point_m = Eigen::Vector3d::Zero();    ///< application point in the body frame [m]
  Frame frame = Frame::kWorld;                          ///< axes of force_N and torque_Nm
  Eigen::Vector3d force_N = Eigen::Vector3d::Zero();    ///< full-scale force [N]
  Eigen::Vector3d torque_Nm = Eigen::Vector3d::Zero();  ///< full-scale pure moment [N.m]
  Profile profile = Profile::kStep;
  double start_s = 0.0;
  double duration_s = 0.0;
  double rise_s = 0.0;  ///< kRamp only

  /// Profile value in [0, 1] at time t.
  double scale_at(double t) const {
    const double s = t - start_s;
    if (s < 0.0 || s >= duration_s) return 0.0;
    switch (profile) {
      case Profile::kStep: return 1.0;
      case Profile::kRamp: return rise_s > 0.0 ? std::min(1.0, s / rise_s) : 1.0;
      case Profile::kHalfSine: return std::sin(std::numbers::pi * s / duration_s);
    }
    return 0.0;
  }
};

}  // namespace phri
