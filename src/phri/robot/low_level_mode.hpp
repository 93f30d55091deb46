#pragma once
// phri::LowLevelMode: how the arm's joint drives interpret a RobotCommand, i.e. which of the
// vendor's actuator control loops runs (Kinova Kortex low-level servoing, ActuatorConfig
// ControlMode POSITION / TORQUE / TORQUE_HIGH_VELOCITY / CURRENT).
#include <phri/core/enum_names.hpp>

#include <cstdint>
#include <optional>
#include <string_view>

namespace phri {

enum class LowLevelMode : std::uint8_t {
  kPosition = 0,                  ///< joint position servo on q_des (the vendor's stiff position loop)
  kKinovaTorque = 1,              ///< vendor torque loop with velocity negative feedback on tau_des
  kKinovaTorqueHighVelocity = 2,  ///< vendor torque loop: tau_des + H(z)(tau_des - tau_sensor)
  kCurrent = 3,                   ///< raw motor current i_des: the drives in current mode, driven by
                                  ///< the paper's custom torque loop (named "custom")
};

inline constexpr int kLowLevelModeCount = 4;

constexpr bool is_valid(LowLevelMode mode) { return static_cast<int>(mode) < kLowLevelModeCount; }

/// The names users see (configurations, events, logs, experiment files): kCurrent is the paper's
/// "custom" torque loop.
inline constexpr std::array<std::string_view, kLowLevelModeCount> kLowLevelModeNames = {
    "position", "kinova_torque", "kinova_torque_high_velocity", "custom"};
constexpr std::string_view to_string(LowLevelMode mode) { return enum_name(mode, kLowLevelModeNames, "invalid"); }

/// Parses the names of to_string; "current" (Kortex's name of the drive mode) is accepted for kCurrent.
constexpr std::optional<LowLevelMode> low_level_mode_from_string(std::string_view name) {
  if (name == "current") return LowLevelMode::kCurrent;
  return enum_from_string<LowLevelMode, kLowLevelModeCount>(name);
}

}  // namespace phri
