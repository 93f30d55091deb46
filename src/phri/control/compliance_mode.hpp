#pragma once
// The paper's compliance modes (section "Control Modes"): which tasks let an external push
// through (gamma = 1) and which negate it (gamma = 0).
#include <phri/core/enum_names.hpp>

#include <optional>
#include <string_view>

namespace phri {

enum class ComplianceMode {
  kStiff,      ///< gamma_EE = 0, gamma_posture = 0: every push is negated
  kNullSpace,  ///< gamma_EE = 0, gamma_posture = 1: the posture yields, the end effector holds
  kFullBody,   ///< gamma_EE = 1, gamma_posture = 1: impedance-like everywhere
  kDual,       ///< null-space compliance; the end effector becomes free while it is touched
};
inline constexpr int kComplianceModeCount = 4;

inline constexpr std::array<std::string_view, kComplianceModeCount> kComplianceModeNames = {"stiff", "null_space",
                                                                                          "full_body", "dual"};
constexpr std::string_view to_string(ComplianceMode mode) { return enum_name(mode, kComplianceModeNames); }

constexpr std::optional<ComplianceMode> compliance_mode_from_string(std::string_view name) {
  return enum_from_string<ComplianceMode, kComplianceModeCount>(name);
}

}  // namespace phri
