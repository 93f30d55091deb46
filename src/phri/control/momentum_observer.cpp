#include <phri/control/momentum_observer.hpp>
#include <phri/core/error.hpp>

#include <algorithm>

namespace phri {

MomentumObserver::MomentumObserver(const Model& model, double gain)
    : gains_(Eigen::VectorXd::Constant(model.nv(), gain)),
      momentum_(Eigen::VectorXd::Zero(model.nv())),
      initial_momentum_(Eigen::VectorXd::Zero(model.nv())),
      integral_(Eigen::VectorXd::Zero(model.nv())),
      residual_(Eigen::VectorXd::Zero(model.nv())),
      release_integral_(Eigen::VectorXd::Zero(model.nv())),
      release_residual_(Eigen::VectorXd::Zero(model.nv())),
      release_velocity_(Eigen::VectorXd::Zero(model.nv())),
      release_kick_(Eigen::VectorXd::Zero(model.nv())) {}

void MomentumObserver::set_release_path(double gain, double threshold, const Eigen::VectorXd& release_speed) {
  check_size("MomentumObserver::set_release_path", "release_speed", release_speed.size(), gains_.size());
  release_gain_ = gain;
  release_threshold_ = threshold;
  release_speed_ = release_speed;
  // The fast observer starts where the slow one stands: r_fast = gain (p - p0 - I_fast) = r.
  release_residual_ = residual_;
  if (gain > 0.0) release_integral_ = momentum_ - initial_momentum_ - residual_ / gain;
}

void MomentumObserver::set_gain(double gain) { gains_.setConstant(gain); }
void MomentumObserver::set_gains(const Eigen::VectorXd& gains) { gains_ = gains; }

void MomentumObserver::reset(const Data& data, const Eigen::VectorXd& qd) {
  initial_momentum_.noalias() = data.mass_matrix.lazyProduct(qd);
  integral_.setZero();
  residual_.setZero();
  release_integral_.setZero();
  release_residual_.setZero();
  release_velocity_ = qd;
  initialised_ = true;
}

const Eigen::VectorXd& MomentumObserver::update(const Data& data, const Eigen::VectorXd& qd,
                                                const Eigen::VectorXd& tau_sensor, double dt) {
  if (!initialised_) {
    reset(data, qd);
    return residual_;
  }
  // Integrate the model's momentum rate over the last period (with last period's residual),
  // then compare with the measured momentum.
  integral_ += dt * (tau_sensor + data.coriolis_transpose_qd - data.gravity_torque + residual_);
  momentum_.noalias() = data.mass_matrix.lazyProduct(qd);  // lazy: no general gemv call at n ~ 7
  residual_ = gains_.cwiseProduct(momentum_ - initial_momentum_ - integral_);
  if (release_gain_ <= 0.0) return residual_;
  release_integral_ += dt * (tau_sensor + data.coriolis_transpose_qd - data.gravity_torque + release_residual_);
  // After missed periods gain x dt may exceed 1, and the step would overshoot (x -9 at 20 ms): at
  // most a deadbeat step, the state kept consistent with the gain for the next one.
  const double step_gain = std::min(release_gain_, 1.0 / dt);
  release_residual_ = step_gain * (momentum_ - initial_momentum_ - release_integral_);
  if (step_gain < release_gain_) release_integral_ = momentum_ - initial_momentum_ - release_residual_ / release_gain_;
  // The joint's speed over the last ~10 ms: an elastic joint's ringing (fast, tiny) is no motion.
  release_velocity_ += (dt / (kReleaseVelocityFilter_s + dt)) * (qd - release_velocity_);
  // The kick the arm would get if every push were gone and the controller still cancelled r:
  // -M^-1 r. Only where it drives a fast joint along its motion does the release path act (no fast
  // joint: no kick to compute).
  bool any_fast = false;
  for (Eigen::Index j = 0; j < residual_.size(); ++j) any_fast |= std::abs(release_velocity_[j]) > release_speed_[j];
  if (!any_fast) return residual_;
  release_kick_ = -residual_;
  data.mass_matrix_llt.solve_in_place(release_kick_);
  bool kick_along_motion = false;
  for (Eigen::Index j = 0; j < residual_.size(); ++j) {
    kick_along_motion = kick_along_motion || (std::abs(release_velocity_[j]) > release_speed_[j] &&
                                              release_kick_[j] * release_velocity_[j] > 0.0);
  }
  if (!kick_along_motion) return residual_;
  for (Eigen::Index i = 0; i < residual_.size(); ++i) {
    // Shrink r toward the fast estimate, never past zero nor beyond r itself.
    const double r = residual_[i];
    const double shrunk = r > 0.0 ? std::clamp(release_residual_[i] + release_threshold_, 0.0, r)
                                   : std::clamp(release_residual_[i] - release_threshold_, r, 0.0);
    if (shrunk != r) {
      residual_[i] = shrunk;
      integral_[i] = momentum_[i] - initial_momentum_[i] - shrunk / gains_[i];  // the observer's state follows
    }
  }
  return residual_;
}

}  // namespace phri
