#include <phri/trajectory/joint_move.hpp>

#include <phri/trajectory/quintic.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace phri {

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
