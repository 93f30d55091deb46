#pragma once
// The paper's dual-compliance evaluation on the simulated Gen3 (section "Evaluation", "Dual
// compliance", Fig. dual-compliance): the arm holds the demo posture in dual compliance with the
// custom torque loop; a hand (a scripted force on the tool, half-sine profile) guides the end
// effector to new positions and lets go, twice. Recorded every cycle: the F/T wrench norm the
// Schmitt trigger sees (touch above touch_threshold, release below release_threshold), the
// touched flag, the end effector's force, speed and position (plant truth), the joint torques'
// and velocities' norms. Per guide: where the end effector went (displacement while touched) and
// its drift after the release (how far it moves from the pose at the release over `drift_window_s`:
// the new target is that pose, so ideally 0).
#include <phri/control/controller_settings.hpp>

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

#include <Eigen/Core>

#include <phri/control/power_force_limit.hpp>

namespace phri {

struct DualComplianceOptions {
  std::string plant_config_path = "configs/plant_gen3.yaml";
  std::string urdf_path = "robots/kinova_gen3/gen3.urdf";
  std::string end_effector_frame = "end_effector_link";  ///< the URDF's frame the end of arm mounts on
  std::string actuators_path = "robots/kinova_gen3/actuators.yaml";
  std::string collision_path = "robots/kinova_gen3/collision.yaml";
  /// Body regions of the power-and-force-limiting figures (experiment_contact.hpp); empty: the
  /// iso_ts_15066_regions.yaml beside plant_config_path.
  std::string regions_file;
  std::string output_dir = "results/dual_compliance";
  std::uint64_t seed = 1;
  std::vector<double> start_q_rad = {0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57};
  double switch_s = 1.0;  ///< position control until then (F/T bias), then the custom loop
  /// The hand's guides: force on the tool (world axes) [N], start [s], duration [s] (half sine).
  /// ESTIMATE: a hand guiding a tool by ~10 cm: about a second and ~10 N, above the 8 N touch threshold.
  struct Guide {
    Eigen::Vector3d force_N;
    double start_s, duration_s;
  };
  std::vector<Guide> guides = {{Eigen::Vector3d(0.0, 12.0, 0.0), 2.5, 1.5}, {Eigen::Vector3d(0.0, 0.0, -12.0), 6.5, 1.5}};
  double drift_window_s = 2.0;
  double duration_s = 10.5;
};

struct DualComplianceGuide {
  double touch_s = -1.0, release_s = -1.0;  ///< trigger in and out (-1: never)
  double peak_wrench = 0.0;                 ///< max of the trigger's wrench norm [N, N.m]
  double displacement_mm = 0.0;             ///< end effector from touch to release
  double drift_mm = 0.0;                    ///< from the release to drift_window_s later
};

struct DualComplianceResult {
  std::vector<DualComplianceGuide> guides;
  double touch_threshold = 0.0, release_threshold = 0.0;
  std::vector<ContactLinkSummary> contact;  ///< per link, the whole run (experiment_contact.hpp)
  std::vector<std::string> files;
};

/// Runs the session; writes dual_compliance.csv (every 2 ms: t, wrench norm, touched, EE force
/// norm, joint torque norm, EE speed, joint speed norm, EE position) and dual_compliance.md.
DualComplianceResult run_dual_compliance(const DualComplianceOptions& options, std::ostream* progress = nullptr);
std::string dual_compliance_table(const DualComplianceResult& result);
int run_dual_compliance_command(const DualComplianceOptions& options, std::ostream& out);

}  // namespace phri
