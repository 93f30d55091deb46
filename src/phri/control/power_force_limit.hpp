#pragma once
// Power and force limiting (ISO/TS 15066 Annex A.3, now ISO 10218-2:2025 Annex A): how fast a point
// of the arm may meet a body region so that a transient contact stays below the region's force.
//
// The two-body model: the arm's reflected mass along the motion u at the contact point,
//   m_u = 1 / (u^T J_v (M + I_r)^-1 J_v^T u)            (Khatib 1995; rotor inertia I_r included)
// meets the region's effective mass m_H through its spring k; reduced mass mu = (1/m_H + 1/m_u)^-1,
// energy transferred E = 1/2 mu v^2 = F^2 / (2 k), so the force stays below F where
//   v <= v_max = F / sqrt(mu k),   F = transient_factor x F_QS (the transient limit).
//
// PowerForceLimitConstraint (not in the paper; off unless configured) bounds the speed of each
// capsule's end points (a capsule's fastest point is one of them: a rigid body's point velocity is
// affine in the point) along their motion, as the velocity limit bounds the joints (paper eq.
// sec-order-vel-damp's form): u^T (J_v qdd + J̇_v qd) <= gain (v_max - |v|). Stiff like the other
// constraints: a push toward a faster motion is negated.
#include <phri/control/constraint.hpp>
#include <phri/model/collision_model.hpp>
#include <phri/model/data.hpp>

#include <Eigen/Cholesky>

#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace phri {

/// A body region of the standard's table (values: configs/iso_ts_15066_regions.yaml, its source).
struct BodyRegion {
  std::string name;
  double stiffness_N_per_m = 0.0;      ///< k
  double mass_kg = 0.0;                ///< m_H
  double quasi_static_force_N = 0.0;   ///< F_QS
  double transient_factor = 2.0;       ///< transient limit / F_QS (1 for the skull and the face)
  double transient_force_N() const { return transient_factor * quasi_static_force_N; }
};

/// Which region each link may meet: `region` for any link, `links` for the named ones (a
/// workcell's data: who works where, at which height).
struct BodyRegionMap {
  BodyRegion region;
  std::vector<std::pair<std::string, BodyRegion>> links;
  const BodyRegion& for_link(std::string_view link) const;
};

/// Throws ConfigError unless every region's k, m_H and F_QS are > 0 and finite and its transient
/// factor >= 1.
void check_body_regions(const BodyRegionMap& map);

/// mu = (1/m_H + 1/m_R)^-1.
double reduced_mass(double robot_kg, double human_kg);
/// v_max = F_T / sqrt(mu k) for a robot mass m_R meeting `region` [m/s].
double permissible_speed(const BodyRegion& region, double robot_kg);
/// m_u = 1 / (u^T J_v W J_v^T u) with W = (M + I_r)^-1 given by its Cholesky factor; `scratch` and
/// `solved` of size nv (no allocation).
double reflected_mass(const Eigen::Ref<const Eigen::MatrixXd>& linear_jacobian, const SmallCholesky& inertia,
                      const Eigen::Vector3d& direction, Eigen::VectorXd& scratch, Eigen::VectorXd& solved);

struct PowerForceLimitSettings {
  BodyRegionMap regions;      ///< the region each monitored link may meet
  double gain = 50.0;         ///< [1/s] as the velocity limit's
  double min_speed_m_s = 1e-3;  ///< below: the point's direction is undefined and its row left out
};

/// The latest cycle's figures at one monitored point.
struct ContactPointState {
  double speed_m_s = 0.0;
  double reflected_mass_kg = 0.0;
  double permissible_speed_m_s = 0.0;
  double ratio() const { return permissible_speed_m_s > 0.0 ? speed_m_s / permissible_speed_m_s : 0.0; }
  /// 1/2 mu v^2 with the region's mass [J].
  double energy_J = 0.0;
};

/// The point's figures from its velocity and, when it moves (|v| >= min_speed), its reflected mass
/// along the motion; `direction` is then v / |v| and `jacobian` its 3 x nv linear Jacobian. False
/// (figures zero) when it does not move. `inertia`: the factor of M + I_r; no allocation.
bool contact_point_figures(const Model& model, const Data& data, const SmallCholesky& inertia, int body,
                           const Eigen::Vector3d& local, const BodyRegion& region, double min_speed_m_s,
                           ContactPointState& state, Eigen::Vector3d& direction, Eigen::MatrixXd& jacobian,
                           Eigen::VectorXd& scratch, Eigen::VectorXd& solved);

