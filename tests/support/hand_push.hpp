#pragma once
// A push as a hand gives it, for the simulated plant's disturbance timeline: a force at a point of
// a body (world axes) rising over 50 ms, held, then released.
#include <phri/config/external_force.hpp>

#include <string>

namespace phri::test {

inline ExternalForce hand_push(const std::string& body, const Eigen::Vector3d& point, const Eigen::Vector3d& force,
                               double start_s, double duration_s) {
  ExternalForce f;
  f.body = body;
  f.point_m = point;
  f.force_N = force;
  f.profile = ExternalForce::Profile::kRamp;
  f.rise_s = 0.05;
  f.start_s = start_s;
  f.duration_s = duration_s;
  return f;
}

}  // namespace phri::test
