#pragma once
// Torque-tracking experiment on the simulated Gen3, as in the paper (section "Evaluation",
// "Torque tracking", Fig. torque-control-results): the norm of the joint torque tracking error
// ||tau_d - tau_s|| over time, for the custom low-level torque loop (LowLevelMode::kCurrent) and
// Kinova's "high-velocity" torque loop (the plant's emulation, LowLevelMode::kKinovaTorqueHighVelocity),
// in two scenarios:
//
// * static: the arm partially extended horizontally (the paper demo's posture target by default),
//   a weight at the end effector (in the plant only: the controller's model keeps its nominal
//   tool, so the weight is an external load the momentum observer estimates and the inverse
//   dynamics compensates), the end-effector task non-compliant (ComplianceMode::kStiff); the arm
//   holds in position control, then the loop under test takes over;
// * dynamic: a 6-D Cartesian task moving back and forth in the y-z plane, the paper demo's "Sin"
//   state: z = z0 + 0.1 sin(3 t), y a triangle at 0.1 m/s between y0 - 0.4 and y0 + 0.05 m
//   (numbers from the authors' demo code, see torque_tracking.cpp), x and orientation held;
//   posture compliant, end effector stiff (ComplianceMode::kNullSpace, as in the demo's state).
//
// The error of cycle k pairs the QP's desired torque tau_d[k] (the set-point both loops track)
// with the torque sensors' reading at the end of the period that command was in force, tau_s[k+1].
// "measured" uses the sensors as a real arm reports them (noise 0.05 N.m per joint, zero offsets);
// "true" uses the plant's noise-free transmitted torque. Statistics (RMS, 95th percentile, max of
// the norm) are taken from `transient_s` after the switch to the loop under test to the end.
//
// Each run builds a fresh plant (same seed: same noise and mismatch) and a fresh Controller, from
// the model, actuator table and collision model loaded once from the options' files. A run in which
// the supervisor safe-stopped, the QP fell back or another loop ran after the switch is marked
// invalid (RunValidity), in the table and the summary CSV. With `elastic`, each run also records
// the plant's computed two-mass modes at its final posture (elastic_modes.hpp), the figure the
// report sets beside the ringing it measures in the run's log.
//
// What to expect from the static scenario in this framework: the inverse dynamics subtracts the
// momentum observer's tau_ext, which at rest converges to g - tau_s, so tau_d = M qdd_d + tau_s
// (low-passed) whatever low-level loop runs. An arm that stays at rest therefore has a torque
// error made of sensor and controller noise only, with either loop (with the plant's sensor noise
// switched off it is exactly zero for both); the loops differ only once the arm moves, and then
// through friction: Kinova's loop leaves it uncompensated, the custom loop pre-compensates it.
// What makes a resting arm move is a static torque error larger than the joints' static friction,
// e.g. a drive whose true K_T G_r is off the value the controllers convert with (plant
// mismatch.torque_constant_fraction, --torque-constant-error); torque_tracking_sweep.hpp works this
// out and measures it (`phri experiment torque-tracking --static-sweep`).
// In the dynamic scenario the custom loop's residual error is dominated by its friction model's
// switching: a joint sliding slower than the velocity threshold gets static sign(qdd_d) or nothing
// depending on whether |qdd_d| crosses the acceleration threshold, which noise makes chatter
// (friction_velocity_threshold_rad_s lets a run try other thresholds).
#include <phri/control/controller_settings.hpp>
#include <phri/control/compliance_mode.hpp>
#include <phri/lowlevel/custom_torque_controller.hpp>
#include <phri/lowlevel/low_level_controller.hpp>
#include <phri/experiments/elastic_modes.hpp>
#include <phri/experiments/run_validity.hpp>

#include <cstdint>
#include <iosfwd>
#include <optional>
#include <string>
#include <vector>

