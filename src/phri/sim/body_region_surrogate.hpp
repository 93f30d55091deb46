#pragma once
// A body region as the standard's two-body model builds it (ISO/TS 15066 Annex A.3): a mass m_H
// behind a spring k (and an optional damper c) that the robot meets, as the standard's force
// measuring devices are built. The spring is compressed by how far the robot has gone past the
// face where it rests, less how far the mass has recoiled:
//
//   compression  x = s - x_H                s: the robot's depth past the face at rest
//   force        F = max(0, k x + c dx/dt)  while x > 0 (it only pushes), 0 otherwise
//   the mass     m_H dd(x_H) = F            free (a transient contact: the body recoils), or
//                x_H = 0                    backed by a wall (a clamping, quasi-static contact)
//
// Integrated with the plant's physics step (semi-implicit Euler, as MuJoCo's); the simulator
// applies F to the robot at its deepest point (sim_robot.cpp). No MuJoCo contact is involved, so
// the force is the model's own and not the contact solver's softness.
#include <phri/config/sim_robot_config.hpp>

namespace phri {

class BodyRegionSurrogate {
public:
  explicit BodyRegionSurrogate(const BodyRegionSurrogateSettings& settings = {}) : settings_(settings) {}

  /// Back at rest, untouched.
  void reset();
  /// One step of `dt` with the robot `depth_m` past the face at rest (negative: in front of it),
  /// `over_face` whether it is over the face (not beside it); returns the force on the robot,
  /// along the face's normal [N]. A contact begins only through the face (the step before, the
  /// robot was in front of it): a robot that comes back over the face from beside or behind the
  /// body is not pushed out of it.
  double step(double depth_m, bool over_face, double dt);

  double force_N() const { return force_; }
  /// Of the spring while touched; 0 otherwise.
  double compression_m() const { return touching_ ? compression_ : 0.0; }
  bool touching() const { return touching_; }
  /// How far the mass has recoiled from its rest [m] (0 against a wall).
  double displacement_m() const { return displacement_; }
  double velocity_m_s() const { return velocity_; }
  const BodyRegionSurrogateSettings& settings() const { return settings_; }

private:
  BodyRegionSurrogateSettings settings_;
  double displacement_ = 0.0, velocity_ = 0.0;
  double compression_ = 0.0, previous_compression_ = 0.0;
  double force_ = 0.0;
  bool touching_ = false;
};

}  // namespace phri
