#pragma once
// Generalized-momentum residual observer (De Luca et al.): an estimate of the external joint
// torque tau_ext from the measured link-side joint torques and the model, with no acceleration.
//
//   p = M(q) qd,   dp/dt = tau_s + C^T qd - g + tau_ext
//   r(t) = K_O ( p(t) - p(0) - integral(tau_s + C^T qd - g + r) dt )    ->  dr/dt = K_O (tau_ext - r)
//
// so r follows tau_ext through a first-order low-pass of bandwidth K_O (rad/s) per joint. A high
// gain follows pushes faster but passes more torque-sensor noise and model error; the paper's
// implementation uses K_O = 10 (mc_residual_estimation, paper_parameters §4); the controller's
// default, ControllerSettings::observer_gain, is 50 (the reason is given there).
// M must be the link-side inertia (no rotor inertia): the torque sensors sit after the rotor.
#include <phri/model/data.hpp>
#include <phri/model/model.hpp>

namespace phri {

class MomentumObserver {
public:
  /// gain: K_O in rad/s for every joint.
  MomentumObserver(const Model& model, double gain);

  void set_gain(double gain);
  void set_gains(const Eigen::VectorXd& gains);
  const Eigen::VectorXd& gains() const { return gains_; }

  /// Starts from r = 0 at the current state. `data` after compute_all_terms(q, qd).
  void reset(const Data& data, const Eigen::VectorXd& qd);
  /// One control period of length dt: `data` after compute_all_terms(q, qd) and
  /// coriolis_transpose_times_velocity; tau_sensor is the measured link-side joint torque.
  /// The first call after construction resets.
  const Eigen::VectorXd& update(const Data& data, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau_sensor,
                                double dt);
  const Eigen::VectorXd& external_torque() const { return residual_; }

private:
  Eigen::VectorXd gains_;
  Eigen::VectorXd momentum_;
  Eigen::VectorXd initial_momentum_;
  Eigen::VectorXd integral_;
  Eigen::VectorXd residual_;
  bool initialised_ = false;
};

}  // namespace phri
