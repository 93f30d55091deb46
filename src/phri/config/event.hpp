#pragma once
// phri::Event: what an operator (DS4 gamepad, app/gamepad.hpp) or a scripted timeline (the
// `events:` list of a run config, config/config.hpp) asks of the FSM (app/fsm.hpp). One flat
// enumeration: an event is a plain value, copied through lock-free queues and logged as its
// integer code (the enumerator's value, stable: append new events at the end).
//
// Names (timeline YAML, log legend) and meaning:
//   stiff_compliance, null_space_compliance, full_body_compliance, dual_compliance
//                          compliance mode (ControllerTargets::compliance_mode)
//   position_loop, kinova_torque_loop, kinova_torque_high_velocity_loop, custom_loop
//                          low-level loop (ControllerTargets::low_level_mode)
//   toggle_loop            position <-> the last torque loop used (custom at first)
//   static_scenario, dynamic_scenario
//                          start a scenario (the FSM brakes the current motion first)
//   toggle_scenario        static <-> dynamic
//   stop_scenario          brake to rest and hold, wait for the next scenario
//   stiffness_up, stiffness_down
//                          scale the end-effector stiffness by the FSM's stiffness step
//   stop                   brake to rest and hold; the session is over (Fsm::finished())
#include <phri/control/compliance_mode.hpp>
#include <phri/core/enum_names.hpp>
#include <phri/lowlevel/low_level_controller.hpp>

#include <array>
#include <cstdint>
#include <optional>
#include <string_view>

namespace phri {

enum class Event : std::uint8_t {
  kStiffCompliance = 0,
  kNullSpaceCompliance = 1,
  kFullBodyCompliance = 2,
  kDualCompliance = 3,
  kPositionLoop = 4,
  kKinovaTorqueLoop = 5,
  kKinovaTorqueHighVelocityLoop = 6,
  kCustomLoop = 7,
  kToggleLoop = 8,
  kStaticScenario = 9,
  kDynamicScenario = 10,
  kToggleScenario = 11,
  kStopScenario = 12,
  kStiffnessUp = 13,
  kStiffnessDown = 14,
  kStop = 15,
};

inline constexpr int kEventCount = 16;

inline constexpr std::array<std::string_view, kEventCount> kEventNames = {
    "stiff_compliance", "null_space_compliance", "full_body_compliance", "dual_compliance",
    "position_loop",    "kinova_torque_loop",    "kinova_torque_high_velocity_loop", "custom_loop",
    "toggle_loop",      "static_scenario",       "dynamic_scenario",     "toggle_scenario",
    "stop_scenario",    "stiffness_up",          "stiffness_down",       "stop"};

constexpr int code(Event e) { return static_cast<int>(e); }

constexpr std::string_view to_string(Event e) { return enum_name(e, kEventNames); }

constexpr std::optional<Event> event_from_string(std::string_view name) { return enum_from_string<Event, kEventCount>(name); }

/// The compliance mode an event selects, if it is a compliance event.
constexpr std::optional<ComplianceMode> compliance_of(Event e) {
  switch (e) {
    case Event::kStiffCompliance: return ComplianceMode::kStiff;
    case Event::kNullSpaceCompliance: return ComplianceMode::kNullSpace;
    case Event::kFullBodyCompliance: return ComplianceMode::kFullBody;
    case Event::kDualCompliance: return ComplianceMode::kDual;
    default: return std::nullopt;
  }
}

/// The low-level loop an event selects, if it selects one (toggle_loop does not: the FSM decides).
constexpr std::optional<LowLevelMode> loop_of(Event e) {
  switch (e) {
    case Event::kPositionLoop: return LowLevelMode::kPosition;
    case Event::kKinovaTorqueLoop: return LowLevelMode::kKinovaTorque;
    case Event::kKinovaTorqueHighVelocityLoop: return LowLevelMode::kKinovaTorqueHighVelocity;
    case Event::kCustomLoop: return LowLevelMode::kCurrent;
    default: return std::nullopt;
  }
}

/// An event of a scripted timeline: `at` seconds of robot time (RobotState::time_s).
struct TimedEvent {
  double time_s = 0.0;
  Event event = Event::kStop;
};

}  // namespace phri
