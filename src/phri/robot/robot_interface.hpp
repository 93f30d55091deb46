#pragma once
// phri::RobotInterface: the one boundary between the controller and an arm. The MuJoCo plant
// (phri::SimRobot) and, later, the Kortex hardware client implement it; nothing above it may know
// which one it talks to.
//
// The control loop is read -> compute -> write, once per period():
//
//   phri::RobotCommand cmd(robot.dof());
//   for (;;) {
//     const phri::RobotState& state = robot.read();  // the newest measurements
//     ...compute cmd from state...
//     if (robot.write(cmd) != phri::WriteStatus::kOk) { /* refused: the robot keeps the last command */ }
//     clock.wait_next();                              // pacing, see phri::LoopClock (app/)
//   }
//
// Semantics shared by every implementation:
// * read() returns the state of the robot at the start of the cycle. A hardware client waits for
//   the next feedback frame; the simulator advances its physics by one period on the last accepted
//   command (lockstep) and returns the resulting state. The reference stays valid until the next
//   read().
// * write() validates and stores a command; it takes effect at the next cycle, including a change
//   of LowLevelMode (which resets the mode's internal loop state, bumplessly where possible).
//   A refused command (WriteStatus != kOk) changes nothing but the reported status.
// * Neither call throws or allocates; errors are statuses and flags in RobotState.
#include <phri/robot/robot_command.hpp>
#include <phri/robot/robot_state.hpp>
#include <phri/robot/write_status.hpp>

namespace phri {

class RobotInterface {
public:
  virtual ~RobotInterface() = default;
  RobotInterface() = default;
  RobotInterface(const RobotInterface&) = delete;
  RobotInterface& operator=(const RobotInterface&) = delete;

  /// Number of joints.
  virtual int dof() const = 0;
  /// Control period [s] (1 ms for the Kinova Gen3 low-level servoing).
  virtual double period_s() const = 0;
  /// Waits for (hardware) or produces (simulation) the next state; see above.
  virtual const RobotState& read() = 0;
  /// Validates and stores the command for the next cycle; see above.
  virtual WriteStatus write(const RobotCommand& command) = 0;
};

}  // namespace phri
