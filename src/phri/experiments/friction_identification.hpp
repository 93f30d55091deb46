#pragma once
// Friction identification on the simulated Gen3, as in the paper (section "Evaluation",
// "Friction parameters identification"): the arm upright in its zero-gravity-torque stance
// (q = 0: every joint's gravity torque is below 2e-3 N.m there), one joint at a time driven by a
// constant motor current, the others held; at each current level the steady-state joint velocity
// and the torque error
//
//   e = K_T G_r i_meas - tau_s = (friction on the motor side of the torque sensor) + I_r qdd,
//
// whose rotor-inertia part vanishes at steady state. Least squares on the steady-state levels
//
//   e = c0 + tau_c sign(qd) + tau_v qd           (c0: minus the torque sensor's zero offset)
//
// gives the Coulomb and viscous coefficients; the static (breakaway) level is the smallest
// current that starts the joint from rest, found by bisection in each direction.
//
// Protocol per joint (choices the paper does not spell out; see tools/report and the issue notes):
// * The whole arm runs in LowLevelMode::kCurrent (the mode is per arm, not per joint). The other
//   joints get gravity compensation from the controller's model plus a joint PD holding their
//   start position (bandwidth 30 rad/s on each joint's own inertia at q = 0). At the upright
//   stance their gravity torque is nil and their stiction alone would hold them; the PD keeps
//   them there when a joint under test tilts the arm (joints 2, 4, 6) or spins it.
// * Levels are chosen by speed: a short velocity run-up (PI on the joint velocity, in current,
//   along a ramp with its acceleration and the nominal friction fed forward) brings the joint to
//   the level's speed, then the run-up's mean current is held constant
//   (settle, then average). The run-up only sets which constant current is applied and makes the
//   transient short for the joints with a large inertia (joint 2: M_22 ~ 2 kg.m^2, a 1 s
//   mechanical time constant against 2 N.m.s/rad viscous friction); the recorded data are those
//   of the constant-current phase. Continuous joints (1, 3, 5, 7) spin freely; the limited ones
//   (2, 4, 6) sweep back and forth within +-limited_half_range_rad of upright, with the model's
//   gravity torque added to their constant current (it does not enter e, which is measured
//   across the drive).
// * A level is "steady" when the joint moves (faster than a quarter of the run-up speed: a joint
//   that stuck when the servo let go is not sliding friction) and the mean velocity of the second
//   half of its averaging window differs from the first half's by less than 2 % (+ 0.005 rad/s);
//   only steady levels enter the fit.
//
// The plant may be given friction that differs from actuators.yaml by a seeded random fraction
// (friction_perturbation.hpp); the result then holds the plant's true values beside the
// identified ones.
#include <phri/experiments/friction_model_form.hpp>
#include <phri/robot/friction_parameters.hpp>

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace phri {

struct FrictionIdentificationOptions {
  // ---- files (relative paths are relative to the working directory)
  std::string plant_config_path = "configs/plant_gen3.yaml";
  /// The controller's model, for the gravity compensation of the held joints.
  std::string urdf_path = "robots/kinova_gen3/gen3.urdf";
  std::string end_effector_frame = "end_effector_link";  ///< the URDF's frame the end of arm mounts on
  /// CSV, YAML and markdown go here (created when missing); empty: no files.
  std::string output_dir = "results/friction_identification";
  /// Figure script run by the command (tools/report/friction_figure.py); empty: no figure.
  std::string figure_script = "tools/report/friction_figure.py";

  // ---- plant
  /// Plant friction = actuators.yaml's, each coefficient off by up to this fraction (seeded, see
  /// friction_perturbation.hpp); 0: the plant YAML's own friction (overrides included).
  double friction_perturbation = 0.2;
  std::uint64_t seed = 1;  ///< friction perturbation and sensor noise
  /// The plant friction's form: the model's (default) or Stribeck + ripple (friction_model_form.hpp),
  /// then compared with the identified model and swept over v_s.
  PlantFrictionForm plant_friction = PlantFrictionForm::kModelForm;
  StribeckRippleSettings stribeck_ripple;

  // ---- protocol
  std::vector<int> joints = {1, 2, 3, 4, 5, 6, 7};  ///< 1-based joint numbers
  int speed_levels = 12;               ///< per direction, geometric from min to max speed
  double min_speed_rad_s = 0.05;
  double max_speed_fraction = 0.75;    ///< of the joint's velocity limit (actuators.yaml)
  double run_up_s = 0.5;               ///< velocity run-up before the constant current
  double settle_s = 0.25;              ///< constant current, not recorded
  double average_s = 0.3;              ///< constant current, averaged
  double limited_half_range_rad = 1.2; ///< joints with position limits stay within +- this of 0
  int static_bisection_steps = 12;     ///< per direction
  double static_trial_s = 0.3;         ///< how long a trial current is applied from rest
  double breakaway_rad = 5e-4;         ///< motion that counts as "started" (20 encoder counts)
  bool static_search = true;           ///< false: sliding levels only (the v_s sweep)
};

/// One constant-current level at steady state (means over the averaging window).
struct FrictionLevel {
  int joint = 0;       ///< 1-based
  int direction = 0;   ///< +1 / -1
  double target_speed_rad_s = 0.0;  ///< speed of the run-up (sets the current)
  double current_A = 0.0;           ///< measured motor current
  double velocity_rad_s = 0.0;      ///< measured joint velocity
  double torque_error_Nm = 0.0;     ///< K_T G_r i - tau_s
  double torque_error_std_Nm = 0.0; ///< over the samples of the window
  double velocity_drift_rad_s = 0.0;  ///< second half minus first half of the window
  bool current_mode = true;  ///< every cycle of the window ran in current mode (else not steady: invalid)
  bool steady = false;
};

/// Raw samples of the constant-current phases (every 5th cycle), for the figure's shaded data.
struct FrictionSample {
  int joint = 0;
  double velocity_rad_s = 0.0;
  double torque_error_Nm = 0.0;
};

/// One bisection trial of the static-friction search.
struct StaticFrictionTrial {
  int joint = 0;
  int direction = 0;
  double torque_Nm = 0.0;  ///< K_T G_r i of the trial current (beyond gravity compensation)
  bool moved = false;
};

struct JointFrictionEstimate {
  int joint = 0;  ///< 1-based
  std::string name;
  FrictionParameters identified;  ///< thresholds copied from the nominal table
  FrictionParameters plant;       ///< the simulated plant's true values
  FrictionParameters nominal;     ///< actuators.yaml
  double offset_Nm = 0.0;         ///< fitted c0 (= minus the torque sensor's zero offset)
  double plant_sensor_offset_Nm = 0.0;  ///< the plant's true torque sensor offset
  double static_positive_Nm = 0.0;
  double static_negative_Nm = 0.0;
  double residual_rms_Nm = 0.0;   ///< of the fit on the steady levels
  int levels_used = 0;
  int levels_total = 0;
  /// False when the joint's intended run did not happen (too few steady levels on a plant of another
  /// form; the model-form plant throws instead): its numbers are not results.
  bool valid = true;
  std::string invalid_reason;
  ModelFormError form;  ///< computed on a plant of another form only

  static double relative_error(double identified, double truth) {
    return truth != 0.0 ? (identified - truth) / truth : 0.0;
  }
  double coulomb_error() const { return relative_error(identified.coulomb_Nm, plant.coulomb_Nm); }
  double viscous_error() const { return relative_error(identified.viscous_Nms_per_rad, plant.viscous_Nms_per_rad); }
  double static_error() const { return relative_error(identified.static_Nm, plant.static_Nm); }
};

struct FrictionIdentificationResult {
  std::vector<JointFrictionEstimate> joints;
  std::vector<FrictionLevel> levels;
  std::vector<FrictionSample> samples;
  std::vector<StaticFrictionTrial> static_trials;
  double simulated_s = 0.0;
  double wall_s = 0.0;
  std::vector<std::string> files;  ///< written into the output directory
  PlantFrictionForm plant_friction = PlantFrictionForm::kModelForm;
  std::vector<FrictionFormSweepRow> sweep;  ///< the v_s sweep (Stribeck + ripple plant only)

  /// Largest |relative error| over the identified Coulomb, viscous and static values (valid joints).
  double worst_relative_error() const;
};

/// Runs the identification on the simulated plant; progress lines go to `progress` (may be null).
/// Writes into options.output_dir (when not empty): friction_levels.csv, friction_samples.csv,
/// friction_static.csv, friction_identified.yaml (per-joint `friction:` blocks with the keys of
/// actuators.yaml), friction_identification.md. Throws ConfigError on bad options or input files,
/// IoError when an output cannot be written, ExperimentError when the plant faults or a joint's
/// friction cannot be identified.
FrictionIdentificationResult identify_friction(const FrictionIdentificationOptions& options,
                                               std::ostream* progress = nullptr);

/// The markdown table of the result: plant truth vs identified, % errors.
std::string friction_identification_table(const FrictionIdentificationResult& result);
/// The YAML of the identified friction, `joints: [{name, friction: {...}}]`, each friction block
/// with the keys of actuators.yaml (static raised to Coulomb if below it, as actuators.yaml requires).
std::string friction_identification_yaml(const FrictionIdentificationResult& result,
                                         const FrictionIdentificationOptions& options);

/// Everything the CLI's `phri identify-friction` needs: simulate, write the files, run the figure
/// script (when /usr/bin/python3 and the script exist), print the table on `out`. Returns 0;
/// failures throw (phri::Error, as identify_friction).
int run_friction_identification_command(const FrictionIdentificationOptions& options, std::ostream& out);

}  // namespace phri
