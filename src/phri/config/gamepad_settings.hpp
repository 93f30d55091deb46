#pragma once
// The gamepad's settings (app/gamepad.hpp): which event each button of a DS4 produces
// (GamepadMapping::ds4(), the table in app/gamepad.hpp's header comment), the triggers'
// hysteresis, the polling period. Plain data, read from a run YAML's `gamepad:` without SDL2.
#include <phri/config/event.hpp>

#include <array>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>
#include <string_view>

namespace phri {

/// Buttons by their DS4 names.
enum class GamepadButton : std::uint8_t {
  kCross, kCircle, kSquare, kTriangle, kShare, kPs, kOptions, kL3, kR3, kL1, kR1,
  kDpadUp, kDpadDown, kDpadLeft, kDpadRight, kTouchpad,
};
inline constexpr int kGamepadButtonCount = 16;
std::string_view to_string(GamepadButton button);

enum class GamepadAxis : std::uint8_t { kLeftX, kLeftY, kRightX, kRightY, kL2, kR2 };
inline constexpr int kGamepadAxisCount = 6;

/// Which event each button (and the analog triggers) produces.
struct GamepadMapping {
  std::array<std::optional<Event>, kGamepadButtonCount> buttons{};
  std::optional<Event> l2;  ///< when L2 crosses `trigger_press` upward
  std::optional<Event> r2;
  double trigger_press = 0.5;    ///< [0, 1] of the trigger's travel
  double trigger_release = 0.3;  ///< re-armed below this (hysteresis)
  /// The table in this file's header comment.
  static GamepadMapping ds4();
};

struct GamepadSettings {
  bool enabled = true;           ///< false: no source is opened, no events
  GamepadMapping mapping = GamepadMapping::ds4();
  int poll_interval_ms = 5;      ///< background thread's polling period
  std::size_t queue_capacity = 256;
  /// One-line news (SDL unavailable, pad connected/disconnected), from the polling thread.
  /// Default: printed to stderr as "phri: gamepad: ...".
  std::function<void(const std::string&)> notice;
};

}  // namespace phri
