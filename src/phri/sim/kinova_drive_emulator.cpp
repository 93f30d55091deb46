#include <phri/sim/kinova_drive_emulator.hpp>

#include <algorithm>

namespace phri {

KinovaDriveEmulator::KinovaDriveEmulator(const ActuatorTable& drives, const SimRobotConfig::Vendor& vendor,
                                         double tick_s, double control_period_s)
    : tick_s_(tick_s), control_period_s_(control_period_s) {
  const int n = drives.size();
  torque_per_amp_.resize(n);
  current_limit_.resize(n);
  velocity_limit_.resize(n);
  for (int i = 0; i < n; ++i) {
    torque_per_amp_[i] = drives[i].torque_per_amp();
    current_limit_[i] = drives[i].current_limit_A;
    velocity_limit_[i] = drives[i].velocity_limit_rad_s;
  }
  kp_ = per_joint_or_zero(vendor.position_kp_Nm_per_rad, n);
  kd_ = per_joint_or_zero(vendor.position_kd_Nms_per_rad, n);
  ki_ = per_joint_or_zero(vendor.position_ki_Nm_per_rad_s, n);
  integral_limit_ = per_joint_or_zero(vendor.position_integral_limit_Nm, n);
  kt_ = per_joint_or_zero(vendor.torque_feedback_gain, n);
  damping_ = per_joint_or_zero(vendor.torque_velocity_damping_Nms_per_rad, n);
  const DiscreteTransferFunction filter(vendor.high_velocity_numerator, vendor.high_velocity_denominator);
  filters_.assign(static_cast<std::size_t>(n), filter);
  q_des_ = Eigen::VectorXd::Zero(n);
  qd_ff_ = Eigen::VectorXd::Zero(n);
  tau_des_ = Eigen::VectorXd::Zero(n);
  current_des_ = Eigen::VectorXd::Zero(n);
  integral_ = Eigen::VectorXd::Zero(n);
  filter_out_ = Eigen::VectorXd::Zero(n);
  last_qd_meas_ = Eigen::VectorXd::Zero(n);
}

void KinovaDriveEmulator::set_position_integral(const Eigen::VectorXd& integral) {
  integral_ = integral.cwiseMax(-integral_limit_).cwiseMin(integral_limit_);
}

void KinovaDriveEmulator::enter(LowLevelMode mode, const Eigen::VectorXd& q_meas, const Eigen::VectorXd& tau_motor) {
  mode_ = mode;
  entered_ = true;
  switch (mode) {
    case LowLevelMode::kPosition:
      // Bumpless: the servo starts by producing the torque the motor produced last; moving as the
      // arm moves, so the D term starts at zero (the next fresh set-point gives the feed-forward).
      qd_ff_ = last_qd_meas_.cwiseMax(-velocity_limit_).cwiseMin(velocity_limit_);
      integral_ = (tau_motor - kp_.cwiseProduct(q_des_ - q_meas)).cwiseMax(-integral_limit_).cwiseMin(integral_limit_);
      break;
    case LowLevelMode::kKinovaTorqueHighVelocity:
      for (auto& f : filters_) f.reset();
      filter_out_.setZero();
      break;
    case LowLevelMode::kKinovaTorque:
    case LowLevelMode::kCurrent:
    case LowLevelMode::kTorque:  // not offered
      break;
  }
}

void KinovaDriveEmulator::begin_cycle(const RobotCommand& command, bool fresh, const Eigen::VectorXd& q_meas,
                                      const Eigen::VectorXd& tau_motor) {
  const bool mode_change = !entered_ || command.mode != mode_;
  switch (command.mode) {
    case LowLevelMode::kPosition:
      if (mode_change) {
        q_des_ = command.q_rad;
      } else if (fresh) {
        follow_set_point(command.q_rad, control_period_s_, velocity_limit_, q_des_, qd_ff_);
      } else {
        qd_ff_.setZero();  // no new set-point: hold
      }
      break;
    case LowLevelMode::kKinovaTorque:
    case LowLevelMode::kKinovaTorqueHighVelocity:
      tau_des_ = command.tau_Nm;
      break;
    case LowLevelMode::kCurrent:
      current_des_ = command.current_A;
      break;
    case LowLevelMode::kTorque:  // not offered (SimRobot::validate refuses it)
      break;
  }
  if (mode_change) enter(command.mode, q_meas, tau_motor);
}

void KinovaDriveEmulator::tick(const Eigen::VectorXd& q_meas, const Eigen::VectorXd& qd_meas,
                               const Eigen::VectorXd& tau_meas, bool filter_tick, Eigen::VectorXd& current_out) {
  last_qd_meas_ = qd_meas;
  const int n = dof();
  for (int i = 0; i < n; ++i) {
    double tau = 0.0;
    switch (mode_) {
      case LowLevelMode::kPosition: {
        const double e = q_des_[i] - q_meas[i];
        integral_[i] = std::clamp(integral_[i] + ki_[i] * e * tick_s_, -integral_limit_[i], integral_limit_[i]);
        tau = kp_[i] * e + kd_[i] * (qd_ff_[i] - qd_meas[i]) + integral_[i];
        break;
      }
      case LowLevelMode::kKinovaTorque:
        tau = tau_des_[i] + kt_[i] * (tau_des_[i] - tau_meas[i]) - damping_[i] * qd_meas[i];
        break;
      case LowLevelMode::kKinovaTorqueHighVelocity:
        if (filter_tick) filter_out_[i] = filters_[static_cast<std::size_t>(i)].step(tau_des_[i] - tau_meas[i]);
        tau = tau_des_[i] + filter_out_[i];
        break;
      case LowLevelMode::kCurrent:
        current_out[i] = std::clamp(current_des_[i], -current_limit_[i], current_limit_[i]);
        continue;
      case LowLevelMode::kTorque:  // not offered: no torque rather than a loop Kinova lacks
        break;
    }
    current_out[i] = std::clamp(tau / torque_per_amp_[i], -current_limit_[i], current_limit_[i]);
  }
}

}  // namespace phri
