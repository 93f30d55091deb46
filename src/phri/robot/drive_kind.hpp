#pragma once
// phri::DriveKind: whose drives an arm has (robot.yaml `drive:`), hence which low-level loops it
// offers. The plant runs the matching loops (sim/drive_loops.hpp); the controller, the FSM and the
// run configuration refuse any other loop.
//   kinova   Kinova's actuator loops (emulated in simulation): position servo, torque with velocity
//            feedback, torque high-velocity (H(z)), and current, driven by phri's custom loop
//   generic  a plain current/torque drive: a PD position hold, plain torque, current
#include <phri/core/enum_names.hpp>
#include <phri/robot/low_level_mode.hpp>

#include <array>
#include <string_view>

namespace phri {

enum class DriveKind : std::uint8_t { kKinova = 0, kGeneric = 1 };

inline constexpr std::array<std::string_view, 2> kDriveKindNames = {"kinova", "generic"};
constexpr std::string_view to_string(DriveKind kind) { return enum_name(kind, kDriveKindNames, "invalid"); }

constexpr LowLevelModeSet offered_loops(DriveKind kind) {
  switch (kind) {
    case DriveKind::kKinova:
      return {LowLevelMode::kPosition, LowLevelMode::kKinovaTorque, LowLevelMode::kKinovaTorqueHighVelocity,
              LowLevelMode::kCurrent};
    case DriveKind::kGeneric:
      return {LowLevelMode::kPosition, LowLevelMode::kTorque, LowLevelMode::kCurrent};
  }
  return {};
}

}  // namespace phri
