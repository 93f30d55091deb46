#include <phri/control/power_force_limit.hpp>

#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace phri {

const BodyRegion& BodyRegionMap::for_link(std::string_view link) const {
  for (const auto& [name, r] : links) {
    if (name == link) return r;
  }
  return region;
}

void check_body_regions(const BodyRegionMap& map) {
  auto check = [](const BodyRegion& r) {
    if (!(r.stiffness_N_per_m > 0 && r.mass_kg > 0 && r.quasi_static_force_N > 0 && r.transient_factor >= 1 &&
          std::isfinite(r.stiffness_N_per_m + r.mass_kg + r.quasi_static_force_N + r.transient_factor))) {
      throw ConfigError("PowerForceLimitSettings", "region", "'" + r.name + "': k, m_H and F_QS must be > 0, the transient factor >= 1");
    }
  };
  check(map.region);
  for (const auto& named : map.links) check(named.second);
}

double reduced_mass(double robot_kg, double human_kg) { return 1.0 / (1.0 / human_kg + 1.0 / robot_kg); }

double permissible_speed(const BodyRegion& region, double robot_kg) {
  return region.transient_force_N() / std::sqrt(reduced_mass(robot_kg, region.mass_kg) * region.stiffness_N_per_m);
}

double reflected_mass(const Eigen::Ref<const Eigen::MatrixXd>& linear_jacobian, const SmallCholesky& inertia,
                      const Eigen::Vector3d& direction, Eigen::VectorXd& scratch, Eigen::VectorXd& solved) {
  scratch.noalias() = linear_jacobian.transpose() * direction;  // J^T u
  solved = scratch;
  inertia.solve_in_place(solved);
  const double along = scratch.dot(solved);
  return along > 0.0 ? 1.0 / along : std::numeric_limits<double>::infinity();
}

bool contact_point_figures(const Model& model, const Data& data, const SmallCholesky& inertia, int body,
                           const Eigen::Vector3d& local, const BodyRegion& region, double min_speed_m_s,
                           ContactPointState& s, Eigen::Vector3d& direction, Eigen::MatrixXd& jacobian,
                           Eigen::VectorXd& scratch, Eigen::VectorXd& solved) {
  const Eigen::Vector3d world = data.body_placements[static_cast<std::size_t>(body)] * local;
  const Eigen::Vector3d velocity = body_point_velocity(model, data, body, world);
  s.speed_m_s = velocity.norm();
  if (s.speed_m_s < min_speed_m_s) {
    s.reflected_mass_kg = s.permissible_speed_m_s = s.energy_J = 0.0;
    return false;
  }
  direction = velocity / s.speed_m_s;
  body_point_linear_jacobian(model, data, body, world, jacobian);
  s.reflected_mass_kg = reflected_mass(jacobian, inertia, direction, scratch, solved);
  s.permissible_speed_m_s = permissible_speed(region, s.reflected_mass_kg);
  s.energy_J = 0.5 * reduced_mass(s.reflected_mass_kg, region.mass_kg) * s.speed_m_s * s.speed_m_s;
  return true;
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
  check_body_regions(settings.regions);
  if (!(settings.gain > 0) || !(settings.min_speed_m_s > 0)) throw ConfigError("PowerForceLimitSettings", "gain", "must be > 0");
  if (rotor_inertia_.size() != model.nv()) throw ConfigError("PowerForceLimitSettings", "rotor_inertia", "one value per joint");
  for (const Capsule& c : capsules.capsules()) {
    if (c.body < 0) continue;  // the base does not move
    const BodyRegion& region = settings.regions.for_link(c.link);
    points_.push_back({c.body, c.p0, region});
    points_.push_back({c.body, c.p1, region});
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
    const auto row = static_cast<Eigen::Index>(i);
    l[row] = -kInf;
    Eigen::Vector3d direction;
    if (!contact_point_figures(c.model, c.data, inertia_llt_, p.body, p.local, p.region, settings_.min_speed_m_s, states_[i],
                               direction, jacobian_, scratch_, solved_)) {
      a.row(row).setZero();
      u[row] = kInf;
      continue;
    }
    // d|v|/dt = u^T (J qdd + J̇ qd): driven back to v_max at the gain's rate.
    const Eigen::Vector3d world = c.data.body_placements[static_cast<std::size_t>(p.body)] * p.local;
    a.row(row).noalias() = direction.transpose() * jacobian_;
    u[row] = settings_.gain * (states_[i].permissible_speed_m_s - states_[i].speed_m_s) -
             direction.dot(body_point_jdot_qdot(c.model, c.data, p.body, world));
  }
}

