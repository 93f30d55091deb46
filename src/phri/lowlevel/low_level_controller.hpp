#pragma once
// phri::LowLevelController: the last stage of the control cycle. It turns the QP's desired
// acceleration qdd_d and torque tau_d into a RobotCommand for the selected loop, and switches
// between loops at any cycle without a jump (paper: position control, Kinova's torque loops and
// the custom torque loop, switched live from the gamepad):
//
//   kPosition                 q_ref += T qd_ref, qd_ref += T qdd_d (the robot's position servo
//                             tracks q_ref); entered at the measured q, qd
//   kKinovaTorque             tau_d to the vendor's torque loop
//   kKinovaTorqueHighVelocity tau_d to the vendor's high-velocity torque loop
//                             (both entered at the torque the motors produce: the set-point
//                             starts at the measured current x K_T G_r, or at tau_s without a
//                             current reading, and blends into tau_d, time constant 50 ms)
//   kCustom                   CustomTorqueController: motor current (reset bumplessly on entry
//                             from the current the drives carry)
//
// A requested switch takes effect at the next update(); every switch is counted and its torque
// step (the change of the robot's measured motor torque across the switch is what a test checks)
// can be logged from switch_count() and last_switch_time().
#include <phri/lowlevel/custom_torque_controller.hpp>
#include <phri/robot/robot_command.hpp>
#include <phri/robot/robot_state.hpp>


namespace phri {

class LowLevelController {
public:
  LowLevelController(const ActuatorTable& actuators, const CustomTorqueSettings& custom, LowLevelMode initial);

  /// Switch to `loop` at the next update (no effect if it is already running).
  void request(LowLevelMode loop) { requested_ = loop; }
  LowLevelMode loop() const { return loop_; }
  LowLevelMode requested() const { return requested_; }
  int switch_count() const { return switches_; }

  /// One control period: the command for the running loop, in `command` (sized for the robot).
  void update(const RobotState& state, const Eigen::VectorXd& tau_desired, const Eigen::VectorXd& qdd_desired,
              RobotCommand& command);

  const CustomTorqueController& custom() const { return custom_; }
  const Eigen::VectorXd& position_reference() const { return q_ref_; }

private:
  CustomTorqueController custom_;
  double period_s_;
  LowLevelMode loop_;
  LowLevelMode requested_;
  bool started_ = false;
  int switches_ = 0;
  Eigen::VectorXd q_ref_, qd_ref_;
  Eigen::VectorXd torque_offset_;  // motor minus desired torque at a torque-loop entry, fading
  Eigen::VectorXd torque_per_amp_; // nominal K_T G_r per joint
  double offset_decay_ = 0.0;
};

}  // namespace phri
