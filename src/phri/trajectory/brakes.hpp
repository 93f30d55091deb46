#pragma once
// Bringing a moving reference to rest at a bounded deceleration with continuous velocity and
// acceleration, so that no scenario change steps the reference or its feed-forward: one Hermite
// brake, for end-effector references (PoseBrake) and joint references (JointBrake).
#include <phri/control/controller_targets.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

namespace phri {

/// How a moving reference is brought to rest (PoseBrake, JointBrake).
struct BrakeSettings {
  double linear_deceleration_m_s2 = 1.0;      ///< bound of the velocity term's deceleration
  double angular_deceleration_rad_s2 = 2.0;
  double joint_deceleration_rad_s2 = 1.0;     ///< joint-space references (start-up move)
  double min_duration_s = 0.2;                ///< keeps the jerk of the initial acceleration's fade bounded
};

/// Brings a moving reference to rest with continuous velocity AND acceleration: over a duration
/// T, velocity v(tau) = v0 h00(tau) + T a0 h10(tau) (cubic Hermite basis, tau = t / T), from (v0,
/// a0) at the start to (0, 0) at the end; position its integral. The velocity term decelerates at
/// most 1.5 |v0| / T, so T = max(min_duration, 1.5 |v0| / deceleration); the initial
/// acceleration a0 fades out within the same T. Per component of the twist; the orientation
/// integrates the angular part as a rotation vector (exact for a fixed axis; the brakes here start
/// from pure linear motion or a fixed-axis rotation).
struct HermiteBrake {
  struct Terms {
    double h = 0.0, dh = 0.0;  // velocity basis value and its derivative (per tau), for v0
    double g = 0.0, dg = 0.0;  // for T a0
    double H = 0.0, G = 0.0;   // integrals (per tau) of h and g
  };
  static Terms at(double tau);
  static constexpr double kPeakDeceleration = 1.5;  ///< max |dh/dtau|
};

class PoseBrake {
public:
  void start(const PoseReference& from, const BrakeSettings& settings);
  void evaluate(double t, PoseReference& out) const;
  double duration() const { return duration_; }

private:
  Eigen::Isometry3d from_ = Eigen::Isometry3d::Identity();
  Vector6d velocity_ = Vector6d::Zero(), acceleration_ = Vector6d::Zero();
  double duration_ = 0.0;
};

/// The same brake in joint space (every joint over the same time: the path keeps its shape).
class JointBrake {
public:
  explicit JointBrake(int nv)
      : from_(Eigen::VectorXd::Zero(nv)), velocity_(Eigen::VectorXd::Zero(nv)), acceleration_(Eigen::VectorXd::Zero(nv)) {}
  void start(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd,
             const BrakeSettings& settings);
  void evaluate(double t, Eigen::VectorXd& q, Eigen::VectorXd& qd, Eigen::VectorXd& qdd) const;
  double duration() const { return duration_; }

private:
  Eigen::VectorXd from_, velocity_, acceleration_;
  double duration_ = 0.0;
};

}  // namespace phri
