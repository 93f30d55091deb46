#pragma once
// The FSM's settings (app/fsm.hpp), plain data the configuration library fills from a run YAML
// (`fsm:` and `events:`): the start-up move, the paper's scenarios, the brakes, the timeline.
// The scenarios themselves (reference generators) run in app/fsm.cpp.
#include <phri/config/event.hpp>
#include <phri/robot/low_level_mode.hpp>
#include <phri/trajectory/brakes.hpp>
#include <phri/trajectory/dynamic_trajectory.hpp>

#include <cstddef>
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

struct StartupSettings {
  bool enabled = true;  ///< false: the first scenario starts at once, in the torque loop
  std::vector<double> home_q_rad = paper_posture_target();  ///< one per joint
  double max_joint_speed_rad_s = 0.3;  ///< peak joint speed of the move
  double min_duration_s = 1.0;
  double tolerance_rad = 0.05;  ///< posture error norm allowing the switch (paper: 0.05)
  double timeout_s = 5.0;       ///< after the move: switch anyway (startup_timed_out())
};

struct FsmSettings {
  StartupSettings startup;
  StaticScenarioSettings static_scenario;
  DynamicScenarioSettings dynamic_scenario;
  BrakeSettings brake;
  Scenario first_scenario = Scenario::kStatic;    ///< entered after start-up
  LowLevelMode torque_loop = LowLevelMode::kCurrent;  ///< start-up hands over to it; toggle_loop's torque side
  double stiffness_step = 1.25;  ///< factor of stiffness_up / stiffness_down
  double rest_speed_rad_s = 0.01;  ///< |qd| below which the arm is at rest (finished())
  std::vector<TimedEvent> timeline;  ///< scripted events (sorted here by time)
  std::size_t queue_capacity = 64;   ///< posted events waiting for update()
};

}  // namespace phri