class PowerForceLimitConstraint final : public Constraint {
public:
  /// rotor_inertia: reflected rotor inertia per joint (added to M's diagonal); zero: none.
  PowerForceLimitConstraint(const Model& model, const CollisionModel& capsules, const Eigen::VectorXd& rotor_inertia,
                            const PowerForceLimitSettings& settings);

  std::string_view type() const override { return "power_force_limit"; }
  int num_rows() const override { return static_cast<int>(points_.size()); }
  void fill_rows(const ConstraintContext& context, Eigen::Ref<Eigen::MatrixXd> a, Eigen::Ref<Eigen::VectorXd> l,
                 Eigen::Ref<Eigen::VectorXd> u) override;

  /// Two points per capsule: its end points, in capsule order.
  const std::vector<ContactPointState>& points() const { return states_; }
  /// The largest v / v_max of the last cycle.
  double worst_ratio() const;
  const PowerForceLimitSettings& settings() const { return settings_; }

private:
  struct Point {
    int body;
    Eigen::Vector3d local;
    BodyRegion region;
  };
  PowerForceLimitSettings settings_;
  std::vector<Point> points_;
  std::vector<ContactPointState> states_;
  Eigen::VectorXd rotor_inertia_;
  Eigen::MatrixXd inertia_;        // M + I_r
  SmallCholesky inertia_llt_;
  Eigen::MatrixXd jacobian_;       // 3 x nv
  Eigen::VectorXd scratch_, solved_;
};

/// The same figures on every link with a capsule, each cycle, for the run's log and summary
/// (changes nothing the arm does; the constraint above is what enforces them). A link's figures
/// are those of its faster capsule end point (a rigid body's fastest point of a segment is an end).
class PowerForceLimitMonitor {
public:
  /// rotor_inertia: as the constraint's. Throws ConfigError on a region out of range.
  PowerForceLimitMonitor(const Model& model, const CollisionModel& capsules, const Eigen::VectorXd& rotor_inertia,
                         const BodyRegionMap& regions);

  /// The links it monitors, in index order: those with a capsule, but the base's (it does not move).
  static std::vector<std::string> monitored_links(const CollisionModel& capsules);

  /// data: after compute_all_terms (placements, velocities, M) of the state to judge. No allocation.
  void update(const Model& model, const Data& data);

  int num_links() const { return static_cast<int>(links_.size()); }
  const std::string& link_name(int i) const { return links_[static_cast<std::size_t>(i)].name; }
  const BodyRegion& region(int i) const { return links_[static_cast<std::size_t>(i)].region; }
  const ContactPointState& link(int i) const { return states_[static_cast<std::size_t>(i)]; }
  /// The link with the largest v / v_max this cycle (-1 before the first update or with no link).
  int worst_link() const { return worst_; }

private:
  struct Link {
    std::string name;
    int body;
    Eigen::Vector3d p0, p1;
    BodyRegion region;
  };
  std::vector<Link> links_;
  std::vector<ContactPointState> states_;
  int worst_ = -1;
  Eigen::VectorXd rotor_inertia_;
  Eigen::MatrixXd inertia_;
  SmallCholesky inertia_llt_;
  Eigen::MatrixXd jacobian_;
  Eigen::VectorXd scratch_, solved_;
};

/// One link's power-and-force-limiting figures over a run (ISO/TS 15066 transient contact).
struct ContactLinkSummary {
  std::string link, region;
  double max_ratio = 0.0;                 ///< largest v / v_max
  double speed_at_max_m_s = 0.0;          ///< the speed, reflected mass and v_max of that cycle
  double reflected_mass_at_max_kg = 0.0;
  double permissible_speed_at_max_m_s = 0.0;
  double max_speed_m_s = 0.0;
  double max_energy_J = 0.0;              ///< largest 1/2 mu v^2
  double time_above_s = 0.0;              ///< time with v / v_max > 1
};

/// A run's per-link maxima of the monitor's figures, state after state (phri run's summary, the
/// experiments' reports).
class ContactRecorder {
public:
  /// As PowerForceLimitMonitor's.
  ContactRecorder(const Model& model, const CollisionModel& capsules, const Eigen::VectorXd& rotor_inertia,
                  const BodyRegionMap& regions);
  /// The figures of the state (q, qd), which lasted `period` [s]; a state of the wrong size or not
  /// finite is skipped. No allocation.
  void record(const Model& model, const Eigen::VectorXd& q, const Eigen::VectorXd& qd, double period);
  const PowerForceLimitMonitor& monitor() const { return monitor_; }
  const std::vector<ContactLinkSummary>& links() const { return links_; }

private:
  PowerForceLimitMonitor monitor_;
  Data data_;
  std::vector<ContactLinkSummary> links_;
};

}  // namespace phri
