#include <phri/trajectory/brakes.hpp>

#include <phri/control/end_effector_task.hpp>

#include <algorithm>
#include <cmath>

namespace phri {

HermiteBrake::Terms HermiteBrake::at(double tau) {
  tau = std::clamp(tau, 0.0, 1.0);
  const double t2 = tau * tau, t3 = t2 * tau, t4 = t3 * tau;
  Terms k;
  k.h = 2.0 * t3 - 3.0 * t2 + 1.0;
  k.dh = 6.0 * t2 - 6.0 * tau;
  k.g = t3 - 2.0 * t2 + tau;
  k.dg = 3.0 * t2 - 4.0 * tau + 1.0;
  k.H = 0.5 * t4 - t3 + tau;
  k.G = 0.25 * t4 - 2.0 / 3.0 * t3 + 0.5 * t2;
  return k;
}

void PoseBrake::start(const PoseReference& from, const BrakeSettings& settings) {
  from_ = from.pose;
  velocity_ = from.velocity;
  acceleration_ = from.acceleration;
  duration_ = std::max({settings.min_duration_s,
                        HermiteBrake::kPeakDeceleration * velocity_.head<3>().norm() / settings.linear_deceleration_m_s2,
                        HermiteBrake::kPeakDeceleration * velocity_.tail<3>().norm() / settings.angular_deceleration_rad_s2});
}

void PoseBrake::evaluate(double t, PoseReference& out) const {
  const double T = duration_;
  const bool done = t >= T;
  const HermiteBrake::Terms k = HermiteBrake::at(T > 0.0 ? t / T : 1.0);
  const Vector6d displacement = T * (k.H * velocity_ + T * k.G * acceleration_);
  out.pose.translation() = from_.translation() + displacement.head<3>();
  const Eigen::Vector3d rotation = displacement.tail<3>();
  const double angle = rotation.norm();
  out.pose.linear() = angle > 1e-15 ? Eigen::Matrix3d(Eigen::AngleAxisd(angle, rotation / angle).toRotationMatrix() *
                                                      from_.linear())
                                    : from_.linear();
  if (done) {
    out.velocity.setZero();
    out.acceleration.setZero();
    return;
  }
  out.velocity = k.h * velocity_ + T * k.g * acceleration_;
  out.acceleration = (k.dh / T) * velocity_ + k.dg * acceleration_;
}

void JointBrake::start(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd,
                       const BrakeSettings& settings) {
  from_ = q;
  velocity_ = qd;
  acceleration_ = qdd;
  duration_ = std::max(settings.min_duration_s, HermiteBrake::kPeakDeceleration * velocity_.cwiseAbs().maxCoeff() /
                                                    settings.joint_deceleration_rad_s2);
}

void JointBrake::evaluate(double t, Eigen::VectorXd& q, Eigen::VectorXd& qd, Eigen::VectorXd& qdd) const {
  const double T = duration_;
  const HermiteBrake::Terms k = HermiteBrake::at(T > 0.0 ? t / T : 1.0);
  q = from_ + (T * k.H) * velocity_ + (T * T * k.G) * acceleration_;
  if (t >= T) {
    qd.setZero();
    qdd.setZero();
    return;
  }
  qd = k.h * velocity_ + (T * k.g) * acceleration_;
  qdd = (k.dh / T) * velocity_ + k.dg * acceleration_;
}

}  // namespace phri
