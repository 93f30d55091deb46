#include <phri/lowlevel/low_level_controller.hpp>

#include <phri/lowlevel/friction_compensation.hpp>

#include <algorithm>
#include <cmath>

namespace phri {
namespace {
constexpr double kTorqueBlendTime = 0.05;  // s
}

LowLevelController::LowLevelController(const ActuatorTable& actuators, const CustomTorqueSettings& custom,
                                       LowLevelMode initial, double following_error_rad)
    : custom_(actuators, custom),
      period_s_(custom.period_s),
      loop_(initial),
      requested_(initial),
      following_error_rad_(following_error_rad),
      q_ref_(Eigen::VectorXd::Zero(actuators.size())),
      qd_ref_(Eigen::VectorXd::Zero(actuators.size())),
      torque_offset_(Eigen::VectorXd::Zero(actuators.size())),
      torque_per_amp_(Eigen::VectorXd::Zero(actuators.size())),
      current_limit_(Eigen::VectorXd::Zero(actuators.size())),
      entry_current_(Eigen::VectorXd::Zero(actuators.size())),
      breakaway_(Eigen::VectorXd::Zero(actuators.size())),
      breakaway_share_(Eigen::VectorXd::Constant(actuators.size(), kVendorBreakawayShare)),
      reflected_inertia_(Eigen::VectorXd::Zero(actuators.size())),
      feedforward_(Eigen::VectorXd::Zero(actuators.size())),
      entry_torque_(Eigen::VectorXd::Zero(actuators.size())),
      measured_current_(Eigen::VectorXd::Zero(actuators.size())),
      offset_decay_(std::exp(-custom.period_s / kTorqueBlendTime)) {
  for (int i = 0; i < actuators.size(); ++i) {
    reflected_inertia_[i] = actuators[i].reflected_inertia_kgm2;
    torque_per_amp_[i] = actuators[i].torque_per_amp();
    current_limit_[i] = actuators[i].current_limit_A;
    friction_.push_back(actuators[i].friction);
  }
}

// The entry offset and the feed-forward terms ride on a tau_d the QP keeps within its limits; their
// sum is held within what the drive can give (its current limit x K_T G_r), since a set-point beyond
// it is refused (the robot faults) rather than saturated.
void LowLevelController::saturate_to_drive_range(Eigen::VectorXd& tau) const {
  for (int i = 0; i < tau.size(); ++i) {
    const double range = current_limit_[i] * torque_per_amp_[i];
    tau[i] = std::clamp(tau[i], -range, range);
  }
}

void LowLevelController::command_torque(const Eigen::VectorXd& tau, RobotCommand& command) {
  current_samples_ = 0;
  switch (loop_) {
    case LowLevelMode::kPosition: return;
    case LowLevelMode::kKinovaTorque:
    case LowLevelMode::kKinovaTorqueHighVelocity:
    case LowLevelMode::kTorque:
      command.mode = loop_;
      command.tau_Nm = tau;
      return;
    case LowLevelMode::kCurrent:
      command.mode = loop_;
      command.current_A = tau.cwiseQuotient(torque_per_amp_).cwiseMax(-current_limit_).cwiseMin(current_limit_);
      return;
  }
}

void LowLevelController::hold(const Eigen::VectorXd& q, RobotCommand& command) {
  current_samples_ = 0;  // the average restarts with the next reading (no state comes with a hold)
  if (loop_ != LowLevelMode::kPosition) ++switches_;
  loop_ = requested_ = LowLevelMode::kPosition;
  started_ = true;
  q_ref_ = q;
  qd_ref_.setZero();
  command.mode = LowLevelMode::kPosition;
  command.q_rad = q_ref_;
}

void LowLevelController::update(const RobotState& state, const Eigen::VectorXd& tau_desired,
                                const Eigen::VectorXd& qdd_desired, RobotCommand& command) {
  const bool current_known = track_current(state);
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
      // The integration is open loop: when the servo cannot follow (a push it cannot resist), the
      // reference would run away. It is kept within following_error_rad of the arm, below the
      // robot's following-error fault, and stops moving: the servo keeps resisting the push with
      // the largest error allowed, and the arm returns once the push ends.
      for (int i = 0; i < q_ref_.size(); ++i) {
        const double error = q_ref_[i] - state.q_rad[i];
        if (std::abs(error) <= following_error_rad_) continue;
        q_ref_[i] = state.q_rad[i] + std::copysign(following_error_rad_, error);
        qd_ref_[i] = 0.0;
        ++resyncs_;
      }
      command.mode = LowLevelMode::kPosition;
      command.q_rad = q_ref_;
      break;
    case LowLevelMode::kKinovaTorque:
    case LowLevelMode::kKinovaTorqueHighVelocity:
      command.mode = loop_;
      // Bumpless: start from the torque the motors produce now, fade into tau_d. That torque is
      // the measured current in the vendor's own units (nominal K_T G_r, the constant its loop
      // converts with), so the first command asks for the present current even when the drives'
      // true constant differs; without a current reading, the joint torque sensors (which miss
      // the friction and rotor torque between motor and sensor).
      if (entering) torque_offset_ = entry_torque(state) - tau_desired;
      update_friction_assist(state.qd_rad_s, qdd_desired);
      command.tau_Nm = tau_desired + torque_offset_ + breakaway_;
      saturate_to_drive_range(command.tau_Nm);
      torque_offset_ *= offset_decay_;
      break;
    case LowLevelMode::kTorque:
      // A plain torque drive applies the set-point as it is: no sensor feedback rejects the gear
      // friction or drives the rotor, so the custom loop's feed-forward terms are added here.
      command.mode = LowLevelMode::kTorque;
      if (entering) torque_offset_ = entry_torque(state) - tau_desired;  // bumpless, as above
      plain_torque_feedforward(state.qd_rad_s, qdd_desired);
      command.tau_Nm = tau_desired + torque_offset_ + feedforward_;
      saturate_to_drive_range(command.tau_Nm);
      torque_offset_ *= offset_decay_;
      break;
    case LowLevelMode::kCurrent:
      if (entering) {
        // Start from the current the drives carry; a robot without current readings (or with a
        // short vector): from the desired torque's nominal current.
        if (current_known) {
          entry_current_ = measured_current_;
        } else {
          entry_current_ = tau_desired.cwiseQuotient(torque_per_amp_);
        }
        custom_.reset(entry_current_, tau_desired, qdd_desired, state.tau_sensor_Nm, state.qd_rad_s);
      } else {
        custom_.update(tau_desired, qdd_desired, state.tau_sensor_Nm, state.qd_rad_s);
      }
      command.mode = LowLevelMode::kCurrent;
      command.current_A = custom_.current();
      break;
  }
}

