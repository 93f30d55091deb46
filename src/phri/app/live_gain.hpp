#pragma once
// phri::LiveGain: the controller gains an operator may change while the arm runs (the
// dashboard's sliders), each with the one range it is validated against. A GainRequest travels
// the same way as an Event: posted to the FSM (Fsm::post), which writes it into that period's
// ControllerTargets; the controller clamps it again where it enters (ComplianceController).
//
//   stiffness_scale    end-effector stiffness factor (what stiffness_up / stiffness_down step)
//   ee_gamma           gamma of the end-effector task, [0, 1]; -1 gives it back to the compliance mode
//   posture_gamma      gamma of the posture task, [0, 1]; -1 gives it back to the compliance mode
//   posture_stiffness  posture task stiffness [1/s^2]
#include <phri/control/controller_targets.hpp>
#include <phri/core/enum_names.hpp>

#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <string_view>

namespace phri {

enum class LiveGain : std::uint8_t { kStiffnessScale = 0, kEeGamma = 1, kPostureGamma = 2, kPostureStiffness = 3 };
inline constexpr int kLiveGainCount = 4;
inline constexpr std::array<std::string_view, kLiveGainCount> kLiveGainNames = {
    "stiffness_scale", "ee_gamma", "posture_gamma", "posture_stiffness"};

constexpr std::string_view to_string(LiveGain g) { return enum_name(g, kLiveGainNames); }
constexpr std::optional<LiveGain> live_gain_from_string(std::string_view name) {
  return enum_from_string<LiveGain, kLiveGainCount>(name);
}

/// The validated range of a gain; `mode_value`: the gain also accepts -1, "as the compliance mode says".
struct LiveGainRange {
  double min = 0.0, max = 0.0;
  bool mode_value = false;
};

constexpr LiveGainRange range_of(LiveGain g) {
  switch (g) {
    case LiveGain::kStiffnessScale: return {0.1, 4.0, false};  // ComplianceController::clamped_stiffness_scale
    case LiveGain::kEeGamma:
    case LiveGain::kPostureGamma: return {0.0, 1.0, true};
    case LiveGain::kPostureStiffness: return {0.0, 400.0, false};  // ComplianceController::kMaxPostureStiffness
  }
  return {};
}

/// True when `value` is finite and within the gain's range (or -1 where the mode may decide).
inline bool in_range(LiveGain g, double value) {
  const LiveGainRange r = range_of(g);
  if (!std::isfinite(value)) return false;
  return (value >= r.min && value <= r.max) || (r.mode_value && value == -1.0);
}

struct GainRequest {
  LiveGain gain = LiveGain::kStiffnessScale;
  double value = 1.0;
};

/// Writes the request into this period's targets.
inline void apply(const GainRequest& request, ControllerTargets& targets) {
  switch (request.gain) {
    case LiveGain::kStiffnessScale: targets.stiffness_scale = request.value; break;
    case LiveGain::kEeGamma: targets.ee_gamma = request.value; break;
    case LiveGain::kPostureGamma: targets.posture_gamma = request.value; break;
    case LiveGain::kPostureStiffness: targets.posture_stiffness = request.value; break;
  }
}

}  // namespace phri
