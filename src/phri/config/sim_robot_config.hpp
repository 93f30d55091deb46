#pragma once
// phri::SimRobotConfig: everything the simulated arm (phri::SimRobot) needs, loaded from a plant
// YAML (configs/plant_gen3.yaml documents every key with its unit and source) or built in code.
//
//   auto config = phri::SimRobotConfig::from_yaml_file("configs/plant_gen3.yaml");
//   config.noise.torque_sensor_std_Nm = 0.0;   // tests and experiments may edit fields
//   phri::SimRobot robot(config);              // validate() runs again there
//
// Loading validates types, ranges, unknown keys and cross-field consistency; errors are
// phri::ConfigError(file, key path, reason), e.g. key path "plant.noise.torque_sensor_std_Nm".
// Relative file names in the YAML are relative to the YAML file's directory.
//
// The simulator's configuration is the robot's description (robot/robot_description.hpp: URDF,
// actuators, base, home posture, end of arm, payloads, drive) plus the plant-only settings here.
// `actuators` is the nominal table of actuators.yaml (what the controller believes);
// `actuator_overrides` and `friction_scale` make the plant's drives differ from it, and `mismatch`
// perturbs the plant's link inertials relative to the URDF (model mismatch).
#include <phri/core/error.hpp>
#include <phri/robot/robot_description.hpp>
#include <phri/config/external_force.hpp>
#include <phri/config/random_push_settings.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace phri {

/// The standard's body-region model as the simulator builds it (sim/body_region_surrogate.hpp).
struct BodyRegionSurrogateSettings {
  double mass_kg = 0.6;                ///< m_H
  double stiffness_N_per_m = 75000.0;  ///< k
  double damping_Ns_per_m = 0.0;       ///< c (the standard's model has none)
  bool backed_by_wall = false;         ///< the mass cannot move: clamping (quasi-static contact)
};

struct SimRobotConfig : RobotDescription {
  static SimRobotConfig from_yaml_file(const std::string& path);
  /// `base_dir` resolves relative file names; `source_name` stands for the file in errors.
  static SimRobotConfig from_yaml_string(const std::string& yaml, const std::string& source_name,
                                         const std::string& base_dir);

  /// Fills the per-joint vectors left empty with their defaults: vendor loop gains by actuator size
  /// (see robots/kinova_gen3/README.md), zero torque-sensor offsets. Called by the loaders and by
  /// SimRobot's constructor, so a config built in code needs only `actuators` and `initial_q_rad`.
  void fill_defaults();
  /// Cross-field checks (sizes, divisibility of rates, joint names); throws ConfigError with the
  /// key path. Called by the loaders and by SimRobot's constructor.
  void validate() const;

  /// Joint-side parameters of the plant's drives: `actuators` with the overrides applied.
  ActuatorTable plant_actuators() const;
  double physics_step_s() const { return 1.0 / physics_rate_Hz; }
  int substeps_per_cycle() const;

  std::string source = "<SimRobotConfig>";  ///< file the config came from (error messages)

  // ---- how the plant is made: a hand-written MJCF of the arm alone (robots/kinova_gen3/gen3_plant.xml),
  // or, when mjcf_path is empty, generated from the description's urdf_path (sim/urdf_plant.hpp)
  std::string mjcf_path;
  bool balance_inertia = false;  ///< generated plant: MuJoCo's balanceinertia (a warning per link it changes)
  /// The file the arm comes from, for messages: mjcf_path, else urdf_path.
  const std::string& arm_file() const { return mjcf_path.empty() ? urdf_path : mjcf_path; }
  // ---- timing
  double physics_rate_Hz = 4000.0;  ///< MuJoCo step rate; multiple of 1 kHz (the Kortex filter rate)
  double control_period_s = 0.001;  ///< read()/write() period; multiple of the physics step

  std::uint64_t seed = 1;  ///< sensor noise and random pushes

  // ---- plant drives differing from actuators.yaml (model mismatch on the drive side)
  struct ActuatorOverride {
    std::string joint;
    std::optional<double> coulomb_Nm;
    std::optional<double> viscous_Nms_per_rad;
    std::optional<double> static_Nm;
    std::optional<double> reflected_inertia_kgm2;
    std::optional<double> torque_constant_scale;  ///< plant K_T = scale x nominal K_T
  };
  std::vector<ActuatorOverride> actuator_overrides;
  double friction_scale = 1.0;  ///< multiplies every plant friction coefficient (after the overrides)

  struct Friction {
    /// Below this joint speed the friction limit is the static (breakaway) level, above it the
    /// Coulomb level [rad/s].
    double breakaway_velocity_rad_s = 1e-3;
    // A sliding-friction form other than the identified model's (StickSlipFriction: Stribeck curve
    // and position-dependent ripple); off by default. Friction identification's
    // `--plant-friction stribeck-ripple` sets it (see friction_identification.hpp for the values).
    double stribeck_velocity_rad_s = 0.0;  ///< v_s; 0: off (sliding level = Coulomb)
    double stribeck_exponent = 2.0;        ///< delta
    double ripple_fraction = 0.0;          ///< a_r: ripple amplitude as a fraction of each joint's Coulomb level
    double ripple_cycles_per_rev = 200.0;  ///< n_r: 2 per wave-generator turn x gear ratio 100
    double ripple_phase_rad = 0.0;         ///< phi
  } friction;

