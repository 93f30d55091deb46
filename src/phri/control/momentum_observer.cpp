#include <phri/control/momentum_observer.hpp>

namespace phri {

MomentumObserver::MomentumObserver(const Model& model, double gain)
    : gains_(Eigen::VectorXd::Constant(model.nv(), gain)),
      momentum_(Eigen::VectorXd::Zero(model.nv())),
      initial_momentum_(Eigen::VectorXd::Zero(model.nv())),
      integral_(Eigen::VectorXd::Zero(model.nv())),
      residual_(Eigen::VectorXd::Zero(model.nv())) {}

void MomentumObserver::set_gain(double gain) { gains_.setConstant(gain); }
void MomentumObserver::set_gains(const Eigen::VectorXd& gains) { gains_ = gains; }

void MomentumObserver::reset(const Data& data, const Eigen::VectorXd& qd) {
  initial_momentum_.noalias() = data.mass_matrix * qd;
  integral_.setZero();
  residual_.setZero();
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
  momentum_.noalias() = data.mass_matrix * qd;
  residual_ = gains_.cwiseProduct(momentum_ - initial_momentum_ - integral_);
  return residual_;
}

}  // namespace phri
