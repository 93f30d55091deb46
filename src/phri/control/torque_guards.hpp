#pragma once
// The torque-level guards behind the QP (Controller::guard_torque): the maths of the velocity
// guard's coupling bound and of the collision guard, free of the controller's state.
#include <phri/model/collision_model.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <cmath>

namespace phri {

/// Velocity guard: damping D_ii on each joint i above its guard speed (excess_i > 0). Applied as a
/// torque, it changes the guarded joints' speeds by T (M^-1)_SS D e per cycle (T the period, M^-1
/// the mobility, S the guarded set). A per-joint rate x M_ii is stable alone only where
/// M_ii (M^-1)_ii is small: where another joint turns about nearly the same axis (the Gen3's joints
/// 1 and 3 near q2 = 0) it reaches ~7.5, and a per-joint guard rings (replayed: SafetyFuzz.FormerFailuresReplayedPass, seed 60606
/// full_body/custom/0). Returns the scale in (0, 1] that keeps the largest eigenvalue of
/// T D^1/2 (M^-1)_SS D^1/2 (bounded by Gershgorin's row sums) within max_step; 1 where nothing is
/// guarded.
inline double guard_coupling_scale(const Eigen::MatrixXd& mobility, const Eigen::VectorXd& damping,
                                   const Eigen::VectorXd& excess, double period_s, double max_step) {
  double largest = 0.0;
  for (Eigen::Index i = 0; i < excess.size(); ++i) {
    if (!(excess[i] > 0.0)) continue;
    double row = 0.0;
    for (Eigen::Index j = 0; j < excess.size(); ++j) {
      if (excess[j] > 0.0) row += std::sqrt(damping[i] * damping[j]) * std::abs(mobility(i, j));
    }
    largest = std::max(largest, row * period_s);
  }
  return largest > max_step ? max_step / largest : 1.0;
}

/// Collision guard: every capsule pair closer than the damper's safety distance d_s is pushed
/// apart through its distance Jacobian, tau += J_d^T (stiffness x depth + damping x approach
/// speed), J_d^T F being the joint torque of a force F that separates the pair. Returns whether
/// any pair was inside d_s.
inline bool add_collision_guard(const CollisionData& pairs, double safety_distance, double stiffness,
                                double damping, Eigen::VectorXd& tau) {
  bool inside = false;
  for (Eigen::Index p = 0; p < pairs.distance.size(); ++p) {
    const double depth = safety_distance - pairs.distance[p];
    if (!(depth > 0.0)) continue;
    const double force = stiffness * depth + damping * std::max(-pairs.velocity[p], 0.0);
    tau.noalias() += force * pairs.jacobian.row(p).transpose();
    inside = true;
  }
  return inside;
}

}  // namespace phri
