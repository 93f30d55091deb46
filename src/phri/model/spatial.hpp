#pragma once
// Spatial-vector helpers. phri's dynamics run in the world frame: a spatial motion (v; w) is the
// velocity of the body point at the world origin and the angular velocity; a spatial force (f; n)
// is a force and its moment about the world origin. Linear part first, as in Pinocchio.
#include <Eigen/Core>

namespace phri {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6Xd = Eigen::Matrix<double, 6, Eigen::Dynamic>;

/// Motion cross product m1 x m2 (Featherstone's crm).
inline Vector6d motion_cross(const Vector6d& m1, const Vector6d& m2) {
  const auto v1 = m1.head<3>(), w1 = m1.tail<3>(), v2 = m2.head<3>(), w2 = m2.tail<3>();
  Vector6d out;
  out.head<3>() = w1.cross(v2) + v1.cross(w2);
  out.tail<3>() = w1.cross(w2);
  return out;
}

/// Dual cross product m x* f (Featherstone's crf).
inline Vector6d force_cross(const Vector6d& m, const Vector6d& f) {
  const auto v = m.head<3>(), w = m.tail<3>(), fl = f.head<3>(), n = f.tail<3>();
  Vector6d out;
  out.head<3>() = w.cross(fl);
  out.tail<3>() = w.cross(n) + v.cross(fl);
  return out;
}

/// A rigid body's inertia about the world origin, in world axes: mass m, first moment h = m c,
/// rotational inertia I about the origin. Sums of bodies are plain sums (composite inertia).
struct WorldInertia {
  double mass = 0.0;
  Eigen::Vector3d first_moment = Eigen::Vector3d::Zero();
  Eigen::Matrix3d rotational = Eigen::Matrix3d::Zero();

  void set_zero() {
    mass = 0.0;
    first_moment.setZero();
    rotational.setZero();
  }
  WorldInertia& operator+=(const WorldInertia& o) {
    mass += o.mass;
    first_moment += o.first_moment;
    rotational += o.rotational;
    return *this;
  }
  /// Momentum of the body moving with spatial velocity m: (m v - h x w ; I w + h x v).
  Vector6d apply(const Vector6d& motion) const {
    const auto v = motion.head<3>(), w = motion.tail<3>();
    Vector6d f;
    f.head<3>() = mass * v - first_moment.cross(w);
    f.tail<3>() = rotational * w + first_moment.cross(v);
    return f;
  }
};

}  // namespace phri
