#include "closed_loop.hpp"

#include "log_table.hpp"

#include <phri/core/error.hpp>

namespace phri::python {

ClosedLoop::ClosedLoop(RobotInterface& robot, Controller& controller, Fsm* fsm, Logger* logger)
    : robot_(robot),
      controller_(controller),
      fsm_(fsm),
      logger_(logger),
      command_(robot.dof()),
      no_targets_(controller.model().nv()) {
  check_size("ClosedLoop", "robot joints", robot.dof(), controller.model().nv());
}

void ClosedLoop::cycle(const ControllerTargets& targets, bool fill_row) {
  const RobotState& state = robot_.read();
  state_ = &state;
  const ControllerTargets& applied = fsm_ != nullptr ? fsm_->update(state.time_s, state, controller_) : targets;
  status_ = controller_.step(state, applied, command_);
  // A refused command leaves the robot on its previous one: a fault the controller must act on.
  if (robot_.write(command_) != WriteStatus::kOk) {
    ++refused_writes_;
    controller_.report_fault(SafetyFault::kWriteRefused, state.time_s);
  }
  ++cycles_;
  if (fill_row || logger_ != nullptr) {
    if (fsm_ != nullptr) {
      fill_log_row(row_, state, controller_, *fsm_);
    } else {
      fill_log_row(row_, state, controller_);
    }
    if (logger_ != nullptr) logger_->push(row_);
  }
}

CycleStatus ClosedLoop::step(const ControllerTargets* targets) {
  if (targets != nullptr && fsm_ != nullptr) {
    throw ArgumentError("ClosedLoop.step: targets given to a loop driven by an FSM (post events to the FSM instead)");
  }
  cycle(targets != nullptr ? *targets : no_targets_, false);
  return status_;
}

long ClosedLoop::run(long cycles, const ControllerTargets* targets, unsigned char* records) {
  if (targets != nullptr && fsm_ != nullptr) {
    throw ArgumentError("ClosedLoop.run: targets given to a loop driven by an FSM (post events to the FSM instead)");
  }
  const int dof = robot_.dof();
  const std::size_t record_size = records != nullptr ? 8 * log_columns(dof).size() : 0;
  long k = 0;
  for (; k < cycles && !finished(); ++k) {
    cycle(k == 0 && targets != nullptr ? *targets : no_targets_, records != nullptr);
    if (records != nullptr) write_log_record(row_, dof, records + record_size * static_cast<std::size_t>(k));
  }
  return k;
}

}  // namespace phri::python
