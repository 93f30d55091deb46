#pragma once
// phri::LowLevelMode: how the arm's joint drives interpret a RobotCommand, i.e. which of the
// drives' control loops runs (Kinova Kortex low-level servoing, ActuatorConfig ControlMode
// POSITION / TORQUE / TORQUE_HIGH_VELOCITY / CURRENT; a generic drive's position hold, plain torque
// and current), and phri::LowLevelModeSet, the loops a robot's drives offer (robot/drive_kind.hpp).
#include <phri/core/enum_names.hpp>

#include <cstdint>
#include <initializer_list>
#include <optional>
#include <string>
#include <string_view>

namespace phri {

enum class LowLevelMode : std::uint8_t {
  kPosition = 0,                  ///< joint position servo on q_des (the vendor's stiff position loop)
  kKinovaTorque = 1,              ///< vendor torque loop with velocity negative feedback on tau_des
  kKinovaTorqueHighVelocity = 2,  ///< vendor torque loop: tau_des + H(z)(tau_des - tau_sensor)
  kCurrent = 3,                   ///< raw motor current i_des: the drives in current mode, driven by
                                  ///< the paper's custom torque loop (named "custom")
  kTorque = 4,                    ///< joint torque tau_des applied as it is, no vendor loop around it
                                  ///< (a generic drive's plain torque mode; Kinova has none)
};

inline constexpr int kLowLevelModeCount = 5;

constexpr bool is_valid(LowLevelMode mode) { return static_cast<int>(mode) < kLowLevelModeCount; }

/// The names users see (configurations, events, logs, experiment files): kCurrent is the paper's
/// "custom" torque loop.
inline constexpr std::array<std::string_view, kLowLevelModeCount> kLowLevelModeNames = {
    "position", "kinova_torque", "kinova_torque_high_velocity", "custom", "torque"};
constexpr std::string_view to_string(LowLevelMode mode) { return enum_name(mode, kLowLevelModeNames, "invalid"); }

/// Parses the names of to_string; "current" (Kortex's name of the drive mode) is accepted for kCurrent.
constexpr std::optional<LowLevelMode> low_level_mode_from_string(std::string_view name) {
  if (name == "current") return LowLevelMode::kCurrent;
  return enum_from_string<LowLevelMode, kLowLevelModeCount>(name);
}

/// A set of loops, e.g. those a robot's drives offer. No allocation but names().
class LowLevelModeSet {
public:
  constexpr LowLevelModeSet(std::initializer_list<LowLevelMode> modes) {
    for (LowLevelMode m : modes) bits_ |= bit(m);
  }
  /// Every loop (what settings built without a robot bundle accept).
  static constexpr LowLevelModeSet all() {
    return {LowLevelMode::kPosition, LowLevelMode::kKinovaTorque, LowLevelMode::kKinovaTorqueHighVelocity,
            LowLevelMode::kCurrent, LowLevelMode::kTorque};
  }
  constexpr bool contains(LowLevelMode mode) const { return is_valid(mode) && (bits_ & bit(mode)) != 0; }
  constexpr bool operator==(const LowLevelModeSet&) const = default;
  /// "position, torque, custom" (for messages).
  std::string names() const {
    std::string out;
    for (int i = 0; i < kLowLevelModeCount; ++i) {
      const auto mode = static_cast<LowLevelMode>(i);
      if (contains(mode)) out += (out.empty() ? "" : ", ") + std::string(to_string(mode));
    }
    return out;
  }

private:
  static constexpr std::uint8_t bit(LowLevelMode mode) { return static_cast<std::uint8_t>(1u << static_cast<unsigned>(mode)); }
  std::uint8_t bits_ = 0;
};

}  // namespace phri
