#include <phri/sim/generic_drive.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace phri {

GenericDrive::GenericDrive(const ActuatorTable& drives, const std::vector<double>& kp, const std::vector<double>& kd,
                           double control_period_s)
    : control_period_s_(control_period_s) {
  const int n = drives.size();
  torque_per_amp_.resize(n);
  current_limit_.resize(n);
  torque_limit_.resize(n);
  velocity_limit_.resize(n);
  for (int i = 0; i < n; ++i) {
    torque_per_amp_[i] = drives[i].torque_per_amp();
    current_limit_[i] = drives[i].current_limit_A;
    torque_limit_[i] = drives[i].torque_limit_Nm;
    velocity_limit_[i] = drives[i].velocity_limit_rad_s;
  }
  kp_ = per_joint_or_zero(kp, n);
  kd_ = per_joint_or_zero(kd, n);
  q_des_ = Eigen::VectorXd::Zero(n);
  qd_des_ = Eigen::VectorXd::Zero(n);
  hold_torque_ = Eigen::VectorXd::Zero(n);
  tau_des_ = Eigen::VectorXd::Zero(n);
  current_des_ = Eigen::VectorXd::Zero(n);
  last_qd_meas_ = Eigen::VectorXd::Zero(n);
  implicit_damping_ = Eigen::VectorXd::Zero(n);
}

void GenericDrive::hold_gains(const Eigen::VectorXd& inertia, const GenericHoldGains& given, std::vector<double>& kp,
                              std::vector<double>& kd) {
  const double w = 2.0 * std::numbers::pi * kDefaultHoldFrequency_Hz;
  const auto n = static_cast<std::size_t>(inertia.size());
  kp.assign(n, 0.0);
  kd.assign(n, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const double j = inertia[static_cast<Eigen::Index>(i)];
    kp[i] = i < given.kp_Nm_per_rad.size() ? given.kp_Nm_per_rad[i] : j * w * w;
    kd[i] = i < given.kd_Nms_per_rad.size() ? given.kd_Nms_per_rad[i] : 2.0 * std::sqrt(kp[i] * j);
  }
}

void GenericDrive::begin_cycle(const RobotCommand& command, bool fresh, const Eigen::VectorXd& q_meas,
                               const Eigen::VectorXd& tau_motor) {
  const bool mode_change = !entered_ || command.mode != mode_;
  mode_ = command.mode;
  entered_ = true;
  switch (command.mode) {
    case LowLevelMode::kPosition:
      if (mode_change) {
        // Bumpless: the hold starts with the torque the motor produced last, moving as the arm
        // moves (the D term starts at zero).
        q_des_ = command.q_rad;
        qd_des_ = last_qd_meas_.cwiseMax(-velocity_limit_).cwiseMin(velocity_limit_);
        hold_torque_ = tau_motor - kp_.cwiseProduct(q_des_ - q_meas);
      } else if (fresh) {
        follow_set_point(command.q_rad, control_period_s_, velocity_limit_, q_des_, qd_des_);
      } else {
        qd_des_.setZero();  // no new set-point: hold
      }
      break;
    case LowLevelMode::kTorque:
      tau_des_ = command.tau_Nm;
      break;
    case LowLevelMode::kCurrent:
      current_des_ = command.current_A;
      break;
    case LowLevelMode::kKinovaTorque:
    case LowLevelMode::kKinovaTorqueHighVelocity:
      // Not offered (SimRobot::validate refuses them): no torque rather than a loop we lack.
      tau_des_.setZero();
      break;
  }
}

void GenericDrive::tick(const Eigen::VectorXd& q_meas, const Eigen::VectorXd& qd_meas,
                        const Eigen::VectorXd& /*tau_meas*/, bool /*filter_tick*/, Eigen::VectorXd& current_out) {
  last_qd_meas_ = qd_meas;
  for (int i = 0; i < dof(); ++i) {
    double tau = 0.0;
    implicit_damping_[i] = 0.0;
    switch (mode_) {
      case LowLevelMode::kPosition: {
        const double without_damping = hold_torque_[i] + kp_[i] * (q_des_[i] - q_meas[i]) + kd_[i] * qd_des_[i];
        tau = without_damping - kd_[i] * qd_meas[i];
        // Unsaturated: the damping goes to the plant's step (header), and the current sent is the
        // rest of it, not clamped on its own (with the damping the motor stays within its limit);
        // saturated, the current is the limit's.
        if (implicit_allowed_ && std::abs(tau) <= current_limit_[i] * torque_per_amp_[i]) {
          implicit_damping_[i] = kd_[i];
          current_out[i] = without_damping / torque_per_amp_[i];
          continue;
        }
        break;
      }
      case LowLevelMode::kTorque:
        tau = std::clamp(tau_des_[i], -torque_limit_[i], torque_limit_[i]);
        break;
      case LowLevelMode::kCurrent:
        current_out[i] = std::clamp(current_des_[i], -current_limit_[i], current_limit_[i]);
        continue;
      case LowLevelMode::kKinovaTorque:
      case LowLevelMode::kKinovaTorqueHighVelocity:
        break;
    }
    current_out[i] = std::clamp(tau / torque_per_amp_[i], -current_limit_[i], current_limit_[i]);
  }
}

}  // namespace phri
