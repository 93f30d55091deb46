#include <phri/experiments/run_validity.hpp>

#include <phri/control/controller.hpp>
#include <phri/core/format.hpp>

#include <algorithm>
#include <cmath>

namespace phri {

void RunValidity::check_cycle(CycleStatus status, const Controller& cycle, const RobotCommand& command, bool in_named_loop,
                              LowLevelMode expected) {
  if (status == CycleStatus::kQpFallback) {
    ++qp_fallbacks;
    const Eigen::VectorXd& hold = cycle.qp().hold_torque();
    const Eigen::VectorXd& limit = cycle.qp().torque_limit();
    for (Eigen::Index i = 0; i < std::min(hold.size(), limit.size()); ++i) {
      const double ratio = limit[i] > 0.0 ? std::abs(hold[i]) / limit[i] : 0.0;
      if (!(ratio > fallback_hold_ratio)) continue;
      fallback_hold_ratio = ratio;
      fallback_hold_joint = static_cast<int>(i);
      fallback_hold_Nm = std::abs(hold[i]);
      fallback_limit_Nm = limit[i];
    }
  }
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
  if (qp_fallbacks > 0) {
    const std::string hold = fallback_hold_joint < 0 ? std::string()
                             : fallback_hold_ratio > 1.0
                                 ? " (holding against the estimated load asked joint " + std::to_string(fallback_hold_joint + 1) +
                                       " for " + format_fixed(fallback_hold_Nm, 1) + " N.m of its " +
                                       format_fixed(fallback_limit_Nm, 1) + ": beyond its actuator)"
                                 : " (every joint's hold within its torque limit: at most " +
                                       format_fixed(100.0 * fallback_hold_ratio, 0) + " %, joint " +
                                       std::to_string(fallback_hold_joint + 1) + ")";
    add(std::to_string(qp_fallbacks) + " QP fallbacks" + hold);
  }
  if (loop_mismatch_cycles > 0) add(std::to_string(loop_mismatch_cycles) + " cycles in another loop (" + loop_ran + " at the end)");
  return why;
}

std::string RunValidity::invalid_reason_csv() const {
  std::string why = invalid_reason();
  std::replace(why.begin(), why.end(), ',', ';');
  return why;
}

}  // namespace phri
