#include <phri/control/power_force_limit.hpp>

#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace phri {

double reduced_mass(double robot_kg, double human_kg) { return 1.0 / (1.0 / human_kg + 1.0 / robot_kg); }

double permissible_speed(const BodyRegion& region, double robot_kg) {
  return region.transient_force_N() / std::sqrt(reduced_mass(robot_kg, region.mass_kg) * region.stiffness_N_per_m);
}

double reflected_mass(const Eigen::Ref<const Eigen::MatrixXd>& linear_jacobian, const Eigen::LLT<Eigen::MatrixXd>& inertia,
                      const Eigen::Vector3d& direction, Eigen::VectorXd& scratch, Eigen::VectorXd& solved) {
  scratch.noalias() = linear_jacobian.transpose() * direction;  // J^T u
  solved = scratch;
  inertia.solveInPlace(solved);
  const double along = scratch.dot(solved);
  return along > 0.0 ? 1.0 / along : std::numeric_limits<double>::infinity();
}

PowerForceLimitConstraint::PowerForceLimitConstraint(const Model& model, const CollisionModel& capsules,
                                                     const Eigen::VectorXd& rotor_inertia,
                                                     const PowerForceLimitSettings& settings)
    : settings_(settings),
      rotor_inertia_(rotor_inertia.size() ? rotor_inertia : Eigen::VectorXd::Zero(model.nv())),
      inertia_(Eigen::MatrixXd::Zero(model.nv(), model.nv())),
      inertia_llt_(model.nv()),
      jacobian_(Eigen::MatrixXd::Zero(3, model.nv())),
      scratch_(Eigen::VectorXd::Zero(model.nv())),
      solved_(Eigen::VectorXd::Zero(model.nv())) {
  const BodyRegion& r = settings.region;
  if (!(r.stiffness_N_per_m > 0 && r.mass_kg > 0 && r.quasi_static_force_N > 0 && r.transient_factor >= 1 &&
        std::isfinite(r.stiffness_N_per_m + r.mass_kg + r.quasi_static_force_N + r.transient_factor))) {
    throw ConfigError("PowerForceLimitSettings", "region", "'" + r.name + "': k, m_H and F_QS must be > 0, the transient factor >= 1");
  }
  if (!(settings.gain > 0) || !(settings.min_speed_m_s > 0)) throw ConfigError("PowerForceLimitSettings", "gain", "must be > 0");
  if (rotor_inertia_.size() != model.nv()) throw ConfigError("PowerForceLimitSettings", "rotor_inertia", "one value per joint");
  for (const Capsule& c : capsules.capsules()) {
    if (c.body < 0) continue;  // the base does not move
    points_.push_back({c.body, c.p0});
    points_.push_back({c.body, c.p1});
  }
  states_.resize(points_.size());
}

void PowerForceLimitConstraint::fill_rows(const ConstraintContext& c, Eigen::Ref<Eigen::MatrixXd> a,
                                          Eigen::Ref<Eigen::VectorXd> l, Eigen::Ref<Eigen::VectorXd> u) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  inertia_ = c.data.mass_matrix;
  inertia_.diagonal() += rotor_inertia_;
  inertia_llt_.compute(inertia_);
  for (std::size_t i = 0; i < points_.size(); ++i) {
    const Point& p = points_[i];
    const Eigen::Vector3d world = c.data.body_placements[static_cast<std::size_t>(p.body)] * p.local;
    const Eigen::Vector3d velocity = body_point_velocity(c.model, c.data, p.body, world);
    ContactPointState& s = states_[i];
    s.speed_m_s = velocity.norm();
    const auto row = static_cast<Eigen::Index>(i);
    l[row] = -kInf;
    if (s.speed_m_s < settings_.min_speed_m_s) {
      a.row(row).setZero();
      u[row] = kInf;
      s.reflected_mass_kg = s.permissible_speed_m_s = s.energy_J = 0.0;
      continue;
    }
    const Eigen::Vector3d direction = velocity / s.speed_m_s;
    body_point_linear_jacobian(c.model, c.data, p.body, world, jacobian_);
    s.reflected_mass_kg = reflected_mass(jacobian_, inertia_llt_, direction, scratch_, solved_);
    s.permissible_speed_m_s = permissible_speed(settings_.region, s.reflected_mass_kg);
    s.energy_J = 0.5 * reduced_mass(s.reflected_mass_kg, settings_.region.mass_kg) * s.speed_m_s * s.speed_m_s;
    // d|v|/dt = u^T (J qdd + J̇ qd): driven back to v_max at the gain's rate.
    a.row(row).noalias() = direction.transpose() * jacobian_;
    u[row] = settings_.gain * (s.permissible_speed_m_s - s.speed_m_s) -
             direction.dot(body_point_jdot_qdot(c.model, c.data, p.body, world));
  }
}

double PowerForceLimitConstraint::worst_ratio() const {
  double worst = 0.0;
  for (const ContactPointState& s : states_) worst = std::max(worst, s.ratio());
  return worst;
}

}  // namespace phri
