#pragma once
// ISO 9283 pose accuracy and repeatability (section 7.2 of the standard) on the simulated Gen3,
// for each low-level loop: the paper's central claim (torque control as precise as position
// control) measured with the standard's own metric.
//
// The test cube is centred on the end-effector target at the start posture (the controller's
// kinematics, as a programmed pose is); its diagonal plane through
// corners C1 C2 C7 C8 carries the five poses: P1 at the centre, P2..P5 on the plane's diagonals at
// 10 % of their length from the corners (P = C + 0.8 (corner - C)). The orientation is the start
// orientation at every pose. n cycles P1 -> P5 -> P4 -> P3 -> P2 -> P1, each a minimum-jerk
// straight line (so each pose is always approached from the same side, as the standard asks),
// then a dwell. The attained position is the true end effector (forward kinematics of the
// simulator's link-side joint angles) averaged over the dwell's last 100 ms, as an instrument
// averages; its orientation the last sample's:
//
//   AP = || mean_j(P_j) - P_c ||,   RP = l_mean + 3 S_l,  l_j = || P_j - mean(P) ||
//   orientation: AP_a = |mean_j(a_j) - a_c| per world axis (rotation vector of R_j R_c^T), RP_a = 3 S_a
//
// with the stabilisation time (from the end of the move until the position, through the
// instrument's 20 ms mean, stays within a band of the attained one; for a tight and a coarse
// band) and the overshoot (the largest excursion past the attained position along the approach
// direction after the move's end). An arrival still outside a band in the last tenth of its
// dwell did not stabilise and is counted; a loop whose run did not stay in that loop with every
// cycle ok (no fallback, no safe stop) is reported invalid, not as a result.
#include <phri/control/power_force_limit.hpp>
#include <phri/robot/low_level_mode.hpp>

#include <Eigen/Core>

#include <array>
#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace phri {

struct Iso9283Options {
  std::string plant_config_path = "configs/plant_gen3.yaml";
  std::string urdf_path = "robots/kinova_gen3/gen3.urdf";
  std::string end_effector_frame = "end_effector_link";
  std::string actuators_path = "robots/kinova_gen3/actuators.yaml";
  std::string collision_path = "robots/kinova_gen3/collision.yaml";
  /// Body regions of the power-and-force-limiting figures (experiment_contact.hpp); empty: the
  /// iso_ts_15066_regions.yaml beside plant_config_path.
  std::string regions_file;
  std::string output_dir = "results/iso9283";
  std::string figure_script = "tools/report/iso9283_figure.py";  ///< empty: no figure
  std::uint64_t seed = 1;
  std::vector<double> start_q_rad = {0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57};  ///< the demo's home [DEMO 1.4]
  std::vector<LowLevelMode> loops = {LowLevelMode::kPosition, LowLevelMode::kCurrent,
                                     LowLevelMode::kKinovaTorqueHighVelocity, LowLevelMode::kKinovaTorque};
  int cycles = 30;              ///< the standard's n
  double cube_side_m = 0.2;     ///< [OURS] within the Gen3's reach around the demo's home posture
  double max_speed_m_s = 0.25;  ///< peak speed of the moves [OURS: ISO 10218-1's 250 mm/s of a collaborative arm]
  double dwell_s = 1.5;         ///< after each move, before the pose is taken
  /// Stabilisation bands, tight and coarse [OURS: the standard leaves the band to the maker; the
  /// tight one is the order of the repeatability cobot makers state, the coarse one 10x it].
  std::array<double, 2> bands_mm = {0.1, 1.0};
  double switch_s = 1.0;        ///< position loop until then (F/T bias), then the loop under test
  double settle_s = 1.0;        ///< after the switch, before the first move
  int jobs = 2;                 ///< loops run on this many threads
};

/// One arrival at a pose.
struct Iso9283Arrival {
  int pose = 0;  ///< 0..4 for P1..P5
  Eigen::Vector3d attained_m = Eigen::Vector3d::Zero();  ///< mean of the dwell's last 100 ms (world)
  Eigen::Vector3d position_error_m = Eigen::Vector3d::Zero();     ///< attained - commanded (world)
  Eigen::Vector3d orientation_error_rad = Eigen::Vector3d::Zero();  ///< rotation vector of R R_c^T (world)
  std::array<double, 2> stabilisation_s = {0.0, 0.0};  ///< per band
  double overshoot_mm = 0.0;
  std::array<bool, 2> settled = {true, true};  ///< per band
};

/// The standard's figures at one pose.
struct Iso9283Pose {
  double ap_mm = 0.0, rp_mm = 0.0;
  Eigen::Vector3d ap_deg = Eigen::Vector3d::Zero(), rp_deg = Eigen::Vector3d::Zero();  ///< about world x, y, z
  std::array<double, 2> stabilisation_median_s = {0.0, 0.0}, stabilisation_max_s = {0.0, 0.0};  ///< per band
  double overshoot_max_mm = 0.0;
  int arrivals = 0;
  std::array<int, 2> unsettled = {0, 0};  ///< per band
};

struct Iso9283Loop {
  LowLevelMode loop = LowLevelMode::kPosition;
  bool valid = false;
  std::string invalid_reason;  ///< why the run does not count (empty when valid)
  std::vector<Iso9283Pose> poses;  ///< P1..P5
  std::vector<Iso9283Arrival> arrivals;
  std::vector<ContactLinkSummary> contact;  ///< per link, the measured cycles (experiment_contact.hpp)
};

struct Iso9283Result {
  std::vector<Iso9283Loop> loops;
  std::vector<Eigen::Vector3d> commanded;  ///< P1..P5 (world) [m]
  Iso9283Options options;
  std::vector<std::string> files;
};

/// The five poses of the cube (side `side`, centred at `centre`) in the standard's order P1..P5.
std::vector<Eigen::Vector3d> iso9283_cube_poses(const Eigen::Vector3d& centre, double side);
/// AP, RP and the orientation figures of one pose from its arrivals (all at that pose).
Iso9283Pose iso9283_pose_figures(const std::vector<Iso9283Arrival>& arrivals);

Iso9283Result run_iso9283(const Iso9283Options& options, std::ostream* progress = nullptr);
/// The markdown table and the conclusion computed from it.
std::string iso9283_table(const Iso9283Result& result);
int run_iso9283_command(const Iso9283Options& options, std::ostream& out);

}  // namespace phri
