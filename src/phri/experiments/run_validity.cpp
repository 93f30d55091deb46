#include <phri/experiments/run_validity.hpp>

#include <phri/control/controller.hpp>
#include <phri/core/format.hpp>

#include <algorithm>

namespace phri {

void RunValidity::check_cycle(CycleStatus status, const Controller& cycle, const RobotCommand& command, bool in_named_loop,
                              LowLevelMode expected) {
  if (status == CycleStatus::kQpFallback) ++qp_fallbacks;
  if (!safe_stop && cycle.supervisor().safe_stop()) {
    const SafetyTransition& t = cycle.supervisor().safe_stop_transition();
    safe_stop = true;
    safe_stop_s = t.time_s;
    safe_stop_reason = std::string(to_string(t.reason)) + (t.joint >= 0 ? ", joint " + std::to_string(t.joint + 1) : "");
  }
  if (in_named_loop && (command.mode != expected || cycle.low_level().loop() != expected)) ++loop_mismatch_cycles;
  loop_ran = to_string(command.mode);
}

std::string RunValidity::invalid_reason() const {
  std::string why;
  auto add = [&why](const std::string& x) { why += (why.empty() ? "" : "; ") + x; };
  if (safe_stop) add("safe stop at " + format_fixed(safe_stop_s, 3) + " s (" + safe_stop_reason + ")");
  if (qp_fallbacks > 0) add(std::to_string(qp_fallbacks) + " QP fallbacks");
  if (loop_mismatch_cycles > 0) add(std::to_string(loop_mismatch_cycles) + " cycles in another loop (" + loop_ran + " at the end)");
  return why;
}

std::string RunValidity::invalid_reason_csv() const {
  std::string why = invalid_reason();
  std::replace(why.begin(), why.end(), ',', ';');
  return why;
}

}  // namespace phri
