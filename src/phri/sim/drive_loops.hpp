#pragma once
// phri::DriveLoops: the loops a simulated arm's drives run below the RobotInterface (in the
// actuator firmware on a real arm), one implementation per robot.yaml `drive:`:
//   kinova  KinovaDriveEmulator: position servo, Kinova's two torque loops, current
//   generic GenericDrive: PD position hold, plain torque, current
// Every mode ends in a motor current, saturated at the drive's limit; the plant turns it into
// joint torque K_T G_r i. begin_cycle() and tick() do not allocate.
#include <phri/robot/low_level_mode.hpp>
#include <phri/robot/robot_command.hpp>

#include <Eigen/Core>

#include <algorithm>
#include <vector>

namespace phri {

/// A position servo's velocity feed-forward from consecutive set-points (what the arm was asked
/// to move per period), each joint clamped to its velocity limit; the set-point becomes `q_des`.
inline void follow_set_point(const Eigen::VectorXd& q_new, double period_s, const Eigen::VectorXd& velocity_limit,
                             Eigen::VectorXd& q_des, Eigen::VectorXd& qd_ff) {
  for (Eigen::Index i = 0; i < q_des.size(); ++i) {
    const double v = (q_new[i] - q_des[i]) / period_s;
    qd_ff[i] = std::clamp(v, -velocity_limit[i], velocity_limit[i]);
  }
  q_des = q_new;
}

/// A per-joint gain list from the configuration as an n-vector, zero where the list is short
/// (construction only: it allocates).
inline Eigen::VectorXd per_joint_or_zero(const std::vector<double>& values, int n) {
  Eigen::VectorXd out = Eigen::VectorXd::Zero(n);
  for (int i = 0; i < n && i < static_cast<int>(values.size()); ++i) out[i] = values[static_cast<std::size_t>(i)];
  return out;
}

class DriveLoops {
public:
  virtual ~DriveLoops() = default;

  /// The modes these drives run; SimRobot refuses a write in any other mode.
  virtual LowLevelModeSet offered() const = 0;
  virtual LowLevelMode mode() const = 0;

  /// Start of a control cycle. `command` is the command in force for this cycle (already
  /// validated, in an offered mode); `fresh` says whether it was written since the previous
  /// cycle. `q_meas` and `tau_motor` (the motor torque of the previous tick) initialise a newly
  /// entered mode.
  virtual void begin_cycle(const RobotCommand& command, bool fresh, const Eigen::VectorXd& q_meas,
                           const Eigen::VectorXd& tau_motor) = 0;
  /// One inner-loop tick: measured q, qd, tau_s in; saturated motor current out. `filter_tick`
  /// clocks loops that run slower than the physics (Kinova's H(z)).
  virtual void tick(const Eigen::VectorXd& q_meas, const Eigen::VectorXd& qd_meas, const Eigen::VectorXd& tau_meas,
                    bool filter_tick, Eigen::VectorXd& current_out) = 0;

  /// Which measurements the running mode reads (the plant draws sensor noise only for those, and
  /// reads the encoder for the loop only when it closes on position).
  virtual bool uses_position() const = 0;
  virtual bool uses_velocity() const = 0;
  virtual bool uses_torque() const = 0;

  /// The arm starts the simulation already holding itself: the position hold carries `tau` [N.m]
  /// (the gravity torque of the initial pose) from the first tick.
  virtual void start_holding(const Eigen::VectorXd& tau) = 0;

  /// Whether a tick may leave its damping on the joint velocity to the plant (SimRobot allows it
  /// where the motor torque acts on the link itself: rigid transmissions).
  virtual void allow_implicit_damping(bool /*allowed*/) {}
  /// The damping c [N.m.s/rad] of `joint` the last tick left out of its current: the plant applies
  /// -c qd within its step, on the velocity at the step's end (implicit), as a drive's continuous
  /// loop does; an explicit -c qd_meas rings at the step's rate on a light mode of the arm when
  /// c h exceeds that mode's inertia. 0: none.
  virtual double implicit_damping(int /*joint*/) const { return 0.0; }
};

}  // namespace phri
