#pragma once
// phri::KinovaDriveEmulator: the Kinova Gen3 actuators' own control loops, emulated inside the
// simulated plant (they run in the actuator firmware on the real arm, below the RobotInterface).
// Every mode ends in a motor current command, saturated at the drive's current limit; the plant
// turns it into joint torque K_T G_r i. The loops see the drive's own (noisy) sensors.
//
// Structures (per joint; tau = K_T G_r i before saturation; see robots/kinova_gen3/README.md,
// "Simulated plant", for the choice of gains):
//
// * kPosition — an industrial joint servo, PID on the joint encoder with velocity feed-forward:
//     tau = Kp (q_d - q) + Kd (qd_ff - qd) + I,   I += Ki (q_d - q) dt, |I| <= I_max
//   qd_ff = (q_d[k] - q_d[k-1]) / T_control, clipped to the joint velocity limit (so streamed
//   trajectories are tracked without lag while a set-point step gives only a bounded kick). No
//   model: gravity and friction are rejected by the stiff gains and the integrator, which gives a
//   small steady-state error that decays, and an underdamped excursion under impacts. Entering the
//   mode is bumpless, also while the arm moves: the velocity feed-forward starts at the measured
//   velocity (the D term starts at zero) and I at the motor torque of the previous cycle minus
//   the P term.
// * kKinovaTorque — "torque control with negative feedback on the joint velocity" (paper, section
//   "Low-level Control": an over-damped, sluggish robot):
//     tau = tau_d + Kt (tau_d - tau_s) - B qd
//   Kt < 1 because the loop closes through an almost algebraic path (tau_s follows tau_m within
//   one tick) with one tick of measurement delay; it divides the friction seen at the sensor by
//   (1 + Kt). B is the firmware's velocity damping.
// * kKinovaTorqueHighVelocity — the paper's H(z) on the torque error, into current, with the
//   set-point fed forward and no friction or rotor-inertia compensation:
//     tau = tau_d + H(z)(tau_d - tau_s)
//   H is clocked at its design rate (1 kHz, the Kortex cycle at which the coefficients were read);
//   its output is held between its ticks. H's DC gain is 1, so it halves static torque errors.
// * kCurrent — i = i_d (saturated only).
// kTorque (a generic drive's plain torque) is not offered: SimRobot refuses it before it reaches
// the drives.
//
// All buffers are sized at construction; begin_cycle() and tick() do not allocate.
#include <phri/core/discrete_transfer_function.hpp>
#include <phri/robot/actuator_table.hpp>
#include <phri/robot/drive_kind.hpp>
#include <phri/robot/robot_command.hpp>
#include <phri/sim/drive_loops.hpp>
#include <phri/config/sim_robot_config.hpp>

#include <Eigen/Core>

#include <vector>

namespace phri {

class KinovaDriveEmulator final : public DriveLoops {
public:
  /// `drives`: the plant's actuators (K_T, G_r, current and velocity limits); `tick_s`: period of
  /// tick() (the physics step); `control_period_s`: period of begin_cycle().
  KinovaDriveEmulator(const ActuatorTable& drives, const SimRobotConfig::Vendor& vendor, double tick_s,
                      double control_period_s);

  int dof() const { return static_cast<int>(kp_.size()); }
  LowLevelModeSet offered() const override { return offered_loops(DriveKind::kKinova); }
  LowLevelMode mode() const override { return mode_; }

  /// Start of a control cycle. `command` is the command in force for this cycle (already
  /// validated); `fresh` says whether it was written since the previous cycle. `q_meas` and
  /// `tau_motor` (the motor torque of the previous tick) initialise a newly entered mode.
  void begin_cycle(const RobotCommand& command, bool fresh, const Eigen::VectorXd& q_meas,
                   const Eigen::VectorXd& tau_motor) override;
  /// One inner-loop tick: measured q, qd, tau_s in; saturated motor current out. `filter_tick`
  /// clocks the high-velocity filter H(z).
  void tick(const Eigen::VectorXd& q_meas, const Eigen::VectorXd& qd_meas, const Eigen::VectorXd& tau_meas,
            bool filter_tick, Eigen::VectorXd& current_out) override;

  /// Which measurements the running mode reads (the plant draws sensor noise only for those).
  bool uses_position() const override { return mode_ == LowLevelMode::kPosition; }
  bool uses_velocity() const override { return mode_ == LowLevelMode::kPosition || mode_ == LowLevelMode::kKinovaTorque; }
  bool uses_torque() const override {
    return mode_ == LowLevelMode::kKinovaTorque || mode_ == LowLevelMode::kKinovaTorqueHighVelocity;
  }
  /// Integrator of the position servo [N.m] (for tests and logs).
  const Eigen::VectorXd& position_integral() const { return integral_; }
  /// Sets the position servo's integrator, e.g. to the gravity torque of the initial pose (the
  /// arm is already holding itself when the simulation starts).
  void set_position_integral(const Eigen::VectorXd& integral);
  /// The position servo's integrator carries the initial pose's holding torque.
  void start_holding(const Eigen::VectorXd& tau) override { set_position_integral(tau); }

private:
  void enter(LowLevelMode mode, const Eigen::VectorXd& q_meas, const Eigen::VectorXd& tau_motor);

  double tick_s_;
  double control_period_s_;
  Eigen::VectorXd torque_per_amp_, current_limit_, velocity_limit_;
  Eigen::VectorXd kp_, kd_, ki_, integral_limit_, kt_, damping_;
  std::vector<DiscreteTransferFunction> filters_;

  LowLevelMode mode_ = LowLevelMode::kPosition;
  bool entered_ = false;
  Eigen::VectorXd q_des_, qd_ff_, tau_des_, current_des_;
  Eigen::VectorXd integral_, filter_out_;
  Eigen::VectorXd last_qd_meas_;  // the velocity the drive last measured (bumpless position entry)
};

}  // namespace phri
