#pragma once
// phri::InputGate: every check a ROS 2 input passes before it reaches the run loop, as the
// dashboard's request checks (dashboard/dashboard_request.hpp) do for the page. It runs on the
// bridge's thread; what it accepts becomes a LiveCommand (an event, or an end-effector target the
// FSM takes while it holds a pose, then approached by the controller's reference governor).
//
//   /phri/target_pose  geometry_msgs/PoseStamped: frame_id "world", "" (world) or the base link;
//                      finite; a unit quaternion (|q| within 1 +- 0.01, normalised); the position
//                      within max_reach_m of the base; at most max_rate_hz accepted.
//   /phri/event        std_msgs/String: one of config/event.hpp's names (the gamepad's and the
//                      dashboard's), at most max_rate_hz accepted.
//   /phri/ft_in        geometry_msgs/WrenchStamped: finite, |F| <= 1e4 N, |M| <= 1e3 N.m (no F/T
//                      sensor reads more: garbage); no rate limit (a sensor streams at its rate).
//                      The rest (range, staleness, frozen values, consistency with the observer)
//                      is the controller's WrenchSupervisor's, as for any sensor.
// Refused input changes nothing and is counted by reason (the bridge's /phri/status reports them).
#include <phri/app/live_channel.hpp>
#include <phri/config/event.hpp>
#include <phri/model/model.hpp>

#include <Eigen/Geometry>

#include <array>
#include <cstdint>
#include <string>
#include <string_view>

namespace phri {

enum class InputRefusal : std::uint8_t {
  kNone = 0,
  kNotFinite,          ///< NaN or infinite number
  kNotUnitQuaternion,  ///< |q| not within 1 +- 0.01
  kOutOfReach,         ///< farther than max_reach_m from the base
  kUnknownFrame,       ///< frame_id neither world nor the base link
  kTooFast,            ///< more than max_rate_hz on this topic
  kUnknownEvent,       ///< not an event name
  kQueueFull,          ///< the loop has not taken the previous commands
  kAbsurdWrench,       ///< /phri/ft_in beyond any F/T sensor (|F| > 1e4 N or |M| > 1e3 N.m)
  kLast = kAbsurdWrench,
};
inline constexpr int kInputRefusalCount = static_cast<int>(InputRefusal::kLast) + 1;

constexpr std::string_view to_string(InputRefusal r) {
  constexpr std::array<std::string_view, kInputRefusalCount> names = {
      "none", "not_finite", "not_unit_quaternion", "out_of_reach", "unknown_frame", "too_fast", "unknown_event", "queue_full",
      "absurd_wrench"};
  const auto i = static_cast<std::size_t>(r);
  return i < names.size() ? names[i] : "unknown";
}

struct InputLimits {
  std::string world_frame = "world";
  std::string base_frame;                                            ///< the model's base link
  Eigen::Isometry3d base_in_world = Eigen::Isometry3d::Identity();  ///< Model::base_placement()
  double max_reach_m = 1.0;
  double max_rate_hz = 50.0;
  double max_force_N = 1e4, max_moment_Nm = 1e3;  ///< /phri/ft_in: beyond is garbage
};

/// A PoseStamped as received (quaternion x, y, z, w as in ROS).
struct PoseInput {
  std::string_view frame_id;
  std::array<double, 3> position{};
  std::array<double, 4> orientation_xyzw{0.0, 0.0, 0.0, 1.0};
};

/// The arm's reach from its base, bounded from above: the lengths of the joint offsets along the
/// chain plus the end-effector frame's offset on its link (no configuration puts the end effector
/// farther from the base than their sum).
double arm_reach_m(const Model& model, int ee_frame);

class InputGate {
public:
  explicit InputGate(const InputLimits& limits) : limits_(limits) {}

  /// `now_s`: the bridge's monotonic clock [s]. kNone: `out` holds the target in world axes.
  InputRefusal target(const PoseInput& pose, double now_s, LiveTarget& out);
  InputRefusal event(std::string_view name, double now_s, Event& out);
  /// Fx, Fy, Fz [N], Mx, My, Mz [N.m].
  InputRefusal wrench(const std::array<double, 6>& w);
  /// Counts a refusal found outside the gate (kQueueFull).
  void count(InputRefusal r) { ++refused_[static_cast<std::size_t>(r)]; }

  std::uint64_t accepted() const { return accepted_; }
  std::uint64_t refused(InputRefusal r) const { return refused_[static_cast<std::size_t>(r)]; }
  std::uint64_t refused_total() const;
  InputRefusal last_refusal() const { return last_refusal_; }
  const InputLimits& limits() const { return limits_; }

private:
  InputRefusal refuse(InputRefusal r);
  bool rate_allows(double& last_s, double now_s) const;

  InputLimits limits_;
  double last_target_s_ = -1e300, last_event_s_ = -1e300;
  std::uint64_t accepted_ = 0;
  std::array<std::uint64_t, kInputRefusalCount> refused_{};
  InputRefusal last_refusal_ = InputRefusal::kNone;
};

}  // namespace phri
