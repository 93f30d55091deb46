#include <phri/lowlevel/low_level_controller.hpp>

#include <cmath>

namespace phri {
namespace {
constexpr double kTorqueBlendTime = 0.05;  // s
}

LowLevelController::LowLevelController(const ActuatorTable& actuators, const CustomTorqueSettings& custom,
                                       LowLevelMode initial)
    : custom_(actuators, custom),
      period_s_(custom.period_s),
      loop_(initial),
      requested_(initial),
      q_ref_(Eigen::VectorXd::Zero(actuators.size())),
      qd_ref_(Eigen::VectorXd::Zero(actuators.size())),
      torque_offset_(Eigen::VectorXd::Zero(actuators.size())),
      torque_per_amp_(Eigen::VectorXd::Zero(actuators.size())),
      offset_decay_(std::exp(-custom.period_s / kTorqueBlendTime)) {
  for (int i = 0; i < actuators.size(); ++i) torque_per_amp_[i] = actuators[i].torque_per_amp();
}

void LowLevelController::update(const RobotState& state, const Eigen::VectorXd& tau_desired,
                                const Eigen::VectorXd& qdd_desired, RobotCommand& command) {
  const bool entering = !started_ || requested_ != loop_;
  if (requested_ != loop_) ++switches_;
  loop_ = requested_;
  started_ = true;
  switch (loop_) {
    case LowLevelMode::kPosition:
      if (entering) {
        // Start the reference where the arm is, moving as it moves: no position step.
        q_ref_ = state.q_rad;
        qd_ref_ = state.qd_rad_s;
      }
      // Semi-implicit Euler integration of the desired acceleration.
      qd_ref_ += period_s_ * qdd_desired;
      q_ref_ += period_s_ * qd_ref_;
      command.mode = LowLevelMode::kPosition;
      command.q_rad = q_ref_;
      break;
    case LowLevelMode::kKinovaTorque:
    case LowLevelMode::kKinovaTorqueHighVelocity:
      command.mode = loop_ == LowLevelMode::kKinovaTorque ? LowLevelMode::kKinovaTorque
                                                          : LowLevelMode::kKinovaTorqueHighVelocity;
      // Bumpless: start from the torque the motors produce now, fade into tau_d. That torque is
      // the measured current in the vendor's own units (nominal K_T G_r, the constant its loop
      // converts with), so the first command asks for the present current even when the drives'
      // true constant differs; without a current reading, the joint torque sensors (which miss
      // the friction and rotor torque between motor and sensor).
      if (entering) {
        if (state.current.valid) {
          torque_offset_ = torque_per_amp_.cwiseProduct(state.current_A) - tau_desired;
        } else {
          torque_offset_ = state.tau_sensor_Nm - tau_desired;
        }
      }
      command.tau_Nm = tau_desired + torque_offset_;
      torque_offset_ *= offset_decay_;
      break;
    case LowLevelMode::kCurrent:
      if (entering) {
        custom_.reset(state.current_A, tau_desired, qdd_desired, state.tau_sensor_Nm, state.qd_rad_s);
      } else {
        custom_.update(tau_desired, qdd_desired, state.tau_sensor_Nm, state.qd_rad_s);
      }
      command.mode = LowLevelMode::kCurrent;
      command.current_A = custom_.current();
      break;
  }
}

}  // namespace phri
