#include <phri/ros2/status_text.hpp>

#include <phri/app/fsm.hpp>
#include <phri/control/compliance_mode.hpp>
#include <phri/robot/low_level_mode.hpp>
#include <phri/safety/state_supervisor.hpp>
#include <phri/safety/wrench_supervisor.hpp>

#include <cstdio>
#include <string_view>

namespace phri {
namespace {

int width(std::string_view s) { return static_cast<int>(s.size()); }

}  // namespace

std::size_t status_text(const LiveSnapshot& s, const BridgeCounters& c, char* buffer, std::size_t size) {
  const LogRow& r = s.row;
  const std::string_view mode = to_string(static_cast<ComplianceMode>(r.compliance_mode));
  const std::string_view loop = to_string(static_cast<LowLevelMode>(r.low_level_loop));
  const std::string_view fsm = r.fsm_state < 0 ? std::string_view("none") : to_string(static_cast<FsmState>(r.fsm_state));
  const std::string_view safety = to_string(static_cast<SupervisorState>(r.safety_state));
  const std::string_view fault =
      r.safety_fault == 0 ? std::string_view("none") : to_string(static_cast<SafetyFault>(r.safety_fault));
  const std::string_view ft = to_string(static_cast<WrenchStatus>(r.ft_status));
  const int n = std::snprintf(
      buffer, size,
      "t=%.3f cycle=%lld mode=%.*s touched=%d loop=%.*s fsm=%.*s safety=%.*s fault=%.*s ft=%.*s cycle_us=%.1f "
      "overruns=%llu stiffness=%.3f err_mm=%.2f inputs_accepted=%llu inputs_refused=%llu last_refusal=%.*s "
      "snapshots_dropped=%llu",
      r.time_s, static_cast<long long>(r.cycle), width(mode), mode.data(), r.touched, width(loop), loop.data(), width(fsm),
      fsm.data(), width(safety), safety.data(), width(fault), fault.data(), width(ft), ft.data(), 1e6 * r.cycle_time_s,
      static_cast<unsigned long long>(s.overruns), r.stiffness_scale, 1e3 * r.error_position_m,
      static_cast<unsigned long long>(c.inputs_accepted), static_cast<unsigned long long>(c.inputs_refused),
      width(c.last_refusal), c.last_refusal.data(), static_cast<unsigned long long>(c.snapshots_dropped));
  if (n < 0) return 0;
  return static_cast<std::size_t>(n) < size ? static_cast<std::size_t>(n) : size - 1;
}

}  // namespace phri
