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
//
// Release path: a push that ends leaves r behind for ~1/K_O, and a controller that cancels r
// goes on pushing for the human who has let go: the arm gets the kick -M^-1 r. Where that kick
// drives a fast joint along its motion, near its velocity limit it is an overspeed. A second observer of gain release_gain runs beside; while
// -M^-1 r points along the velocity of a joint faster than its release_speed (over 10 ms), each
// r_i whose fast estimate is below |r_i| by more than release_threshold drops to it at once (only
// toward zero). Otherwise r keeps its K_O low-pass: a bouncing load (the drop test) must be
// averaged, not followed down fast and up slowly (that under-estimates it: 35 mm sag, not 3).
// `data` must hold the mass matrix's Cholesky factor (compute_all_terms).
#include <phri/model/data.hpp>
#include <phri/model/model.hpp>

namespace phri {

class MomentumObserver {
public:
  /// gain: K_O in rad/s for every joint.
  MomentumObserver(const Model& model, double gain);

  void set_gain(double gain);
  /// The release path (gain 0: off), gated by joints moving faster than release_speed [rad/s].
  /// gain * dt must stay below 1 (checked by the caller's settings).
  void set_release_path(double gain, double threshold, const Eigen::VectorXd& release_speed);
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
  /// The release path's own estimate of the same tau_ext (gain release_gain: ~10x faster and
  /// noisier than r); zero while the release path is off.
  const Eigen::VectorXd& fast_external_torque() const { return release_residual_; }

private:
  Eigen::VectorXd gains_;
  Eigen::VectorXd momentum_;
  Eigen::VectorXd initial_momentum_;
  Eigen::VectorXd integral_;
  Eigen::VectorXd residual_;
  double release_gain_ = 0.0;
  double release_threshold_ = 0.0;
  Eigen::VectorXd release_speed_;
  Eigen::VectorXd release_integral_;  // the release path's own observer (gain release_gain_)
  Eigen::VectorXd release_residual_;
  Eigen::VectorXd release_velocity_;  // qd low-passed over kReleaseVelocityFilter_s
  Eigen::VectorXd release_kick_;      // -M^-1 r
  static constexpr double kReleaseVelocityFilter_s = 0.01;
  bool initialised_ = false;
};

}  // namespace phri
