#pragma once
// The part of a push the command does not cancel yet (ours, not the paper's).
//
// tau_d = M qdd_d + h - tau_ext cancels the observer's tau_ext, which follows a push at K_O (20 ms
// at 50/s). Meanwhile the arm gets a_u = (M + B)^-1 (tau_true - tau_ext) on top of qdd_d, B being
// the rotors behind rigid gears. The QP's bounds hold the command, not the arm: a light wrist goes
// from rest past its speed limit in 5 ms that way (a UR5e's wrist under a 173 N step: 3.96 rad/s
// for a 3.14 rad/s limit, with 28 N.m available and 5.5 used).
//
// Two estimates of a_u, each fooled by a different fault:
// - the observer's fast path (MomentumObserver::fast_external_torque, ~500/s): tau_true ~ tau_fast;
//   a spike or offset on a torque sensor reads as a push;
// - the arm's motion over the last period: (qd - qd_prev) / dt - qdd_sent(prev), qdd_sent the
//   acceleration the command sent asks (the QP's, plus what the guards changed in its torque);
//   velocity noise and the torque loop's tracking error read as one.
// acceleration() takes, per joint, the motion alone where it speeds the joint up (m qd > 0): that is
// the direction that overspeeds, and where an offset on a torque sensor shows (the observer reads a
// push that is not there, the command cancels it, and the torque side, fooled too, may disagree in
// sign). Elsewhere the smaller of the two where they agree in sign, and 0 where they do not.
// WholeBodyQp's bounds and its rows on the motion hold for it. Without motion evidence (the first
// cycle, after a cycle with no QP command) it is 0.
//
// Both the motion estimate and the bound's counter-acceleration assume a command reaches the link
// within the period, as through rigid gears. Through an elastic transmission (stiffness K behind a
// rotor B) a torque step reaches the link as K (theta - q), and the link sees on average
// f = 1 - sin(x) / x of it over the period, x = sqrt(K / B) dt (rotor against a held link): on the
// Gen3's declared springs f ~ 0.07. So a_u is scaled by f: where the command cannot counter the push
// within the period, the bounds do not ask it to, and the command the drive has not delivered yet is
// not read back as a push (replayed: the drop test with the observer alone at K_O 10, whose wrist
// rang between -4 and +4 rad/s on the full shift).
#include <phri/model/data.hpp>
#include <phri/model/small_cholesky.hpp>

#include <Eigen/Core>

namespace phri {

class UncancelledPush {
public:
  /// rotor_inertia: B, the reflected rotor inertia per joint (zero where unknown); compliance: 1 / K
  /// of each transmission (empty, or 0 where rigid); period_s: the control period.
  UncancelledPush(const Eigen::VectorXd& rotor_inertia, const Eigen::VectorXd& compliance, double period_s);

  /// One cycle. data: after compute_all_terms(q, qd) (M; and M + B's factor when data.rotor_inertia
  /// is this B, which the update then reuses); tau_ext: the estimate the command cancels;
  /// tau_fast: the observer's fast estimate; qd: this sample's velocity; qdd_commanded: the
  /// acceleration the last cycle's command asked of the arm (as sent), or null when it sent none from
  /// the QP; dt: the time since that sample.
  const Eigen::VectorXd& update(const Data& data, const Eigen::VectorXd& tau_ext, const Eigen::VectorXd& tau_fast,
                                const Eigen::VectorXd& qd, const Eigen::VectorXd* qdd_commanded, double dt);
  /// No estimate this cycle (a mode without it): the next update has no motion evidence either.
  void forget();

  const Eigen::VectorXd& acceleration() const { return acceleration_; }
  /// What the arm would get if the push ended now, the command still cancelling tau_ext:
  /// f (M + B)^-1 (-tau_ext) (the last update's; 0 before one).
  const Eigen::VectorXd& release_acceleration() const { return release_; }
  /// The two estimates of the last update: (M + B)^-1 (tau_fast - tau_ext), and the motion's.
  const Eigen::VectorXd& from_torque() const { return from_torque_; }
  const Eigen::VectorXd& from_motion() const { return from_motion_; }
  /// Per joint, the share f of a command the link sees within one period (1: rigid).
  const Eigen::VectorXd& delivered_fraction() const { return delivered_; }

private:
  Eigen::VectorXd rotor_inertia_, delivered_;
  Eigen::MatrixXd inertia_;  // M + B
  SmallCholesky inertia_llt_;
  Eigen::VectorXd previous_qd_;
  bool have_previous_ = false;
  Eigen::VectorXd from_torque_, from_motion_, acceleration_, release_;
};

}  // namespace phri
