#include <phri/robot/fake_robot.hpp>

#include <phri/core/error.hpp>

#include <limits>
#include <string>

namespace phri {

FakeRobotSettings fake_robot_settings(const RobotDescription& robot, double period_s) {
  FakeRobotSettings s;
  s.dof = robot.dof();
  s.period_s = period_s;
  if (static_cast<int>(robot.initial_q_rad.size()) == s.dof) {
    s.initial_q_rad = Eigen::Map<const Eigen::VectorXd>(robot.initial_q_rad.data(), s.dof);
  }
  s.torque_per_amp_Nm_per_A.resize(s.dof);
  for (int i = 0; i < s.dof; ++i) s.torque_per_amp_Nm_per_A[i] = robot.actuators[i].torque_per_amp();
  return s;
}

FakeRobot::FakeRobot(const FakeRobotSettings& settings) : n_(settings.dof), period_(settings.period_s) {
  if (settings.dof < 1) throw ConfigError("FakeRobotSettings", "dof", "must be >= 1");
  if (!(settings.period_s > 0.0)) throw ConfigError("FakeRobotSettings", "period_s", "must be > 0");
  q_ = Eigen::VectorXd::Zero(n_);
  if (settings.initial_q_rad.size() > 0) {
    check_size("FakeRobot", "initial_q_rad", settings.initial_q_rad.size(), n_);
    q_ = settings.initial_q_rad;
  }
  torque_per_amp_ = Eigen::VectorXd::Ones(n_);
  if (settings.torque_per_amp_Nm_per_A.size() > 0) {
    check_size("FakeRobot", "torque_per_amp_Nm_per_A", settings.torque_per_amp_Nm_per_A.size(), n_);
    torque_per_amp_ = settings.torque_per_amp_Nm_per_A;
  }
  qd_ = Eigen::VectorXd::Zero(n_);
  acceleration_ = Eigen::VectorXd::Zero(n_);
  command_ = RobotCommand(n_);
  command_.mode = LowLevelMode::kPosition;
  command_.q_rad = q_;  // hold the initial posture until a command is accepted
  state_ = RobotState(n_);
  state_.q_rad = q_;
  state_.joints.valid = state_.torque.valid = state_.current.valid = true;
}

WriteStatus FakeRobot::validate(const RobotCommand& c) const {
  if (fault_) return WriteStatus::kFault;
  if (refused_writes_window_.contains(writes_)) return refusal_;
  if (!is_valid(c.mode)) return WriteStatus::kInvalidMode;
  const Eigen::VectorXd& v = c.mode == LowLevelMode::kPosition ? c.q_rad
                             : c.mode == LowLevelMode::kCurrent ? c.current_A
                                                                : c.tau_Nm;
  if (v.size() != n_) return WriteStatus::kSizeMismatch;
  if (!v.allFinite()) return WriteStatus::kNotFinite;
  return WriteStatus::kOk;
}

WriteStatus FakeRobot::write(const RobotCommand& command) {
  ++writes_;
  const WriteStatus status = validate(command);
  state_.last_write_status = status;
  if (status != WriteStatus::kOk) {
    ++refused_;
    state_.rejected_writes = refused_;
  } else {
    command_.copy_setpoint(command);
  }
  if (observer_) observer_(command, status);
  return status;
}

// One period of the unit-inertia double integrators on the accepted command.
void FakeRobot::integrate() {
  if (command_.mode == LowLevelMode::kPosition) {
    for (int i = 0; i < n_; ++i) {
      const double qd = (command_.q_rad[i] - q_[i]) / period_;
      acceleration_[i] = (qd - qd_[i]) / period_;
      qd_[i] = qd;
      q_[i] = command_.q_rad[i];
    }
    return;
  }
  for (int i = 0; i < n_; ++i) {
    acceleration_[i] = command_.mode == LowLevelMode::kCurrent ? torque_per_amp_[i] * command_.current_A[i]
                                                               : command_.tau_Nm[i];
    qd_[i] += period_ * acceleration_[i];
    q_[i] += period_ * qd_[i];
  }
}

// The state of read number reads_, with the faults of that read.
void FakeRobot::publish() {
  const double t = static_cast<double>(reads_) * period_;
  state_.time_s = t;
  state_.cycle = reads_;
  state_.mode = command_.mode;
  state_.fault = fault_;
  if (!frozen_reads_.contains(reads_)) {
    state_.q_rad = q_;
    state_.qd_rad_s = qd_;
    ++state_.joints.sequence;
    state_.joints.stamp_s = t;
  }
  if (nan_reads_.contains(reads_) && nan_joint_ >= 0 && nan_joint_ < n_) {
    state_.q_rad[nan_joint_] = std::numeric_limits<double>::quiet_NaN();
  }
  state_.joints.valid = !invalid_reads_.contains(reads_);
  state_.tau_sensor_Nm = acceleration_;  // unit inertia: the torque that accelerated the link
  state_.current_A = acceleration_.cwiseQuotient(torque_per_amp_);
  for (SignalStatus* s : {&state_.torque, &state_.current}) {
    ++s->sequence;
    s->stamp_s = t;
    s->valid = true;
  }
}

const RobotState& FakeRobot::read() {
  ++reads_;
  if (fault_) {
    qd_.setZero();  // the brakes hold the arm
    acceleration_.setZero();
  } else {
    integrate();
  }
  publish();
  return state_;
}

}  // namespace phri
