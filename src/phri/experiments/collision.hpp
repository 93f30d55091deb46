#pragma once
// The simulated collision test (ISO/TS 15066 power and force limiting, measured as the standard's
// devices measure it): the arm's tool hits a body region, a mass m_H behind a spring k
// (sim/body_region_surrogate.hpp, k and m_H from the regions file), placed on its path
//
//   * point to point: a minimum-jerk straight line of path_length_m along `direction` (world),
//     the face at its middle, where the speed peaks at the nominal speed; the goal lies behind the
//     face (a programmed path that did not know a person was there);
//   * dynamic: the paper's dynamic scenario (trajectory/dynamic_trajectory.hpp), the face where
//     the reference's speed peaks in the first period after the ramp, square to that motion;
//
// free (transient contact: the body recoils) or backed by a wall (clamping: quasi-static), in each
// compliance mode and low-level loop, with and without the power-and-force-limiting constraint
// (control/power_force_limit.hpp, the region for every link). Measured on the simulator's truth:
// the tool's speed along the motion when it touches, the peak force (the largest over the physics
// steps), the clamping force (mean of the window's last quasi_static_window_s), the time above the
// region's limit and the contact's duration; the reaction (a safe stop, the dual mode's release)
// is part of what is measured. A run that did not stay in its mode and loop with every cycle ok
// until the touch, or never touched, is reported invalid, not as a result.
#include <phri/control/compliance_mode.hpp>
#include <phri/control/power_force_limit.hpp>
#include <phri/robot/low_level_mode.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace phri {

enum class CollisionMotion { kPointToPoint, kDynamic };
constexpr const char* to_string(CollisionMotion m) { return m == CollisionMotion::kPointToPoint ? "point_to_point" : "dynamic"; }

struct CollisionOptions {
  std::string plant_config_path = "configs/plant_gen3.yaml";
  std::string urdf_path = "robots/kinova_gen3/gen3.urdf";
  std::string end_effector_frame = "end_effector_link";
  std::string actuators_path = "robots/kinova_gen3/actuators.yaml";
  std::string collision_path = "robots/kinova_gen3/collision.yaml";
  std::string regions_file = "configs/iso_ts_15066_regions.yaml";
  std::string output_dir = "results/collision";
  std::string figure_script = "tools/report/collision_figure.py";  ///< empty: no figure
  std::uint64_t seed = 1;
  std::vector<double> start_q_rad = {0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57};  ///< the demo's home [DEMO 1.4]
  /// Regions met, by name in regions_file: a hand (the demo's region for its tool) and the face,
  /// the strictest (no transient allowance), where the constraint must act at a cobot's speeds.
  std::vector<std::string> regions = {"hand_fingers", "face"};
  std::vector<double> speeds_m_s = {0.25, 0.5, 1.0};  ///< point to point, peak [OURS: ISO 10218's 250 mm/s to 4x it]
  bool dynamic = true;                                ///< also the dynamic scenario
  std::vector<ComplianceMode> modes = {ComplianceMode::kNullSpace, ComplianceMode::kFullBody, ComplianceMode::kDual};
  std::vector<LowLevelMode> loops = {LowLevelMode::kPosition, LowLevelMode::kCurrent, LowLevelMode::kKinovaTorqueHighVelocity};
  double path_length_m = 0.3;  ///< point to point [OURS]
  Eigen::Vector3d direction = -Eigen::Vector3d::UnitY();  ///< point to point, world: sideways, as the dynamic scenario's sweep
  double contact_window_s = 1.0;        ///< measured after the first touch
  double quasi_static_window_s = 0.2;   ///< the clamping force: mean over the window's last this long
  double switch_s = 1.0;                ///< position loop until then (F/T bias), then the loop under test
  double settle_s = 0.5;                ///< after the switch, before the motion
  int jobs = 2;
};

/// One collision: what was run and what it measured.
struct CollisionRun {
  BodyRegion region;
  CollisionMotion motion = CollisionMotion::kPointToPoint;
  double nominal_speed_m_s = 0.0;  ///< point to point: the move's peak; dynamic: the reference's at the face
  bool clamped = false;
  ComplianceMode mode = ComplianceMode::kNullSpace;
  LowLevelMode loop = LowLevelMode::kPosition;
  bool constraint = false;

  bool valid = false;
  std::string invalid_reason;
  double contact_time_s = 0.0;            ///< first touch (run time)
  double approach_speed_m_s = 0.0;        ///< the tool's true speed into the face at the first touch
  double reflected_mass_kg = 0.0;         ///< the tool's, along its motion, at the first touch (true state)
  double permissible_speed_m_s = 0.0;     ///< v_max for that mass and the region
  double peak_force_N = 0.0;
  double peak_after_s = 0.0;              ///< from the first touch
  double quasi_static_force_N = 0.0;      ///< clamped: the force at the window's end (mean of its last part)
  double time_above_limit_s = 0.0;        ///< above the transient limit (free) or F_QS (clamped)
  double contact_duration_s = 0.0;        ///< force > 0, within the window
  double max_tool_ratio = 0.0;            ///< the tool's largest v / v_max before the touch (true state)
  std::string reaction;                   ///< what the controller did after the touch
  std::vector<double> link_max_ratio;     ///< per monitored link, before the touch (CollisionResult::links)

  /// The limit its peak is judged against: the transient one free, F_QS clamped.
  double limit_N() const { return clamped ? region.quasi_static_force_N : region.transient_force_N(); }
};

struct CollisionResult {
  std::vector<CollisionRun> runs;
  std::vector<std::string> links;  ///< the monitored links, in link_max_ratio's order
  CollisionOptions options;
  std::vector<std::string> files;
};

/// The options' regions from their file; ConfigError on an unknown region or an option out of range.
std::vector<BodyRegion> collision_regions(const CollisionOptions& options);
CollisionResult run_collision(const CollisionOptions& options, std::ostream* progress = nullptr);
/// The markdown tables and the conclusions computed from them.
std::string collision_table(const CollisionResult& result);
/// Exit status 0 when every run was valid.
int run_collision_command(const CollisionOptions& options, std::ostream& out);

}  // namespace phri
