#pragma once
// phri::python::ClosedLoop: the lockstep control loop a script drives, one period per step():
//
//   state = robot.read(); targets = fsm.update(...) or the caller's; controller.step(state, targets,
//   command); robot.write(command) (a refusal is reported to the controller: safe stop); the log row.
//
// run(n) is the same period n times in C++ (the Python binding releases the GIL around it). It is
// the loop of apps/phri's run_session without its pacing, status line and statistics, so that a
// script pays for nothing it does not ask for.
#include <phri/app/fsm.hpp>
#include <phri/app/fill_log_row.hpp>
#include <phri/app/logger.hpp>
#include <phri/control/controller.hpp>
#include <phri/robot/robot_interface.hpp>

#include <cstdint>

namespace phri::python {

class ClosedLoop {
public:
  /// `fsm` and `logger` may be null. Everything is referenced, not owned.
  ClosedLoop(RobotInterface& robot, Controller& controller, Fsm* fsm, Logger* logger);

  /// One period. `targets` (null: none) are this period's requests and references; a loop driven by
  /// an FSM takes the FSM's instead (ArgumentError when both are given).
  CycleStatus step(const ControllerTargets* targets = nullptr);
  /// `cycles` periods (the targets, if any, in the first one); stops early once the FSM has
  /// finished. When `records` is not null, period k's log row goes to record k there, as
  /// write_log_record (log_table.hpp) writes it. Returns the number of periods run.
  long run(long cycles, const ControllerTargets* targets = nullptr, unsigned char* records = nullptr);

  /// The latest state read (null before the first step).
  const RobotState* state() const { return state_; }
  const RobotCommand& command() const { return command_; }
  RobotCommand& command() { return command_; }
  const LogRow& row() const { return row_; }
  std::uint64_t cycles() const { return cycles_; }
  std::uint64_t refused_writes() const { return refused_writes_; }
  CycleStatus status() const { return status_; }
  bool finished() const { return fsm_ != nullptr && fsm_->finished(); }
  bool has_fsm() const { return fsm_ != nullptr; }
  int dof() const { return robot_.dof(); }

private:
  void cycle(const ControllerTargets& targets, bool fill_row);

  RobotInterface& robot_;
  Controller& controller_;
  Fsm* fsm_;
  Logger* logger_;
  RobotCommand command_;
  ControllerTargets no_targets_;
  LogRow row_;
  const RobotState* state_ = nullptr;
  std::uint64_t cycles_ = 0;
  std::uint64_t refused_writes_ = 0;
  CycleStatus status_ = CycleStatus::kOk;
};

}  // namespace phri::python
