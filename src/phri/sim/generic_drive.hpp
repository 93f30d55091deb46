#pragma once
// phri::GenericDrive: the drives of an arm that is not a Kinova (robot.yaml `drive: generic`): a
// plain current/torque drive with the friction and limits of actuators.yaml (the plant applies
// the friction), and no vendor torque loop. Per joint:
//
// * kPosition — the drive's position hold (the safe stop's and the start-up's), a PD servo about
//   the torque the motor carried when the mode was entered, with the drive's own gains (robot.yaml
//   or the plant YAML: drive.position_hold; by default hold_gains' rule, not Kinova's servo gains):
//     tau = tau_entry + Kp (q_d - q) + Kd (qd_d - qd)
//   On a rigid plant the -Kd qd term is applied by the plant within its step (implicit_damping())
//   while the current stays below its limit: a joint pair whose axes nearly align (a Panda at
//   q2 ~ -0.16) has a counter-rotation mode far lighter than either M_ii, on which the explicit
//   term rang at the physics step's Nyquist rate. (It acts on the true velocity: the velocity
//   sensor's noise no longer enters the hold's damping.)
//   qd_d = (q_d[k] - q_d[k-1]) / T_control from streamed set-points (0 when none is new), clipped
//   to the joint velocity limit. tau_entry = the motor torque of the previous tick minus the P
//   term: entering is bumpless, and an arm entering at rest keeps holding its weight with no
//   integrator (a load changed afterwards leaves an error of delta_tau / Kp).
// * kTorque — the joint torque set-point applied directly: tau = clamp(tau_d, torque_limit),
//   no sensor feedback; friction is the controller's to compensate.
// * kCurrent — i = i_d (phri's custom torque loop).
// Every mode: i = tau / (K_T G_r) with the nominal constant, saturated at current_limit_A.
// Kinova's torque loops are not offered (SimRobot refuses them before they reach the drive).
#include <phri/robot/actuator_table.hpp>
#include <phri/robot/drive_kind.hpp>
#include <phri/sim/drive_loops.hpp>
#include <phri/config/sim_robot_config.hpp>

#include <vector>

namespace phri {

class GenericDrive final : public DriveLoops {
public:
  /// `kp`, `kd`: the position hold's gains per joint [N.m/rad], [N.m.s/rad]; `control_period_s`:
  /// the period of begin_cycle().
  GenericDrive(const ActuatorTable& drives, const std::vector<double>& kp, const std::vector<double>& kd,
               double control_period_s);

  /// The position hold's gains: those `given`, and by default, joint by joint, critically damped
  /// at 30 Hz on the joint's inertia J_i [kg.m^2] (the arm's M_ii at the start posture, end of
  /// arm included, plus the reflected rotor inertia):
  ///   kp_i = J_i w^2,   kd_i = 2 sqrt(kp_i J_i),   w = 2 pi x 30 Hz
  /// (a kp given without its kd keeps the critical damping). 30 Hz: on the Gen3 at its home
  /// posture this gives 11 to 26 kN.m/rad on joints 1-4 and 1.1 to 2.6 on joints 5-7, near
  /// Kinova's own servo (12 and 3 kN.m/rad), and w h stays below 0.05 at the plant's 4 kHz step
  /// (the discrete loop is far from its stability bound).
  static constexpr double kDefaultHoldFrequency_Hz = 30.0;
  static void hold_gains(const Eigen::VectorXd& inertia, const GenericHoldGains& given, std::vector<double>& kp,
                         std::vector<double>& kd);

  /// The position hold's gains in force (tests, logs).
  const Eigen::VectorXd& kp() const { return kp_; }
  const Eigen::VectorXd& kd() const { return kd_; }

  LowLevelModeSet offered() const override { return offered_loops(DriveKind::kGeneric); }
  LowLevelMode mode() const override { return mode_; }
  void begin_cycle(const RobotCommand& command, bool fresh, const Eigen::VectorXd& q_meas,
                   const Eigen::VectorXd& tau_motor) override;
  void tick(const Eigen::VectorXd& q_meas, const Eigen::VectorXd& qd_meas, const Eigen::VectorXd& tau_meas,
            bool filter_tick, Eigen::VectorXd& current_out) override;
  bool uses_position() const override { return mode_ == LowLevelMode::kPosition; }
  bool uses_velocity() const override { return mode_ == LowLevelMode::kPosition; }
  bool uses_torque() const override { return false; }
  void start_holding(const Eigen::VectorXd& tau) override { hold_torque_ = tau; }
  void allow_implicit_damping(bool allowed) override { implicit_allowed_ = allowed; }
  double implicit_damping(int joint) const override { return implicit_damping_[joint]; }

  /// The position hold's torque offset [N.m] (tests, logs).
  const Eigen::VectorXd& hold_torque() const { return hold_torque_; }

private:
  int dof() const { return static_cast<int>(kp_.size()); }

  double control_period_s_;
  Eigen::VectorXd torque_per_amp_, current_limit_, torque_limit_, velocity_limit_, kp_, kd_;

  LowLevelMode mode_ = LowLevelMode::kPosition;
  bool entered_ = false;
  Eigen::VectorXd q_des_, qd_des_, hold_torque_, tau_des_, current_des_;
  Eigen::VectorXd last_qd_meas_;  // the velocity the drive last measured (bumpless position entry)
  bool implicit_allowed_ = false;
  Eigen::VectorXd implicit_damping_;  // per joint, the last tick's (implicit_damping())
};

}  // namespace phri
