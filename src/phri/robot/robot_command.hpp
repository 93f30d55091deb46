#pragma once
// phri::RobotCommand: one low-level command for every joint of the arm. Only the set-point vector
// of the selected mode is read (and must have one entry per joint); the others are ignored.
//
//   phri::RobotCommand cmd(robot.dof());       // sized once, before the loop
//   cmd.mode = phri::LowLevelMode::kCurrent;
//   cmd.current_A = ...;                        // then robot.write(cmd) every cycle
#include <phri/robot/low_level_mode.hpp>

#include <Eigen/Core>

namespace phri {

struct RobotCommand {
  RobotCommand() = default;
  explicit RobotCommand(int dof)
      : q_rad(Eigen::VectorXd::Zero(dof)), tau_Nm(Eigen::VectorXd::Zero(dof)), current_A(Eigen::VectorXd::Zero(dof)) {}

  LowLevelMode mode = LowLevelMode::kPosition;
  Eigen::VectorXd q_rad;      ///< kPosition: joint position set-point [rad] (continuous joints unwrapped)
  Eigen::VectorXd tau_Nm;     ///< kKinovaTorque, kKinovaTorqueHighVelocity, kTorque: joint torque set-point [N.m]
  Eigen::VectorXd current_A;  ///< kCurrent: motor current set-point [A] (motor side; tau = K_T G_r i)

  /// The mode of `from` and the set-point that mode uses; the other set-points keep their values
  /// (sizes equal: no allocation).
  void copy_setpoint(const RobotCommand& from) {
    mode = from.mode;
    switch (from.mode) {
      case LowLevelMode::kPosition: q_rad = from.q_rad; break;
      case LowLevelMode::kKinovaTorque:
      case LowLevelMode::kKinovaTorqueHighVelocity:
      case LowLevelMode::kTorque: tau_Nm = from.tau_Nm; break;
      case LowLevelMode::kCurrent: current_A = from.current_A; break;
    }
  }
};

}  // namespace phri