bool LowLevelController::track_current(const RobotState& state) {
  if (!state.current.valid || state.current_A.size() != measured_current_.size() || !state.current_A.allFinite()) {
    current_samples_ = 0;
    return false;
  }
  ++current_samples_;
  const double first_order = period_s_ / (kEntryCurrentTime_s + period_s_);
  const double weight = std::max(first_order, 1.0 / static_cast<double>(current_samples_));
  measured_current_ += weight * (state.current_A - measured_current_);
  return true;
}

const Eigen::VectorXd& LowLevelController::entry_torque(const RobotState& state) {
  if (current_samples_ > 0) {
    entry_torque_ = torque_per_amp_.cwiseProduct(measured_current_);
  } else {
    entry_torque_ = state.tau_sensor_Nm;
  }
  return entry_torque_;
}

// The plain torque mode's feed-forward: the paper's friction model and the rotor's inertia torque,
// each as the custom loop's settings switch it.
void LowLevelController::plain_torque_feedforward(const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd_desired) {
  const CustomTorqueSettings& settings = custom_.settings();
  for (Eigen::Index i = 0; i < feedforward_.size(); ++i) {
    const std::size_t j = static_cast<std::size_t>(i);
    const double friction = settings.friction_compensation ? friction_compensation(friction_[j], qd[i], qdd_desired[i]) : 0.0;
    const double rotor = settings.rotor_inertia_compensation ? reflected_inertia_[i] * qdd_desired[i] : 0.0;
    feedforward_[i] = friction + rotor;
  }
}

// The vendor loops' friction assist (not in the paper, whose custom loop pre-compensates all of
// friction): a share of the paper's friction model where the vendor loop, with its velocity
// feedback and no friction compensation, leaves a joint stuck or crawling although the task asks
// it to move. Stuck (the model's breakaway case): share * static friction in the direction asked.
// Sliding slowly (below 3 x the model's velocity threshold) in the direction the task still
// accelerates: share * Coulomb friction along the motion; without it the joint crawls at the
// threshold, the assist switching on and off as it crosses. The share grows (a hand pushing
// harder) while the joint stays slow and asked the same way, up to the whole friction; it starts
// again at the base share otherwise. Off (the controller disables the ramp while a hand carries the
// arm in full-body compliance and in dual compliance once a hand has placed the end effector): the
// breakaway case alone at the base share.
void LowLevelController::update_friction_assist(const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd_desired) {
  for (Eigen::Index i = 0; i < breakaway_.size(); ++i) {
    const FrictionParameters& friction = friction_[static_cast<std::size_t>(i)];
    FrictionCase which = FrictionCase::kNone;
    const double tau_f = friction_compensation(friction, qd[i], qdd_desired[i], &which);
    double direction = 0.0, full = 0.0;
    if (which == FrictionCase::kStatic) {
      direction = tau_f;
      full = friction.static_Nm;
    } else if (breakaway_ramp_ && which == FrictionCase::kSliding &&
               std::abs(qd[i]) < kSlowSlideFactor * friction.velocity_threshold_rad_s && qd[i] * qdd_desired[i] > 0.0) {
      direction = qd[i];
      full = friction.coulomb_Nm;
    }
    const bool same_push = breakaway_ramp_ && direction * breakaway_[i] > 0.0;
    breakaway_share_[i] = same_push ? std::min(breakaway_share_[i] + kBreakawayShareRate_per_s * period_s_, 1.0)
                                    : kVendorBreakawayShare;
    breakaway_[i] = direction == 0.0 ? 0.0 : std::copysign(breakaway_share_[i] * full, direction);
  }
}

}  // namespace phri
