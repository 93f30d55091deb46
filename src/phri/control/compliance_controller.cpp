#include <phri/control/compliance_controller.hpp>

#include <phri/core/error.hpp>

#include <algorithm>
#include <cmath>

namespace phri {

ComplianceController::ComplianceController(const ComplianceSettings& settings)
    : settings_(settings), posture_stiffness_(settings.posture_stiffness) {
  auto fail = [](const std::string& key, const std::string& reason) { throw ConfigError("ComplianceSettings", key, reason); };
  if (!(settings.release_threshold >= 0 && settings.release_threshold < settings.touch_threshold)) {
    fail("release_threshold", "need 0 <= release_threshold < touch_threshold");
  }
  for (double v : {settings.ee_position_stiffness, settings.ee_orientation_stiffness, settings.ee_weight,
                   settings.full_body_ee_stiffness, settings.posture_stiffness, settings.posture_damping,
                   settings.posture_weight, settings.touched_ee_damping, settings.touched_posture_damping,
                   settings.posture_integral_gain, settings.posture_integral_limit, settings.posture_integral_zone,
                   settings.ee_integral.gain, settings.ee_integral.linear_limit, settings.ee_integral.angular_limit,
                   settings.ee_integral.linear_zone, settings.ee_integral.angular_zone}) {
    if (!(v >= 0) || !std::isfinite(v)) fail("gains", "stiffness, damping and weights must be finite and >= 0");
  }
  if (settings.ee_axis_stiffness &&
      (!settings.ee_axis_stiffness->allFinite() || (settings.ee_axis_stiffness->array() < 0.0).any())) {
    fail("ee_axis_stiffness", "must be finite and >= 0 on every axis");
  }
  if (!(settings.posture_weight > 0)) fail("posture_weight", "must be > 0 (it keeps the QP strictly convex)");
}

void ComplianceController::apply(WholeBodyQp& qp) {
  EndEffectorTask& ee = qp.end_effector();
  PostureTask& posture = qp.posture();
  const bool ee_free = mode_ == ComplianceMode::kDual && touched_;
  const double mode_gamma_ee = (mode_ == ComplianceMode::kFullBody || ee_free) ? 1.0 : 0.0;
  const double mode_gamma_posture = mode_ == ComplianceMode::kStiff ? 0.0 : 1.0;
  const double gamma_ee = ee_gamma_override_ >= 0.0 ? ee_gamma_override_ : mode_gamma_ee;
  const double gamma_posture = posture_gamma_override_ >= 0.0 ? posture_gamma_override_ : mode_gamma_posture;
  Vector6d stiffness;
  if (ee_free) {
    stiffness.setZero();
  } else if (settings_.ee_axis_stiffness) {
    stiffness = *settings_.ee_axis_stiffness * stiffness_scale_;
  } else if (mode_ == ComplianceMode::kFullBody) {
    stiffness.setConstant(settings_.full_body_ee_stiffness * stiffness_scale_);
  } else {
    stiffness << Eigen::Vector3d::Constant(settings_.ee_position_stiffness * stiffness_scale_),
        Eigen::Vector3d::Constant(settings_.ee_orientation_stiffness * stiffness_scale_);
  }
  ee.set_stiffness(stiffness);
  if (ee_free) {
    ee.set_damping(Vector6d::Constant(settings_.touched_ee_damping));
  } else if ((stiffness.array() > 0.0).all()) {
    ee.set_critical_damping();
  } else {
    // An axis without a spring (per-axis compliance): the hand-guiding damping along it.
    const Vector6d damping =
        (stiffness.array() > 0.0).select(2.0 * stiffness.cwiseSqrt(), Vector6d::Constant(settings_.touched_ee_damping));
    ee.set_damping(damping);
  }
  ee.set_weight(settings_.ee_weight);
  posture.set_stiffness(posture_stiffness_);
  posture.set_damping(ee_free ? settings_.touched_posture_damping : settings_.posture_damping);
  posture.set_weight(settings_.posture_weight);
  // Gamma per role: every task with the main role or the null-space role, not only these two.
  for (const auto& task : qp.tasks()) {
    if (task->role() == ComplianceRole::kMain) task->set_role_gamma(gamma_ee);
    if (task->role() == ComplianceRole::kNullSpace) task->set_role_gamma(gamma_posture);
  }
}

void ComplianceController::initialise(ComplianceMode mode, WholeBodyQp& qp, const Data& data) {
  mode_ = mode;
  touched_ = false;
  apply(qp);
  // Start at the set values rather than filtering from zero.
  EndEffectorTask& ee = qp.end_effector();
  ee.reset_gains(ee.stiffness_target(), ee.damping_target(), settings_.ee_weight,
                 Vector6d::Constant(mode == ComplianceMode::kFullBody ? 1.0 : 0.0));
  qp.posture().reset_gains(settings_.posture_stiffness, settings_.posture_damping, settings_.posture_weight,
                           mode == ComplianceMode::kStiff ? 0.0 : 1.0);
  qp.posture().set_integral(settings_.posture_integral_gain, settings_.posture_integral_limit,
                            settings_.posture_integral_zone);
  ee.set_integral(settings_.ee_integral);
  ee.hold_current_pose(data);
}

void ComplianceController::set_mode(ComplianceMode mode, WholeBodyQp& qp, const Data& data) {
  if (mode == mode_) return;
  if (touched_) qp.end_effector().hold_current_pose(data);
  mode_ = mode;
  touched_ = false;
  apply(qp);
}

void ComplianceController::set_stiffness_scale(double scale, WholeBodyQp& qp) {
  stiffness_scale_ = clamped_stiffness_scale(scale);
  apply(qp);
}

void ComplianceController::set_live_gains(std::optional<double> ee_gamma, std::optional<double> posture_gamma,
                                          std::optional<double> posture_stiffness, WholeBodyQp& qp) {
  // A gamma outside [0, 1] is not a partial compliance: negative ends the override, above 1 is 1.
  auto gamma = [](double g) { return g < 0.0 ? -1.0 : std::min(g, 1.0); };
  if (ee_gamma && std::isfinite(*ee_gamma)) ee_gamma_override_ = gamma(*ee_gamma);
  if (posture_gamma && std::isfinite(*posture_gamma)) posture_gamma_override_ = gamma(*posture_gamma);
  if (posture_stiffness && std::isfinite(*posture_stiffness)) {
    posture_stiffness_ = std::clamp(*posture_stiffness, 0.0, kMaxPostureStiffness);
  }
  apply(qp);
}

bool ComplianceController::update(double wrench_norm, WholeBodyQp& qp, const Data& data) {
  if (mode_ != ComplianceMode::kDual) return false;
  if (!std::isfinite(wrench_norm)) return false;  // a bad sample changes nothing
  if (!touched_ && wrench_norm >= settings_.touch_threshold) {
    // The spring fades out through the gain filter (the target stays put, so nothing steps).
    touched_ = true;
    ++touch_count_;
    apply(qp);
  } else if (touched_ && wrench_norm < settings_.release_threshold) {
    // The pose at release is the new target; the spring, faded by now, grows back from zero.
    touched_ = false;
    qp.end_effector().hold_current_pose(data);
    apply(qp);
    return true;
  }
  return false;
}

}  // namespace phri