  // ---- joint sensors
  struct Noise {
    double torque_sensor_std_Nm = 0.05;
    std::vector<double> torque_sensor_offset_Nm;  ///< one per joint (empty: zeros)
    double velocity_std_rad_s = 0.002;
    double current_std_A = 0.01;
    double encoder_counts_per_rev = 262144.0;  ///< position quantum 2 pi / counts; 0: no quantisation
  } noise;

  // ---- link inertial and drive-gain mismatch relative to the URDF and actuators.yaml
  struct Mismatch {
    bool enabled = false;
    std::uint64_t seed = 7;
    double mass_fraction = 0.05;
    double com_fraction = 0.05;
    double inertia_fraction = 0.05;
    /// Each drive's true torque per amp (K_T G_r, including the gear's efficiency) is the nominal
    /// one x (1 + u), u uniform in [-f, f], drawn from `seed` (after actuator_overrides). The
    /// vendor's loops keep converting with the nominal value, as real firmware does.
    double torque_constant_fraction = 0.0;
  } mismatch;

  // ---- the vendor's actuator loops, emulated inside the plant (see KinovaDriveEmulator)
  struct Vendor {
    std::vector<double> position_kp_Nm_per_rad;
    std::vector<double> position_kd_Nms_per_rad;
    std::vector<double> position_ki_Nm_per_rad_s;
    std::vector<double> position_integral_limit_Nm;
    std::vector<double> torque_feedback_gain;
    std::vector<double> torque_velocity_damping_Nms_per_rad;
    std::vector<double> high_velocity_numerator = {0.020175, -0.036975, 0.016917};
    std::vector<double> high_velocity_denominator = {1.0, -1.975063, 0.97518};
    double high_velocity_rate_Hz = 1000.0;
  } vendor;

  // ---- joint elasticity: a torsional spring between each drive's rotor and its link
  // (ElasticTransmission); off: a rigid transmission (rotor inertia and friction on the link).
  struct Elasticity {
    bool enabled = false;
    /// K per joint [N.m/rad]; empty: by actuator size (configs/plant_gen3.yaml gives the source).
    std::vector<double> stiffness_Nm_per_rad;
    /// D = 2 ratio sqrt(K B) in parallel with K (B the reflected rotor inertia).
    double damping_ratio = 0.05;
    /// Which position the vendor position servo closes on; the arm reports the link side. kMotor: the
    /// rotor's encoder (collocated; the link sits tau / K off the command, and commanding the measured
    /// position steps the servo by kp tau / K). kMotorCompensated: the rotor's encoder less the static
    /// deflection, theta - LP(tau_s) / K with the drive's torque reading low-passed over
    /// deflection_filter_s: commanding the measured position holds the arm still (as Kinova's low-level
    /// examples rely on) while the servo stays collocated at the elastic modes (the deflection
    /// compensation of Albu-Schaeffer and Hirzinger's motor-side position control, with the sensor's
    /// torque in place of a gravity model; 0 s: unfiltered, the link position). kLink: the link's encoder.
    enum class Encoder { kMotor, kMotorCompensated, kLink } position_loop_encoder = Encoder::kMotor;
    double deflection_filter_s = 0.05;
  } elasticity;

  // ---- the paper's drop test: a mass on a slack cable under the tool, released at a given time
  struct DropTest {
    bool enabled = false;
    double mass_kg = 1.25;
    double radius_m = 0.04;
    double cable_length_m = 0.25;
    double cable_stiffness_N_per_m = 2000.0;
    double cable_damping_Ns_per_m = 10.0;
    Eigen::Vector3d anchor_m = Eigen::Vector3d(0.0, 0.0, 0.1);  ///< cable anchor, sensor frame
    double release_time_s = 1.0;
    double latch_stiffness_N_per_m = 1.0e5;  ///< holds the mass at the anchor until release
    /// Drop-to-drop variability of a hand's release (the paper's weight is let go by hand): the
    /// mass starts its fall offset from the anchor by a uniform draw in [-s, s], vertically (the
    /// fall height, hence the catch's speed) and along each horizontal axis (a swing after the
    /// catch), drawn from the plant's `seed`. 0: every release the same.
    double release_vertical_spread_m = 0.0;
    double release_horizontal_spread_m = 0.0;
    /// Who holds the mass until the release: false, a latch on the tool (the arm carries the
    /// weight, and the release unloads it before the catch loads it); true, a hand fixed in the
    /// world at the anchor's initial position (the arm feels the mass only through the cable, as
    /// in the paper's protocol where the weight is let go by hand).
    bool held_by_hand = false;
  } drop_test;

  /// A body region in the robot's way (sim/body_region_surrogate.hpp: the standard's mass m_H
  /// behind a spring k), met by the tool's box; `phri experiment collision` places it.
  struct Surrogate {
    bool enabled = false;
    BodyRegionSurrogateSettings region;
    Eigen::Vector3d face_m = Eigen::Vector3d::Zero();   ///< centre of its face at rest (world)
    Eigen::Vector3d normal = Eigen::Vector3d::UnitX();  ///< out of the face, toward the robot (world, unit)
    double face_radius_m = 0.1;                      ///< the face is a disc of this radius
  } surrogate;

  struct Floor {
    bool enabled = false;
    double height_m = 0.0;
    /// The tool touches it (a table to press on); otherwise only the drop mass does.
    bool tool_contact = false;
  } floor;

  std::vector<ExternalForce> disturbances;  ///< scripted timeline
  RandomPushSettings random_pushes;
};

}  // namespace phri