namespace phri {

enum class TrackingScenario { kStatic, kDynamic };

/// How the static scenario's weight is attached in the plant.
enum class PayloadMode {
  kToolMass,           ///< added to the tool's mass from the start (held in position control first)
  kHungAfterSwitch,    ///< a downward force of m g on the tool, ramped in after the switch, as
                       ///< when a weight is hung on an arm already in torque control
};

constexpr const char* to_string(TrackingScenario s) { return s == TrackingScenario::kStatic ? "static" : "dynamic"; }

struct TorqueTrackingOptions {
  // ---- files (relative paths are relative to the working directory)
  std::string plant_config_path = "configs/plant_gen3.yaml";
  std::string urdf_path = "robots/kinova_gen3/gen3.urdf";
  std::string end_effector_frame = "end_effector_link";  ///< the URDF's frame the end of arm mounts on
  std::string actuators_path = "robots/kinova_gen3/actuators.yaml";
  std::string collision_path = "robots/kinova_gen3/collision.yaml";
  /// Body regions of the power-and-force-limiting figures (experiment_contact.hpp); empty: the
  /// iso_ts_15066_regions.yaml beside plant_config_path.
  std::string regions_file;
  /// CSV and markdown go here (created when missing); empty: no files.
  std::string output_dir = "results/torque_tracking";
  /// Figure script run by the command; empty: no figure.
  std::string figure_script = "tools/report/torque_tracking_figure.py";

  // ---- plant
  std::uint64_t seed = 1;              ///< sensor noise (and friction perturbation)
  bool model_mismatch = true;          ///< plant link inertials +-5 % from the controller's URDF
  bool elastic = false;                ///< the plant's joint elasticity (plant.elasticity) enabled
  double friction_perturbation = 0.0;  ///< plant friction off actuators.yaml by up to this fraction
  /// Start posture: the paper demo's postureTarget (arm half extended forward).
  std::vector<double> start_q_rad = {0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57};

  // ---- protocol
  std::vector<TrackingScenario> scenarios = {TrackingScenario::kStatic, TrackingScenario::kDynamic};
  std::vector<LowLevelMode> loops = {LowLevelMode::kCurrent, LowLevelMode::kKinovaTorqueHighVelocity};
  double position_phase_s = 1.0;   ///< position control before the switch (F/T bias, settling)
  double static_duration_s = 10.0; ///< after the switch
  double dynamic_duration_s = 20.0;///< after the switch (two periods of the 9 s triangle)
  double transient_s = 0.5;        ///< after the switch, left out of the statistics
  ComplianceMode static_compliance = ComplianceMode::kStiff;
  ComplianceMode dynamic_compliance = ComplianceMode::kNullSpace;
  /// Static scenario: mass added to the plant's tool [kg] (the paper's drop-test weight).
  double payload_kg = 1.25;
  PayloadMode payload_mode = PayloadMode::kToolMass;
  double payload_hang_delay_s = 1.0;  ///< kHungAfterSwitch: after the switch
  double payload_rise_s = 0.2;        ///< kHungAfterSwitch: force ramp
  // dynamic scenario (paper demo "Sin" state; see torque_tracking.cpp for the source)
  double sine_amplitude_m = 0.10;
  double sine_omega_rad_s = 3.0;
  double triangle_speed_m_s = 0.10;
  double triangle_min_m = -0.40;  ///< relative to the start position
  double triangle_max_m = 0.05;
  double trajectory_delay_s = 0.5;  ///< after the switch, before the trajectory starts
  double fade_in_s = 1.0;           ///< the sine's amplitude rises smoothly over this time

  /// The position loop as the paper runs it: the QP integrates its own state open loop into the
  /// vendor servo (ControllerSettings::position_mode_open_loop); false: the QP on the measured state.
  bool position_open_loop = false;

  /// External torque of the static scenario's controller: the observer (default), or, as in the
  /// paper's static experiment, the F/T sensor only (use with PayloadMode::kHungAfterSwitch so the
  /// sensor, zeroed without the weight, measures it).
  ExternalTorqueSource static_external_torque = ExternalTorqueSource::kObserver;

