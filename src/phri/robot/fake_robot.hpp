#pragma once
// phri::FakeRobot: a fast, deterministic RobotInterface without MuJoCo, for tests of whatever sits
// above the interface (the run loop, the controller's handling of bad data, a hardware client's
// callers). Each joint is a decoupled unit-inertia double integrator, no gravity, no friction,
// no noise, stepped once per read() on the last accepted command:
//
//   kPosition                   q[k+1] = q_cmd,  qd[k+1] = (q_cmd - q[k]) / T  (an ideal servo)
//   kKinovaTorque(HighVelocity) u = tau_cmd
//   kCurrent                    u = K_T G_r i_cmd (torque_per_amp, one per joint)
//   torque modes:               qd[k+1] = qd[k] + T u,  q[k+1] = q[k] + T qd[k+1]  (semi-implicit Euler)
//
// The sensors report that motion exactly: tau_sensor = the link's acceleration (unit inertia)
// (qd[k+1] - qd[k]) / T, current = tau_sensor / torque_per_amp; there is no F/T sensor
// (wrench.valid stays false). Like SimRobot, read() number k returns time k T and cycle k, and the
// arm holds its initial posture in kPosition until a command is accepted.
//
// Fault hooks (windows of read or write numbers, 1-based: read k returns cycle k) make the robot
// misbehave the way a real one can, so that tests check how the callers cope:
//   inject_nan         q_rad[joint] is NaN in the state returned (the flag joints.valid stays
//                      true: a driver that did not notice; the caller must check the numbers)
//   invalidate_joints  joints.valid is false (a driver that did notice), numbers finite
//   freeze_joints      no new joint frame: q, qd and joints.sequence/stamp repeat the last frame
//                      (the arm still moves underneath, and time_s still advances)
//   refuse_writes      write() returns the given status and the command is not applied
//   set_fault          the robot stops obeying: every write is refused with kFault, state.fault
//                      is set and the arm stands still (brakes) until set_fault(false)
// write() also refuses what a real robot refuses: kInvalidMode, kSizeMismatch, kNotFinite.
// Counters: reads(), writes(), accepted_writes(), refused_writes(); last_accepted() is the command
// the arm executes; an optional observer sees every write() and its status.
//
// read() and write() never throw and, without an observer that allocates, never allocate.
#include <phri/robot/robot_description.hpp>
#include <phri/robot/robot_interface.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <functional>

namespace phri {

struct FakeRobotSettings {
  int dof = 7;
  double period_s = 1e-3;
  Eigen::VectorXd initial_q_rad;            ///< empty: zeros
  Eigen::VectorXd torque_per_amp_Nm_per_A;  ///< K_T G_r per joint for kCurrent; empty: ones
};

/// A fake of the described robot: its joints, its home posture, its actuators' torque per amp.
FakeRobotSettings fake_robot_settings(const RobotDescription& robot, double period_s);

/// Read or write numbers first .. first + count - 1 (1-based); count 0: none.
struct CycleWindow {
  std::uint64_t first = 0;
  std::uint64_t count = 0;
  bool contains(std::uint64_t k) const { return count > 0 && k >= first && k - first < count; }
};

class FakeRobot final : public RobotInterface {
public:
  using WriteObserver = std::function<void(const RobotCommand& command, WriteStatus status)>;

  /// Throws ConfigError on dof < 1 or period <= 0, ArgumentError on vectors of the wrong size.
  explicit FakeRobot(const FakeRobotSettings& settings = {});

  int dof() const override { return n_; }
  double period_s() const override { return period_; }
  const RobotState& read() override;
  WriteStatus write(const RobotCommand& command) override;

  // ---- fault hooks (replace any earlier window of the same kind)
  void inject_nan(CycleWindow reads, int joint = 0) {
    nan_reads_ = reads;
    nan_joint_ = joint;
  }
  void invalidate_joints(CycleWindow reads) { invalid_reads_ = reads; }
  void freeze_joints(CycleWindow reads) { frozen_reads_ = reads; }
  void refuse_writes(CycleWindow writes, WriteStatus status = WriteStatus::kFault) {
    refused_writes_window_ = writes;
    refusal_ = status;
  }
  void set_fault(bool fault) { fault_ = fault; }
  void set_write_observer(WriteObserver observer) { observer_ = std::move(observer); }

  // ---- counters and the arm's true motion
  std::uint64_t reads() const { return reads_; }
  std::uint64_t writes() const { return writes_; }
  std::uint64_t accepted_writes() const { return writes_ - refused_; }
  std::uint64_t refused_writes() const { return refused_; }
  /// The command the arm executes from the next read() (the initial hold before any write).
  const RobotCommand& last_accepted() const { return command_; }
  /// The arm's true joint positions and velocities (what the state shows when no fault is set).
  const Eigen::VectorXd& true_q() const { return q_; }
  const Eigen::VectorXd& true_qd() const { return qd_; }
  /// The last state returned by read() (the initial state before any).
  const RobotState& state() const { return state_; }

private:
  WriteStatus validate(const RobotCommand& command) const;
  void integrate();
  void publish();

  int n_;
  double period_;
  Eigen::VectorXd torque_per_amp_;
  Eigen::VectorXd q_, qd_, acceleration_;
  RobotCommand command_;
  RobotState state_;
  std::uint64_t reads_ = 0, writes_ = 0, refused_ = 0;
  CycleWindow nan_reads_, invalid_reads_, frozen_reads_, refused_writes_window_;
  int nan_joint_ = 0;
  WriteStatus refusal_ = WriteStatus::kFault;
  bool fault_ = false;
  WriteObserver observer_;
};

}  // namespace phri
