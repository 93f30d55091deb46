#pragma once
// phri::RobotState: what the arm reports once per control cycle, as its sensors measure it (noisy,
// quantised, biased; the simulator's noise-free truth is elsewhere, SimRobot::truth()).
// Sign conventions: joint torques act on the link in the direction of positive q (the same
// convention as the torque commands; the Kortex sign flip of the measured torque is the hardware
// client's business). The wrench is the load the tool exerts on the flange side of the F/T
// sensor, in the sensor frame, about its origin: a tool hanging at rest reads its weight,
// m * g_sensor, and a push on the tool adds the pushing force.
#include <phri/robot/low_level_mode.hpp>
#include <phri/robot/write_status.hpp>

#include <Eigen/Core>

#include <cstdint>

namespace phri {

/// Validity and freshness of one sensor signal. `sequence` increases by one per new sample, so a
/// reader detects a stale signal (same sequence as last cycle) and counts missed samples.
struct SignalStatus {
  bool valid = false;          ///< false: never sampled, or the sample was not finite
  std::uint32_t sequence = 0;  ///< number of samples so far
  double stamp_s = 0.0;        ///< robot time of the sample [s]
};

struct RobotState {
  RobotState() = default;
  explicit RobotState(int dof)
      : q_rad(Eigen::VectorXd::Zero(dof)),
        qd_rad_s(Eigen::VectorXd::Zero(dof)),
        tau_sensor_Nm(Eigen::VectorXd::Zero(dof)),
        current_A(Eigen::VectorXd::Zero(dof)) {}

  double time_s = 0.0;     ///< robot time at the end of the cycle [s]
  std::uint64_t cycle = 0; ///< number of completed control cycles
  LowLevelMode mode = LowLevelMode::kPosition;  ///< mode that ran during the last cycle

  Eigen::VectorXd q_rad;          ///< joint positions (encoder, quantised) [rad]
  Eigen::VectorXd qd_rad_s;       ///< joint velocities as reported by the drives [rad/s]
  Eigen::VectorXd tau_sensor_Nm;  ///< joint torque sensors: torque transmitted to the link [N.m]
  Eigen::VectorXd current_A;      ///< measured motor currents [A]
  Eigen::Matrix<double, 6, 1> wrench_sensor = Eigen::Matrix<double, 6, 1>::Zero();  ///< (f [N]; m [N.m])

  SignalStatus joints;   ///< q and qd
  SignalStatus torque;   ///< tau_sensor
  SignalStatus current;  ///< current
  SignalStatus wrench;   ///< F/T sensor (may run slower than the control cycle)

  bool fault = false;  ///< the robot stopped obeying commands (simulator: the physics diverged)
  /// The robot still obeys and its samples are good, but asks for a safe stop (a degraded link):
  /// the controller brakes on good data, then hands over to the robot's position hold.
  bool stop_requested = false;
  WriteStatus last_write_status = WriteStatus::kOk;  ///< answer to the latest write()
  std::uint64_t rejected_writes = 0;                 ///< refused commands so far
};

}  // namespace phri
