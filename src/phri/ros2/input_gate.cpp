#include <phri/ros2/input_gate.hpp>

#include <cmath>

namespace phri {

double arm_reach_m(const Model& model, int ee_frame) {
  double reach = 0.0;
  for (const Joint& j : model.joints()) reach += j.placement.translation().norm();
  return reach + model.frame(ee_frame).placement.translation().norm();
}

std::uint64_t InputGate::refused_total() const {
  std::uint64_t n = 0;
  for (std::size_t i = 1; i < refused_.size(); ++i) n += refused_[i];
  return n;
}

InputRefusal InputGate::refuse(InputRefusal r) {
  count(r);
  last_refusal_ = r;
  return r;
}

// At most max_rate_hz accepted: an input closer than 1 / max_rate_hz to the last accepted one of
// its topic is refused (a flood costs the bridge a check per message, the loop nothing).
bool InputGate::rate_allows(double& last_s, double now_s) const {
  if (now_s - last_s < 1.0 / limits_.max_rate_hz) return false;
  last_s = now_s;
  return true;
}

InputRefusal InputGate::target(const PoseInput& pose, double now_s, LiveTarget& out) {
  for (double v : pose.position) {
    if (!std::isfinite(v)) return refuse(InputRefusal::kNotFinite);
  }
  for (double v : pose.orientation_xyzw) {
    if (!std::isfinite(v)) return refuse(InputRefusal::kNotFinite);
  }
  const bool in_world = pose.frame_id.empty() || pose.frame_id == limits_.world_frame;
  if (!in_world && pose.frame_id != limits_.base_frame) return refuse(InputRefusal::kUnknownFrame);
  const auto& o = pose.orientation_xyzw;
  Eigen::Quaterniond q(o[3], o[0], o[1], o[2]);
  if (!(std::abs(q.norm() - 1.0) <= 0.01)) return refuse(InputRefusal::kNotUnitQuaternion);
  q.normalize();
  Eigen::Isometry3d target = Eigen::Isometry3d::Identity();
  target.linear() = q.toRotationMatrix();
  target.translation() = Eigen::Vector3d(pose.position[0], pose.position[1], pose.position[2]);
  if (!in_world) target = limits_.base_in_world * target;
  if ((target.translation() - limits_.base_in_world.translation()).norm() > limits_.max_reach_m) {
    return refuse(InputRefusal::kOutOfReach);
  }
  if (!rate_allows(last_target_s_, now_s)) return refuse(InputRefusal::kTooFast);
  out.position = target.translation();
  out.orientation = Eigen::Quaterniond(target.linear()).normalized();
  ++accepted_;
  return InputRefusal::kNone;
}

InputRefusal InputGate::event(std::string_view name, double now_s, Event& out) {
  const std::optional<Event> e = event_from_string(name);
  if (!e) return refuse(InputRefusal::kUnknownEvent);
  if (!rate_allows(last_event_s_, now_s)) return refuse(InputRefusal::kTooFast);
  out = *e;
  ++accepted_;
  return InputRefusal::kNone;
}

InputRefusal InputGate::wrench(const std::array<double, 6>& w) {
  for (double v : w) {
    if (!std::isfinite(v)) return refuse(InputRefusal::kNotFinite);
  }
  const double force = std::hypot(w[0], w[1], w[2]), moment = std::hypot(w[3], w[4], w[5]);
  if (!(force <= limits_.max_force_N) || !(moment <= limits_.max_moment_Nm)) return refuse(InputRefusal::kAbsurdWrench);
  ++accepted_;
  return InputRefusal::kNone;
}

}  // namespace phri
