#include <phri/trajectory/pose_move.hpp>

#include <phri/control/end_effector_task.hpp>
#include <phri/trajectory/quintic.hpp>

#include <algorithm>
#include <cmath>

namespace phri {

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

}  // namespace phri
