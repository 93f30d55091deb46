#pragma once
// Fills a LogRow (config/log_row.hpp) from one cycle: the state, the controller, the FSM.
#include <phri/config/log_row.hpp>

namespace phri {

class Controller;
class Fsm;
struct RobotState;

/// Fills every field the robot state and the control cycle give (after cycle.step()): all but
/// fsm_state, event and cycle_time_s. No allocation.
void fill_log_row(LogRow& row, const RobotState& state, const Controller& cycle);
/// ... and fsm_state and event from the FSM (event: the last one its last update handled).
void fill_log_row(LogRow& row, const RobotState& state, const Controller& cycle, const Fsm& fsm);

}  // namespace phri
