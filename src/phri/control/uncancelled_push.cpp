#include <phri/control/uncancelled_push.hpp>

#include <algorithm>
#include <cmath>

namespace phri {

namespace {

// f = 1 - sin(x) / x, x = sqrt(K / B) dt: the period's mean of 1 - cos(w t), the share of a torque
// step the spring passes to a held link (header). Rigid (no compliance) or no rotor: 1.
Eigen::VectorXd delivered_fractions(const Eigen::VectorXd& rotor_inertia, const Eigen::VectorXd& compliance, double dt) {
  Eigen::VectorXd f = Eigen::VectorXd::Ones(rotor_inertia.size());
  if (compliance.size() != rotor_inertia.size()) return f;
  for (Eigen::Index i = 0; i < f.size(); ++i) {
    if (!(compliance[i] > 0.0) || !(rotor_inertia[i] > 0.0) || !(dt > 0.0)) continue;
    const double x = std::sqrt(1.0 / (compliance[i] * rotor_inertia[i])) * dt;
    f[i] = x < 1e-4 ? x * x / 6.0 : std::min(1.0, 1.0 - std::sin(x) / x);
  }
  return f;
}

}  // namespace

UncancelledPush::UncancelledPush(const Eigen::VectorXd& rotor_inertia, const Eigen::VectorXd& compliance, double period_s)
    : rotor_inertia_(rotor_inertia),
      delivered_(delivered_fractions(rotor_inertia, compliance, period_s)),
      inertia_(Eigen::MatrixXd::Zero(rotor_inertia.size(), rotor_inertia.size())),
      inertia_llt_(rotor_inertia.size()),
      previous_qd_(Eigen::VectorXd::Zero(rotor_inertia.size())),
      from_torque_(Eigen::VectorXd::Zero(rotor_inertia.size())),
      from_motion_(Eigen::VectorXd::Zero(rotor_inertia.size())),
      acceleration_(Eigen::VectorXd::Zero(rotor_inertia.size())),
      release_(Eigen::VectorXd::Zero(rotor_inertia.size())) {}

void UncancelledPush::forget() {
  have_previous_ = false;
  acceleration_.setZero();
  release_.setZero();
}

const Eigen::VectorXd& UncancelledPush::update(const Data& data, const Eigen::VectorXd& tau_ext,
                                               const Eigen::VectorXd& tau_fast, const Eigen::VectorXd& qd,
                                               const Eigen::VectorXd* qdd_commanded, double dt) {
  const bool have_motion = have_previous_ && qdd_commanded && dt > 0.0;
  have_previous_ = true;
  acceleration_.setZero();
  // M + B's factor from compute_all_terms when data carries this B (factored beside M), else here.
  const bool factored = data.rotor_inertia.size() == rotor_inertia_.size() &&
                        (data.rotor_inertia.array() == rotor_inertia_.array()).all();
  const SmallCholesky& llt = factored ? data.mass_matrix_with_rotors_llt : inertia_llt_;
  if (!factored) {
    inertia_ = data.mass_matrix;
    inertia_.diagonal() += rotor_inertia_;
    inertia_llt_.compute(inertia_);
  }
  if (have_motion) {
    from_motion_ = (qd - previous_qd_) / dt - *qdd_commanded;
    from_torque_ = tau_fast - tau_ext;
  }
  previous_qd_ = qd;
  release_.setZero();
  if (!llt.ok()) return acceleration_;
  release_ = -tau_ext;
  if (have_motion) {
    llt.solve_pair_in_place(release_, from_torque_);
  } else {
    llt.solve_in_place(release_);
  }
  release_.array() *= delivered_.array();
  if (!have_motion) return acceleration_;
  for (Eigen::Index i = 0; i < acceleration_.size(); ++i) {
    const double t = from_torque_[i], m = from_motion_[i];
    if (m * qd[i] > 0.0) {  // speeding the joint up: the motion alone (header)
      acceleration_[i] = delivered_[i] * m;
      continue;
    }
    if (t > 0.0 && m > 0.0) acceleration_[i] = delivered_[i] * std::min(t, m);
    if (t < 0.0 && m < 0.0) acceleration_[i] = delivered_[i] * std::max(t, m);
  }
  return acceleration_;
}

}  // namespace phri