  // ---- the custom loop's gains (lambda, K_I, theta, ...)
  CustomTorqueSettings custom_torque;
  /// The custom loop's friction pre-compensation thresholds, replacing actuators.yaml's on every
  /// joint of the controller's actuator table when > 0 (torque_tracking.md records them).
  /// 0: actuators.yaml's (0.1 rad/s and 1 rad/s^2, the paper demo's runtime values).
  double friction_velocity_threshold_rad_s = 0.0;
  double friction_acceleration_threshold_rad_s2 = 0.0;

  // ---- the plant's drive-gain error (used when model_mismatch is on)
  /// Each drive's true K_T G_r off the nominal value by a uniform draw in [-f, f]
  /// (SimRobotConfig::Mismatch::torque_constant_fraction); < 0: the plant file's value.
  double torque_constant_error = -1.0;
  /// Seed of the link-inertial and drive-gain draws; empty: the plant file's mismatch.seed.
  std::optional<std::uint64_t> mismatch_seed;
};

/// Statistics of one run (scenario x loop) over its statistics window, and its validity
/// (RunValidity: a safe stop, a QP fallback or another loop than `loop` after the switch).
struct TorqueTrackingRun : RunValidity {
  TrackingScenario scenario = TrackingScenario::kStatic;
  LowLevelMode loop = LowLevelMode::kCurrent;
  double rms_Nm = 0.0;        ///< of ||tau_d - tau_s|| (measured)
  double p95_Nm = 0.0;
  double max_Nm = 0.0;
  /// Norm of the per-joint time-mean error: the steady part of the error, without the noise.
  double bias_Nm = 0.0;
  double rms_true_Nm = 0.0;   ///< of ||tau_d - tau_s|| with the plant's true transmitted torque
  double p95_true_Nm = 0.0;
  double ee_position_rms_mm = 0.0;  ///< end-effector position error (task target vs plant)
  double ee_position_max_mm = 0.0;
  /// RMS of the end effector's y and z position errors (target - plant) and velocity errors
  /// (the target's reference velocity - plant), the axes of the paper's Fig. dynamic-comparison.
  double ee_y_rms_mm = 0.0, ee_z_rms_mm = 0.0, ee_vy_rms_mm_s = 0.0, ee_vz_rms_mm_s = 0.0;
  int samples = 0;
  /// Elastic plant: each joint's two-mass mode at the run's final posture (elastic_modes.hpp).
  std::vector<ElasticJointMode> elastic_modes;
  std::string csv_path;       ///< time series, when written
  std::vector<ContactLinkSummary> contact;  ///< per link, after the switch (experiment_contact.hpp)
};

struct TorqueTrackingResult {
  std::vector<TorqueTrackingRun> runs;
  double simulated_s = 0.0;
  double wall_s = 0.0;
  std::vector<std::string> files;

  /// The run of (scenario, loop); null if it was not run.
  const TorqueTrackingRun* find(TrackingScenario scenario, LowLevelMode loop) const;
  /// RMS of the high-velocity loop over the custom loop's in a scenario (0 if either is missing).
  double rms_ratio(TrackingScenario scenario) const;
};

/// Runs every (scenario, loop) of the options on the simulated plant; progress lines on `progress`
/// (may be null). Writes into options.output_dir (when not empty) one CSV per run,
/// torque_tracking_<scenario>_<loop>.csv (t_s, error_norm_Nm, error_norm_true_Nm, per-joint
/// measured errors, ee_error_mm), torque_tracking_summary.csv (the statistics) and
/// torque_tracking.md (the table). Throws ConfigError on bad options or input files, IoError when
/// an output cannot be written, ExperimentError when the plant faults.
TorqueTrackingResult run_torque_tracking(const TorqueTrackingOptions& options, std::ostream* progress = nullptr);

/// The markdown table: RMS and p95 per loop and scenario, and the ratios.
std::string torque_tracking_table(const TorqueTrackingResult& result, const TorqueTrackingOptions& options);

/// Everything the CLI's `phri experiment torque-tracking` needs: simulate, write the files, run
/// the figure script (when /usr/bin/python3 and the script exist), print the table on `out`.
/// Returns 0; failures throw (phri::Error, as run_torque_tracking).
int run_torque_tracking_command(const TorqueTrackingOptions& options, std::ostream& out);

}  // namespace phri