double PowerForceLimitConstraint::worst_ratio() const {
  double worst = 0.0;
  for (const ContactPointState& s : states_) worst = std::max(worst, s.ratio());
  return worst;
}

PowerForceLimitMonitor::PowerForceLimitMonitor(const Model& model, const CollisionModel& capsules,
                                               const Eigen::VectorXd& rotor_inertia, const BodyRegionMap& regions)
    : rotor_inertia_(rotor_inertia.size() ? rotor_inertia : Eigen::VectorXd::Zero(model.nv())),
      inertia_(Eigen::MatrixXd::Zero(model.nv(), model.nv())),
      inertia_llt_(model.nv()),
      jacobian_(Eigen::MatrixXd::Zero(3, model.nv())),
      scratch_(Eigen::VectorXd::Zero(model.nv())),
      solved_(Eigen::VectorXd::Zero(model.nv())) {
  check_body_regions(regions);
  if (rotor_inertia_.size() != model.nv()) throw ConfigError("PowerForceLimitMonitor", "rotor_inertia", "one value per joint");
  for (const Capsule& c : capsules.capsules()) {
    if (c.body < 0) continue;  // the base does not move
    links_.push_back({c.link, c.body, c.p0, c.p1, regions.for_link(c.link)});
  }
  states_.resize(links_.size());
}

std::vector<std::string> PowerForceLimitMonitor::monitored_links(const CollisionModel& capsules) {
  std::vector<std::string> names;
  for (const Capsule& c : capsules.capsules()) {
    if (c.body >= 0) names.push_back(c.link);
  }
  return names;
}

void PowerForceLimitMonitor::update(const Model& model, const Data& data) {
  inertia_ = data.mass_matrix;
  inertia_.diagonal() += rotor_inertia_;
  inertia_llt_.compute(inertia_);
  worst_ = links_.empty() ? -1 : 0;
  for (std::size_t i = 0; i < links_.size(); ++i) {
    const Link& link = links_[i];
    // The faster end point (speeds only), then its figures.
    const Eigen::Isometry3d& placement = data.body_placements[static_cast<std::size_t>(link.body)];
    const double v0 = body_point_velocity(model, data, link.body, placement * link.p0).norm();
    const double v1 = body_point_velocity(model, data, link.body, placement * link.p1).norm();
    Eigen::Vector3d direction;
    contact_point_figures(model, data, inertia_llt_, link.body, v1 > v0 ? link.p1 : link.p0, link.region, 1e-9, states_[i],
                          direction, jacobian_, scratch_, solved_);
    if (states_[i].ratio() > states_[static_cast<std::size_t>(worst_)].ratio()) worst_ = static_cast<int>(i);
  }
}

ContactRecorder::ContactRecorder(const Model& model, const CollisionModel& capsules, const Eigen::VectorXd& rotor_inertia,
                                 const BodyRegionMap& regions)
    : monitor_(model, capsules, rotor_inertia, regions), data_(model) {
  for (int i = 0; i < monitor_.num_links(); ++i) links_.push_back({monitor_.link_name(i), monitor_.region(i).name});
}

void ContactRecorder::record(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, double period) {
  if (q.size() != model.nq() || qd.size() != model.nv() || !q.allFinite() || !qd.allFinite()) return;
  compute_all_terms(model, data_, q, qd);
  monitor_.update(model, data_);
  for (int i = 0; i < monitor_.num_links(); ++i) {
    const ContactPointState& p = monitor_.link(i);
    ContactLinkSummary& s = links_[static_cast<std::size_t>(i)];
    if (p.ratio() > s.max_ratio) {
      s.max_ratio = p.ratio();
      s.speed_at_max_m_s = p.speed_m_s;
      s.reflected_mass_at_max_kg = p.reflected_mass_kg;
      s.permissible_speed_at_max_m_s = p.permissible_speed_m_s;
    }
    s.max_speed_m_s = std::max(s.max_speed_m_s, p.speed_m_s);
    s.max_energy_J = std::max(s.max_energy_J, p.energy_J);
    if (p.ratio() > 1.0) s.time_above_s += period;
  }
}

}  // namespace phri
