#include <phri/app/scenario.hpp>

#include <phri/control/end_effector_task.hpp>

#include <cmath>
#include <numbers>

namespace phri {

Quintic Quintic::at(double tau) {
  tau = std::clamp(tau, 0.0, 1.0);
  const double t2 = tau * tau, t3 = t2 * tau;
  Quintic q;
  q.s = t3 * (10.0 - 15.0 * tau + 6.0 * t2);
  q.ds = 30.0 * t2 * (1.0 - 2.0 * tau + t2);
  q.dds = 60.0 * tau * (1.0 - 3.0 * tau + 2.0 * t2);
  return q;
}

// ------------------------------------------------------------------------------------ triangle
SmoothTriangle::SmoothTriangle(double lo, double hi, double speed, double acceleration)
    : lo_(std::min(lo, 0.0)), hi_(std::max(hi, 0.0)), speed_(speed), accel_(acceleration) {
  const double span = hi_ - lo_;
  if (!(accel_ > 0.0)) accel_ = 1.0;
  // Too short a span for the turns at this speed: slow down until the two turns fill it.
  speed_ = std::min(std::max(speed_, 0.0), std::sqrt(accel_ * span));
  if (speed_ <= 0.0) return;  // no motion
  turn_ = speed_ / accel_;
  const double d = 0.5 * speed_ * turn_;  // distance covered by one half-turn
  cruise_ = std::max(0.0, (span - 2.0 * d) / speed_);
  leg_ = 2.0 * turn_ + cruise_;
  // Where the first leg (hi -> lo) passes through 0.
  if (hi_ - d >= 0.0 && lo_ + d <= 0.0) {
    phase_ = turn_ + (hi_ - d) / speed_;
  } else if (hi_ - d < 0.0) {
    phase_ = std::sqrt(2.0 * hi_ / accel_);
  } else {
    phase_ = leg_ - std::sqrt(-2.0 * lo_ / accel_);
  }
}

void SmoothTriangle::leg(double tau, double& x, double& v, double& a) const {
  if (tau < turn_) {
    x = hi_ - 0.5 * accel_ * tau * tau;
    v = -accel_ * tau;
    a = -accel_;
  } else if (tau < turn_ + cruise_) {
    x = hi_ - 0.5 * speed_ * turn_ - speed_ * (tau - turn_);
    v = -speed_;
    a = 0.0;
  } else {
    const double r = std::max(0.0, leg_ - tau);
    x = lo_ + 0.5 * accel_ * r * r;
    v = -accel_ * r;
    a = accel_;
  }
}

void SmoothTriangle::evaluate(double t, double& x, double& v, double& a) const {
  if (leg_ <= 0.0) {
    x = v = a = 0.0;
    return;
  }
  const double tau = std::fmod(std::max(t, 0.0) + phase_, 2.0 * leg_);
  if (tau < leg_) {
    leg(tau, x, v, a);
  } else {
    leg(tau - leg_, x, v, a);  // the way back: mirror image
    x = lo_ + hi_ - x;
    v = -v;
    a = -a;
  }
}

// ------------------------------------------------------------------------------------ dynamic
DynamicTrajectory::DynamicTrajectory(const DynamicScenarioSettings& settings)
    : settings_(settings),
      horizontal_(settings.horizontal_min_offset_m, settings.horizontal_max_offset_m, settings.horizontal_speed_m_s,
                  settings.horizontal_turn_acceleration_m_s2) {}

void DynamicTrajectory::evaluate(double t, PoseReference& out) const {
  t = std::max(t, 0.0);
  double s = 1.0, ds = 0.0, dds = 0.0;
  if (settings_.ramp_s > 0.0) {
    const Quintic e = Quintic::at(t / settings_.ramp_s);
    s = e.s;
    ds = e.ds / settings_.ramp_s;
    dds = e.dds / (settings_.ramp_s * settings_.ramp_s);
  }
  const double amplitude = settings_.vertical_amplitude_m, w = settings_.vertical_angular_frequency_rad_s;
  const double sine = std::sin(w * t), cosine = std::cos(w * t);
  Eigen::Vector3d f(0.0, 0.0, amplitude * sine), fd(0.0, 0.0, amplitude * w * cosine),
      fdd(0.0, 0.0, -amplitude * w * w * sine);
  horizontal_.evaluate(t, f.y(), fd.y(), fdd.y());
  out.pose = centre_;
  out.pose.translation() += s * f;
  out.velocity.head<3>() = ds * f + s * fd;
  out.acceleration.head<3>() = dds * f + 2.0 * ds * fd + s * fdd;
  out.velocity.tail<3>().setZero();
  out.acceleration.tail<3>().setZero();
}

// ------------------------------------------------------------------------------------ pose move
void PoseMove::start(const Eigen::Isometry3d& from, const Eigen::Isometry3d& to, double max_speed,
                     double max_angular_speed, double min_duration) {
  from_ = from;
  to_ = to;
  displacement_ = to.translation() - from.translation();
  rotation_ = rotation_log(to.linear() * from.linear().transpose());
  duration_ = std::max({min_duration, Quintic::kPeakRate * displacement_.norm() / max_speed,
                        Quintic::kPeakRate * rotation_.norm() / max_angular_speed});
}

void PoseMove::evaluate(double t, PoseReference& out) const {
  if (duration_ <= 0.0) {
    out.pose = to_;
    out.velocity.setZero();
    out.acceleration.setZero();
    return;
  }
  const Quintic q = Quintic::at(t / duration_);
  const double rate = q.ds / duration_, rate2 = q.dds / (duration_ * duration_);
  out.pose.translation() = from_.translation() + q.s * displacement_;
  const double angle = rotation_.norm();
  if (angle > 1e-12) {
    out.pose.linear() = Eigen::AngleAxisd(q.s * angle, rotation_ / angle).toRotationMatrix() * from_.linear();
  } else {
    out.pose.linear() = to_.linear();
  }
  out.velocity << rate * displacement_, rate * rotation_;
  out.acceleration << rate2 * displacement_, rate2 * rotation_;
}

// ------------------------------------------------------------------------------------ brakes
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

// ------------------------------------------------------------------------------------ joints
JointMove::JointMove(const Model& model)
    : from_(Eigen::VectorXd::Zero(model.nv())), delta_(Eigen::VectorXd::Zero(model.nv())) {
  for (int i = 0; i < model.nv(); ++i) continuous_.push_back(model.joint(i).type == JointType::kContinuous);
}

void JointMove::difference(const Eigen::VectorXd& from, const Eigen::VectorXd& to, Eigen::VectorXd& out) const {
  for (Eigen::Index i = 0; i < out.size(); ++i) {
    const double d = to[i] - from[i];
    out[i] = continuous_[static_cast<std::size_t>(i)] ? std::remainder(d, 2.0 * std::numbers::pi) : d;
  }
}

void JointMove::start(const Eigen::VectorXd& from, const Eigen::VectorXd& to, double max_speed, double min_duration) {
  from_ = from;
  difference(from, to, delta_);
  duration_ = std::max(min_duration, Quintic::kPeakRate * delta_.cwiseAbs().maxCoeff() / max_speed);
}

void JointMove::evaluate(double t, Eigen::VectorXd& q, Eigen::VectorXd& qd, Eigen::VectorXd& qdd) const {
  if (duration_ <= 0.0) {
    q = from_ + delta_;
    qd.setZero();
    qdd.setZero();
    return;
  }
  const Quintic s = Quintic::at(t / duration_);
  q = from_ + s.s * delta_;
  qd = (s.ds / duration_) * delta_;
  qdd = (s.dds / (duration_ * duration_)) * delta_;
}

}  // namespace phri
