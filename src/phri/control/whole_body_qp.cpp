#include <phri/control/whole_body_qp.hpp>

#include <phri/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace phri {
namespace {
constexpr double kInf = std::numeric_limits<double>::infinity();
}

WholeBodyQp::WholeBodyQp(const Model& model, const CollisionModel* collision, const WholeBodyQpSettings& settings)
    : settings_(settings),
      collision_(collision),
      end_effector_(model, model.frame_id(settings.end_effector_frame), settings.smoothing_time_constant),
      posture_(model, settings.smoothing_time_constant),
      nv_(model.nv()),
      num_pairs_(collision ? collision->num_pairs() : 0) {
  const std::string where = "WholeBodyQpSettings";
  auto fail = [&](const std::string& key, const std::string& reason) { throw ConfigError(where, key, reason); };
  torque_limit_ = settings.torque_limit.size() ? settings.torque_limit : model.effort_limits();
  velocity_limit_ = settings.velocity_limit.size() ? settings.velocity_limit : model.velocity_limits();
  if (torque_limit_.size() != nv_) fail("torque_limit", "needs one value per joint");
  if (velocity_limit_.size() != nv_) fail("velocity_limit", "needs one value per joint");
  if (!(torque_limit_.array() > 0).all() || !torque_limit_.allFinite()) fail("torque_limit", "must be finite and > 0");
  if (!(velocity_limit_.array() > 0).all() || !velocity_limit_.allFinite()) {
    fail("velocity_limit", "must be finite and > 0 (the URDF gives none for some joint: set it)");
  }
  if (!(settings.velocity_limit_fraction > 0 && settings.velocity_limit_fraction <= 1)) fail("velocity_limit_fraction", "must be in (0, 1]");
  if (!(settings.joint_safety_fraction >= 0 && settings.joint_safety_fraction < settings.joint_influence_fraction &&
        settings.joint_influence_fraction < 0.5)) {
    fail("joint_influence_fraction", "need 0 <= joint_safety_fraction < joint_influence_fraction < 0.5");
  }
  if (!(settings.joint_damper_amortization >= 1.0)) fail("joint_damper_amortization", "must be >= 1 (overdamped)");
  const VelocityDamperSettings& c = settings.collision;
  if (!(c.safety_distance >= 0 && c.influence_distance > c.safety_distance && c.xi > 0 && c.amortization >= 1.0)) {
    fail("collision", "need 0 <= safety_distance < influence_distance, xi > 0, amortization >= 1");
  }
  if (!(settings.velocity_limit_gain > 0) || !(settings.brake_damping > 0)) fail("velocity_limit_gain", "gains must be > 0");
  velocity_limit_ *= settings.velocity_limit_fraction;
  deadband_ = settings.compliance_deadband.size() ? settings.compliance_deadband : Eigen::VectorXd::Zero(nv_);
  if (deadband_.size() != nv_ || !(deadband_.array() >= 0).all() || !deadband_.allFinite()) {
    fail("compliance_deadband", "needs one finite value >= 0 per joint");
  }

  lower_ = model.lower_limits();
  upper_ = model.upper_limits();
  influence_ = Eigen::VectorXd::Zero(nv_);
  safety_ = Eigen::VectorXd::Zero(nv_);
  lambda_ = Eigen::VectorXd::Constant(nv_, settings.velocity_limit_gain);
  safe_lower_ = Eigen::VectorXd::Constant(nv_, -kInf);
  safe_upper_ = Eigen::VectorXd::Constant(nv_, kInf);
  for (int i = 0; i < nv_; ++i) {
    if (!model.joint(i).has_position_limits()) continue;
    const double range = upper_[i] - lower_[i];
    influence_[i] = settings.joint_influence_fraction * range;
    safety_[i] = settings.joint_safety_fraction * range;
    const VelocityDamperSettings damper{influence_[i], safety_[i], velocity_limit_[i], settings.joint_damper_amortization};
    lambda_[i] = damper.lambda();
    safe_lower_[i] = lower_[i] + safety_[i];
    safe_upper_[i] = upper_[i] - safety_[i];
  }
  if (collision_) collision_data_.emplace(model, *collision_);

  // Rows: nv torque rows (A = M), then one row per collision pair. Bounds: qdd.
  problem_.resize(nv_, 0, nv_ + num_pairs_);
  solver_.resize(nv_, 0, nv_ + num_pairs_);
  qdd_external_ = Eigen::VectorXd::Zero(nv_);
  qdd_desired_ = Eigen::VectorXd::Zero(nv_);
  tau_desired_ = Eigen::VectorXd::Zero(nv_);
  last_good_tau_ = Eigen::VectorXd::Zero(nv_);
  weighted_jacobian_ = Eigen::MatrixXd::Zero(6, nv_);
}

