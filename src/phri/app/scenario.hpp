#pragma once
// The paper's scenarios as reference generators for the FSM (app/fsm.hpp), each a pure function
// of time, allocation-free once constructed:
//
//   static  — hold the arm extended: posture = the paper demo's postureTarget
//             [0, 0.58, 3.14, -1.84, 0, 0.85, 1.57] rad, end effector at its forward kinematics.
//             Reached by a minimum-jerk move (PoseMove for the end effector, JointMove for the
//             posture), then held: the FSM stops writing the target, so dual compliance may move it.
//   dynamic — the demo's "Sin" state (paper_parameters.md section 5): around the start pose p0,
//               z(t) = z0 + A sin(w t)                 A 0.10 m, w 3 rad/s
//               y(t) = y0 + triangle(t)                0.1 m/s between y0 - 0.40 and y0 + 0.05,
//                                                      starting at y0 toward -y
//             with two changes: the triangle's corners are rounded by a constant-acceleration
//             turn (SmoothTriangle; a true triangle steps the velocity), and both offsets fade in
//             through a quintic envelope s(t) over `ramp_s` (the motion starts at rest, from the
//             current target pose). Position, velocity and acceleration feed-forward are exact
//             derivatives: p = p0 + s f, v = s' f + s f', a = s'' f + 2 s' f' + s f''.
//             Orientation held.
//
// Also the motions between scenarios: JointMove (start-up to the home posture), PoseBrake and
// JointBrake (bring a moving reference to rest at a bounded deceleration with continuous velocity
// and acceleration, so no scenario change steps the reference or the feed-forward).
#include <phri/trajectory/brakes.hpp>
#include <phri/trajectory/dynamic_trajectory.hpp>
#include <phri/trajectory/joint_move.hpp>
#include <phri/trajectory/pose_move.hpp>
#include <phri/trajectory/quintic.hpp>

#include <string_view>
#include <vector>

namespace phri {

enum class Scenario { kStatic, kDynamic };
constexpr std::string_view to_string(Scenario s) { return s == Scenario::kStatic ? "static" : "dynamic"; }

/// The paper demo's postureTarget (NS and Sin states), joints 1..7 [rad].
inline std::vector<double> paper_posture_target() { return {0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57}; }

struct StaticScenarioSettings {
  std::vector<double> posture_q_rad = paper_posture_target();  ///< held posture (one per joint)
  double move_speed_m_s = 0.1;          ///< peak EE speed of the move into the static pose
  double move_angular_speed_rad_s = 0.5;
  /// Peak joint speed of the posture's move back. Dual compliance leaves the posture where the
  /// hand put the arm, a wrist turned by up to ~2 rad; at the start-up's 0.3 rad/s the way back
  /// took 12 s. Half the Gen3's smallest velocity limit (1.22 rad/s).
  double move_joint_speed_rad_s = 0.6;
  double min_move_duration_s = 1.0;
};

}  // namespace phri
