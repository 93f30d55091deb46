#include <phri/control/posture_task.hpp>

#include <phri/control/stiction_term.hpp>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace phri {

PostureTask::PostureTask(const Model& model, double smoothing_time_constant, std::string name, ComplianceRole role)
    : Task(std::move(name), role),
      nv_(model.nv()),
      stiffness_(Eigen::VectorXd::Zero(model.nv()), smoothing_time_constant),
      damping_(Eigen::VectorXd::Zero(model.nv()), smoothing_time_constant),
      weight_(Eigen::VectorXd::Ones(1), smoothing_time_constant),
      gamma_(Eigen::VectorXd::Zero(1), smoothing_time_constant),
      target_q_(Eigen::VectorXd::Zero(model.nv())),
      target_qd_(Eigen::VectorXd::Zero(model.nv())),
      target_qdd_(Eigen::VectorXd::Zero(model.nv())),
      offset_q_(Eigen::VectorXd::Zero(model.nv())),
      error_(Eigen::VectorXd::Zero(model.nv())),
      reference_(Eigen::VectorXd::Zero(model.nv())),
      integral_term_(Eigen::VectorXd::Zero(model.nv())) {
  for (const Joint& j : model.joints()) continuous_.push_back(j.type == JointType::kContinuous);
}

void PostureTask::set_stiffness(const Eigen::VectorXd& stiffness) { stiffness_.set_target(stiffness); }
void PostureTask::set_damping(const Eigen::VectorXd& damping) { damping_.set_target(damping); }
void PostureTask::set_integral(double gain, double limit, double zone) {
  integral_gain_ = std::max(gain, 0.0);
  integral_limit_ = std::max(limit, 0.0);
  integral_zone_ = std::max(zone, 0.0);
  integral_term_.setZero();
}
void PostureTask::set_weight(double weight) { weight_.set_target_constant(weight); }
void PostureTask::set_gamma(double gamma) { gamma_.set_target_constant(std::clamp(gamma, 0.0, 1.0)); }
void PostureTask::reset_gains(double stiffness, double damping, double weight, double gamma) {
  stiffness_.reset(Eigen::VectorXd::Constant(nv_, stiffness));
  damping_.reset(Eigen::VectorXd::Constant(nv_, damping));
  weight_.reset(Eigen::VectorXd::Constant(1, weight));
  if (!fixed_gamma_) gamma_.reset(Eigen::VectorXd::Constant(1, std::clamp(gamma, 0.0, 1.0)));
}

void PostureTask::set_fixed_gamma(double gamma) {
  fixed_gamma_ = true;
  gamma_.reset(Eigen::VectorXd::Constant(1, std::clamp(gamma, 0.0, 1.0)));
}

void PostureTask::add_objective(ObjectiveTerms& objective) const {
  const double w = weight();
  objective.hessian_diagonal.array() += w;
  objective.gradient.noalias() -= w * reference_;
}

void PostureTask::set_target(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd) {
  if (target_q_ != q) integral_term_.setZero();
  target_q_ = q;
  target_qd_ = qd;
  target_qdd_ = qdd;
}
void PostureTask::set_target(const Eigen::VectorXd& q) {
  if (target_q_ != q) integral_term_.setZero();
  target_q_ = q;
  target_qd_.setZero();
  target_qdd_.setZero();
}

void PostureTask::set_target_offset(const Eigen::VectorXd& offset) {
  offset_q_ = offset;
}

void PostureTask::update_integral(const Eigen::VectorXd& qd, double dt) {
  if (integral_gain_ <= 0.0) return;
  const double bleed = std::exp(-dt / kIntegralBleed_s);
  for (int i = 0; i < nv_; ++i) {
    const double e = error_[i];
    const bool creeping = integral_enabled_ && std::abs(qd[i]) < kCreepSpeed_rad_s &&
                          std::abs(e) < integral_zone_ && stiffness_.value()[i] > 0.0;
    integral_term_[i] = stiction_step(integral_term_[i], e, creeping, integral_gain_, integral_limit_, dt, bleed);
  }
}

void PostureTask::update(const Eigen::VectorXd& q, const Eigen::VectorXd& qd, const Eigen::VectorXd& qdd_external,
                         double dt) {
  stiffness_.step(dt);
  damping_.step(dt);
  weight_.step(dt);
  gamma_.step(dt);
  for (int i = 0; i < nv_; ++i) {
    double e = target_q_[i] + offset_q_[i] - q[i];
    // remainder(e, 2 pi) is e itself for |e| <= pi (ties round to the even quotient, 0): skip the call.
    if (continuous_[static_cast<std::size_t>(i)] && std::abs(e) > std::numbers::pi) e = std::remainder(e, 2.0 * std::numbers::pi);
    error_[i] = e;
  }
  update_integral(qd, dt);
  reference_ = target_qdd_ + stiffness_.value().cwiseProduct(error_) + damping_.value().cwiseProduct(target_qd_ - qd) +
               integral_term_ + gamma_.value()[0] * qdd_external;
}

}  // namespace phri