// Acceleration bounds from the joint-limit dampers and the velocity limits (paper: qdd_d <=
// min(ë_p, ë_v) for an upper limit, >= max(...) for a lower one).
void WholeBodyQp::joint_bounds(const Eigen::VectorXd& q, const Eigen::VectorXd& qd) {
  for (int i = 0; i < nv_; ++i) {
    const double lambda = lambda_[i];
    // Velocity limits: ë_v = -lambda (ė - ė_lim) with e = q (upper) and e = -q (lower).
    double upper = -lambda * (qd[i] - velocity_limit_[i]);
    double lower = -lambda * (qd[i] + velocity_limit_[i]);
    if (std::isfinite(upper_[i])) {
      const double k = lambda * lambda / (4.0 * settings_.joint_damper_amortization * settings_.joint_damper_amortization);
      // Distance to the upper limit e = upper - q, ė = -qd: ë = -qdd >= -k (e - d_s) - lambda ė.
      upper = std::min(upper, k * (upper_[i] - q[i] - safety_[i]) - lambda * qd[i]);
      // Distance to the lower limit e = q - lower, ė = qd: qdd >= -k (e - d_s) - lambda qd.
      lower = std::max(lower, -k * (q[i] - lower_[i] - safety_[i]) - lambda * qd[i]);
    }
    if (lower > upper) lower = upper = 0.5 * (lower + upper);  // both limits bind (e.g. beyond one): split
    problem_.lb[i] = lower;
    problem_.ub[i] = upper;
  }
}

WholeBodyQpStatus WholeBodyQp::update(const Model& model, const Data& data, const Eigen::VectorXd& q,
                                     const Eigen::VectorXd& qd, const Eigen::VectorXd& tau_ext, double dt) {
  if (!q.allFinite() || !qd.allFinite() || !tau_ext.allFinite() || !data.mass_matrix.allFinite()) {
    tau_desired_ = last_good_tau_;
    status_ = WholeBodyQpStatus::kInvalidInput;
    return status_;
  }
  // qdd_ext = M^-1 tau_ext: what the push alone would do to the arm (through the dead band).
  for (int i = 0; i < nv_; ++i) {
    const double x = tau_ext[i];
    qdd_external_[i] = std::copysign(std::max(std::abs(x) - deadband_[i], 0.0), x);
  }
  data.mass_matrix_llt.solveInPlace(qdd_external_);

  end_effector_.update(model, data, qdd_external_, dt);
  posture_.update(q, qd, qdd_external_, dt);

  // Objective: 1/2 qdd' H qdd + g' qdd from the weighted least squares (factor 2 dropped).
  const double w_ee = end_effector_.weight();
  const double w_0 = posture_.weight();
  problem_.H.noalias() = w_ee * end_effector_.jacobian().transpose() * end_effector_.jacobian();
  problem_.H.diagonal().array() += w_0 + settings_.regularization;
  problem_.g.noalias() = -w_ee * end_effector_.jacobian().transpose() * end_effector_.reference();
  problem_.g.noalias() -= w_0 * posture_.reference();

  joint_bounds(q, qd);
  // Torque rows: tau_min <= M qdd + h - tau_ext <= tau_max.
  problem_.A.topRows(nv_) = data.mass_matrix;
  problem_.l.head(nv_) = -torque_limit_ - data.nonlinear_effects + tau_ext;
  problem_.u.head(nv_) = torque_limit_ - data.nonlinear_effects + tau_ext;
  // Self-collision rows, active inside the influence distance.
  if (collision_data_) {
    compute_collision_distances(model, data, *collision_, *collision_data_, true);
    const VelocityDamperSettings& c = settings_.collision;
    const double lambda = c.lambda();
    const double k = lambda * lambda / (4.0 * c.amortization * c.amortization);
    for (int p = 0; p < num_pairs_; ++p) {
      const int row = nv_ + p;
      problem_.A.row(row) = collision_data_->jacobian.row(p);
      problem_.u[row] = kInf;
      const double d = collision_data_->distance[p];
      problem_.l[row] = d < c.influence_distance
                            ? -k * (d - c.safety_distance) - lambda * collision_data_->velocity[p] - collision_data_->jdot_qdot[p]
                            : -kInf;
    }
  }

  const QpStatus qp = solver_.solve(problem_, {.warm_start = warm_, .reuse_hessian_factor = false});
  if (qp == QpStatus::kOptimal && solver_.x().allFinite()) {
    warm_ = true;
    qdd_desired_ = solver_.x();
    // tau_d = M qdd_d + h - tau_ext (the convention stated in the header).
    tau_desired_.noalias() = data.mass_matrix * qdd_desired_;
    tau_desired_ += data.nonlinear_effects - tau_ext;
    last_good_tau_ = tau_desired_;
    status_ = WholeBodyQpStatus::kOk;
    return status_;
  }
  warm_ = false;
  status_ = qp == QpStatus::kInfeasible       ? WholeBodyQpStatus::kQpInfeasible
            : qp == QpStatus::kIterationLimit ? WholeBodyQpStatus::kQpIterationLimit
                                              : WholeBodyQpStatus::kQpFailed;
  fallback_brake(data, qd, tau_ext);
  return status_;
}

// Safe fallback: a joint damping brake qdd = -D qd, clipped to the joint bounds where they allow it,
// negating the push like the constraints do, and torques clipped to their limits.
void WholeBodyQp::fallback_brake(const Data& data, const Eigen::VectorXd& qd, const Eigen::VectorXd& tau_ext) {
  for (int i = 0; i < nv_; ++i) {
    double a = -settings_.brake_damping * qd[i];
    if (problem_.lb[i] <= problem_.ub[i]) a = std::clamp(a, problem_.lb[i], problem_.ub[i]);
    qdd_desired_[i] = a;
  }
  tau_desired_.noalias() = data.mass_matrix * qdd_desired_;
  tau_desired_ += data.nonlinear_effects - tau_ext;
  tau_desired_ = tau_desired_.cwiseMax(-torque_limit_).cwiseMin(torque_limit_);
  if (!tau_desired_.allFinite()) tau_desired_ = last_good_tau_;
  last_good_tau_ = tau_desired_;
}

}  // namespace phri
