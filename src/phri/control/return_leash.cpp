#include <phri/control/return_leash.hpp>

#include <phri/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace phri {

ReturnLeash::ReturnLeash(const Model& model, int frame_id, const ReturnLeashSettings& settings)
    : settings_(settings),
      frame_id_(frame_id),
      scratch_(model),
      offset_(Eigen::VectorXd::Zero(model.nv())),
      previous_offset_(Eigen::VectorXd::Zero(model.nv())),
      leash_q_(Eigen::VectorXd::Zero(model.nv())) {
  auto positive = [](double v) { return v > 0.0 && std::isfinite(v); };
  if (!positive(settings.length_rad)) throw ConfigError("ReturnLeashSettings", "length_rad", "must be > 0 and finite");
  if (!positive(settings.return_speed_rad_s)) {
    throw ConfigError("ReturnLeashSettings", "return_speed_rad_s", "must be > 0 and finite");
  }
  if (!positive(settings.walk_posture_weight)) {
    throw ConfigError("ReturnLeashSettings", "walk_posture_weight", "must be > 0 and finite");
  }
  if (!positive(settings.weight_blend_s)) {
    throw ConfigError("ReturnLeashSettings", "weight_blend_s", "must be > 0 and finite");
  }
  for (const Joint& j : model.joints()) continuous_.push_back(j.type == JointType::kContinuous);
}

void ReturnLeash::reset() {
  offset_.setZero();
  out_ = false;
  walk_blend_ = 0.0;
  pose_offset_.setIdentity();
}

double ReturnLeash::posture_weight(double usual) const {
  return usual * std::pow(settings_.walk_posture_weight / usual, walk_blend_);
}

void ReturnLeash::update(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd,
                         const Eigen::VectorXd& q_target, const Eigen::VectorXd& qd_target, bool dragging, double dt) {
  previous_offset_ = offset_;
  // Walk back along the straight line: every joint's offset shrinks by the same fraction, the
  // largest by return_speed * dt; exactly zero on the last step.
  const double largest = offset_.cwiseAbs().maxCoeff();
  if (largest > 0.0) offset_ *= std::max(0.0, 1.0 - settings_.return_speed_rad_s * dt / largest);
  if (dragging) drag(q, qd, q_target, qd_target, dt);
  out_ = offset_.cwiseAbs().maxCoeff() > 0.0;
  const double step = dt / settings_.weight_blend_s;
  walk_blend_ = out_ && !dragging ? std::min(1.0, walk_blend_ + step) : std::max(0.0, walk_blend_ - step);
  if (out_) {
    compute_pose_offset(model, q_target);
  } else {
    pose_offset_.setIdentity();
  }
}

// A joint further than `length` from q_l and moving away from it pulls q_l along; q_l then moves
// with the joint. A joint that lags (friction, a limit) does not hold q_l back: the walk goes on
// and the growing error pulls the joint free. A continuous joint's distance and offset are
// wrapped to (-pi, pi]: q_l stays on the short side, and a turn of 2 pi changes nothing the tasks
// see (the posture wraps its error; the kinematics are periodic).
void ReturnLeash::drag(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& q_target,
                       const Eigen::VectorXd& qd_target, double dt) {
  for (Eigen::Index i = 0; i < offset_.size(); ++i) {
    const bool continuous = continuous_[static_cast<std::size_t>(i)];
    double distance = q[i] - q_target[i] - offset_[i];  // from q_l to the joint
    if (continuous) distance = std::remainder(distance, 2.0 * std::numbers::pi);
    const double away = qd[i] - qd_target[i];
    if (std::abs(distance) > settings_.length_rad && away * distance > 0.0) {
      // Moves with the joint from where it was (no step, whatever the distance when dragging starts).
      offset_[i] = previous_offset_[i] + away * dt;
    }
    if (continuous) offset_[i] = std::remainder(offset_[i], 2.0 * std::numbers::pi);
  }
}

void ReturnLeash::compute_pose_offset(const Model& model, const Eigen::VectorXd& q_target) {
  const auto f = static_cast<std::size_t>(frame_id_);
  forward_kinematics(model, scratch_, q_target);
  update_frame_placements(model, scratch_);
  const Eigen::Isometry3d at_target = scratch_.frame_placements[f];
  leash_q_ = q_target + offset_;
  forward_kinematics(model, scratch_, leash_q_);
  update_frame_placements(model, scratch_);
  pose_offset_ = scratch_.frame_placements[f] * at_target.inverse();
}

}  // namespace phri
