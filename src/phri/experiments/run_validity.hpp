#pragma once
// Whether a simulated run measured what its row names (issue 39: "a run in which the supervisor
// stopped, a fallback happened, or the loop that ran is not the loop the row names, is marked
// invalid and excluded, loudly"). One home for the bookkeeping the drop test and the torque and
// dynamic tracking experiments share: fed once per control cycle, it records QP fallbacks, the
// supervisor's first safe stop and the cycles where the command's or the low level's loop was not
// the loop the row names.
#include <phri/robot/low_level_mode.hpp>

#include <string>

namespace phri {

class Controller;
enum class CycleStatus;
struct RobotCommand;

struct RunValidity {
  long qp_fallbacks = 0;
  bool safe_stop = false;
  double safe_stop_s = 0.0;
  std::string safe_stop_reason;   ///< the supervisor's fault, with its joint
  long loop_mismatch_cycles = 0;  ///< cycles the command's loop was not the loop the row names
  /// Over the QP fallbacks, the largest |h - tau_ext|_i / torque limit_i (WholeBodyQp::hold_torque):
  /// above 1, the estimated load asked a joint for more than its actuator gives, so the QP's bounds
  /// could not all hold; with its joint (0-based) and torques.
  double fallback_hold_ratio = 0.0;
  int fallback_hold_joint = -1;
  double fallback_hold_Nm = 0.0, fallback_limit_Nm = 0.0;
  std::string loop_ran;           ///< the loop commanded at the last cycle checked

  /// One cycle's bookkeeping; `expected` is checked only when `in_named_loop` (after the switch).
  void check_cycle(CycleStatus status, const Controller& cycle, const RobotCommand& command, bool in_named_loop,
                   LowLevelMode expected);
  /// Empty: valid; else why not (safe stop, QP fallback, wrong loop), for tables and CSVs.
  std::string invalid_reason() const;
  bool valid() const { return invalid_reason().empty(); }
  /// invalid_reason() as one CSV field (its commas as semicolons).
  std::string invalid_reason_csv() const;
};

}  // namespace phri
