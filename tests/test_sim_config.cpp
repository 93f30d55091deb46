// ctest-labels: physics
// The simulated plant's building blocks, each against an independent reference: the plant YAML
// and actuators.yaml loaders (every key of the shipped files, validation errors naming the key
// path), the Kinova transfer function (difference equation written out by hand, DC gain),
// the seeded random generator (moments, reproducibility), the stick-slip friction on a single
// inertia (closed-form breakaway and sliding), the inertial perturbation, the force profiles and
// the random-push geometry.
#include <phri/core/error.hpp>
#include <phri/core/random_generator.hpp>
#include <phri/core/discrete_transfer_function.hpp>
#include <phri/robot/actuator_table.hpp>
#include <phri/config/external_force.hpp>
#include <phri/sim/link_inertial.hpp>
#include <phri/sim/mujoco_handles.hpp>
#include <phri/sim/random_push_generator.hpp>
#include <phri/sim/sim_scene.hpp>
#include <phri/config/sim_robot_config.hpp>
#include <phri/sim/stick_slip_friction.hpp>

#include "config_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <numbers>
#include <sstream>
#include <string>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;
const std::string kPlantYaml = kRoot + "/configs/plant_gen3.yaml";
const std::string kActuatorsYaml = kRoot + "/robots/kinova_gen3/actuators.yaml";

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// `text` with `from` replaced by `to` (which must occur: a test bug otherwise).
std::string edited(std::string text, const std::string& from, const std::string& to) {
  const auto pos = text.find(from);
  if (pos == std::string::npos) throw std::runtime_error("test bug: '" + from + "' not found");
  text.replace(pos, from.size(), to);
  return text;
}

// Loading the shipped plant YAML with `from` replaced by `to` (named "test.yaml" in errors), as a
// callable for expect_config_error.
std::function<void()> loading_plant_with(const std::string& from, const std::string& to) {
  return [from, to] {
    (void)phri::SimRobotConfig::from_yaml_string(edited(read_file(kPlantYaml), from, to), "test.yaml",
                                                 kRoot + "/configs");
  };
}

// The same for the Gen3 actuators.yaml (named "act.yaml").
std::function<void()> loading_actuators_with(const std::string& from, const std::string& to) {
  return [from, to] {
    (void)phri::ActuatorTable::from_yaml_string(edited(read_file(kActuatorsYaml), from, to), "act.yaml");
  };
}

using phri::test::expect_config_error;

// ------------------------------------------------------------------------------------ loaders
TEST(ActuatorTable, LoadsTheGen3File) {
  const auto table = phri::ActuatorTable::from_yaml_file(kActuatorsYaml);
  ASSERT_EQ(table.size(), 7);
  EXPECT_EQ(table[0].joint_name, "joint_1");
  EXPECT_EQ(table[3].size, phri::ActuatorSize::kLarge);
  EXPECT_EQ(table[4].size, phri::ActuatorSize::kSmall);
  // K_T G_r = 0.11 * 100 = 11 N.m/A (large), 0.076 * 100 = 7.6 N.m/A (small).
  EXPECT_NEAR(table[1].torque_per_amp(), 11.0, 1e-12);
  EXPECT_NEAR(table[6].torque_per_amp(), 7.6, 1e-12);
  // Current limits were derived from the 105 / 52 N.m hard limits.
  EXPECT_NEAR(table[1].max_motor_torque_Nm(), 105.0, 1e-5);
  EXPECT_NEAR(table[5].max_motor_torque_Nm(), 52.0, 1e-5);
  // The paper's friction model: 2.15 + 2.00 qd (large), 1.60 + 1.36 qd (small), static = Coulomb.
  EXPECT_DOUBLE_EQ(table[2].friction.coulomb_Nm, 2.15);
  EXPECT_DOUBLE_EQ(table[2].friction.viscous_Nms_per_rad, 2.00);
  EXPECT_DOUBLE_EQ(table[5].friction.coulomb_Nm, 1.60);
  EXPECT_DOUBLE_EQ(table[5].friction.viscous_Nms_per_rad, 1.36);
  EXPECT_DOUBLE_EQ(table[5].friction.static_Nm, table[5].friction.coulomb_Nm);
  EXPECT_EQ(table.index_of("joint_6"), 5);
  EXPECT_EQ(table.index_of("nope"), -1);
}

TEST(ActuatorTable, ValidationNamesTheKey) {
  expect_config_error(loading_actuators_with("gear_ratio: 100", "gear_ratio: -1"),
                      {.element = "joints[0].gear_ratio", .file = "act.yaml"});
  expect_config_error(loading_actuators_with("coulomb_Nm: 2.15", "coulomb_Nm: abc"),
                      {.element = "joints[0].friction.coulomb_Nm", .file = "act.yaml"});
  expect_config_error(loading_actuators_with("reflected_inertia_kgm2: 0.03 ", "reflected_inertia_kgm2: 0.05 "),
                      {.element = "joints[0].reflected_inertia_kgm2", .file = "act.yaml"});
  expect_config_error(loading_actuators_with("size: large", "size: huge"),
                      {.element = "joints[0].size", .file = "act.yaml"});
  expect_config_error(loading_actuators_with("static_Nm: 2.15", "static_Nm: 1.0"),
                      {.element = "joints[0].friction.static_Nm", .file = "act.yaml"});
  expect_config_error(loading_actuators_with("    gear_ratio: 100", "    gear_ratios: 100"),
                      {.element = "joints[0].gear_ratios", .file = "act.yaml"});
}

TEST(ActuatorTable, DuplicateKeysAndNullsAreRefused) {
  expect_config_error(loading_actuators_with("    gear_ratio: 100 ", "    gear_ratio: 10\n    gear_ratio: 100 "),
                      {.element = "joints[0].gear_ratio", .mentions = {"duplicate key"}, .file = "act.yaml"});
  expect_config_error(loading_actuators_with("coulomb_Nm: 2.15", "coulomb_Nm:"),
                      {.element = "joints[0].friction.coulomb_Nm", .mentions = {"null"}, .file = "act.yaml"});
}

TEST(SimRobotConfig, DuplicateKeysAndNullsAreRefused) {
  expect_config_error(loading_plant_with("  seed: 1 ", "  seed: 2\n  seed: 1 "),
                      {.element = "plant.seed", .mentions = {"duplicate key"}, .file = "test.yaml"});
  expect_config_error(loading_plant_with("torque_sensor_std_Nm: 0.05", "torque_sensor_std_Nm: ~"),
                      {.element = "plant.noise.torque_sensor_std_Nm", .mentions = {"null"}, .file = "test.yaml"});
}

// Drive limits: the QP's torque bound within what the motor can produce (current x K_T x G_r),
// currents and speeds within physical ranges.
TEST(ActuatorTable, PhysicalRangesNameTheKey) {
  expect_config_error(loading_actuators_with("torque_limit_Nm: 95", "torque_limit_Nm: 500"),
                      {.element = "joints[0].torque_limit_Nm", .mentions = {"105", "drive's maximum"}, .file = "act.yaml"});
  expect_config_error(loading_actuators_with("torque_limit_Nm: 95", "torque_limit_Nm: 1e-6"),
                      {.element = "joints[0].torque_limit_Nm", .file = "act.yaml"});
  expect_config_error(loading_actuators_with("current_limit_A: 9.5454545", "current_limit_A: 1e4"),
                      {.element = "joints[0].current_limit_A", .file = "act.yaml"});
  expect_config_error(loading_actuators_with("velocity_limit_rad_s: 2.0944", "velocity_limit_rad_s: 120"),
                      {.element = "joints[0].velocity_limit_rad_s", .file = "act.yaml"});
  expect_config_error(loading_actuators_with("static_Nm: 2.15", "static_Nm: 200"),
                      {.element = "joints[0].friction.static_Nm", .file = "act.yaml"});
}

TEST(SimRobotConfig, LoadsTheShippedPlant) {
  const auto c = phri::SimRobotConfig::from_yaml_file(kPlantYaml);
  EXPECT_EQ(c.dof(), 7);
  EXPECT_DOUBLE_EQ(c.physics_rate_Hz, 4000.0);
  EXPECT_DOUBLE_EQ(c.control_period_s, 0.001);
  EXPECT_EQ(c.substeps_per_cycle(), 4);
  EXPECT_EQ(c.initial_q_rad.size(), 7u);
  EXPECT_DOUBLE_EQ(c.tool.mass_kg, 0.3);
  EXPECT_DOUBLE_EQ(c.drop_test.mass_kg, 1.25);
  EXPECT_DOUBLE_EQ(c.drop_test.cable_length_m, 0.25);
  EXPECT_EQ(c.vendor.high_velocity_numerator.size(), 3u);
  EXPECT_DOUBLE_EQ(c.vendor.high_velocity_denominator[1], -1.975063);
  EXPECT_EQ(c.vendor.position_kp_Nm_per_rad.size(), 7u);
  EXPECT_TRUE(c.disturbances.empty());
  EXPECT_FALSE(c.random_pushes.enabled);
  EXPECT_NE(c.mjcf_path.find("gen3_plant.xml"), std::string::npos);
  // No overrides: the plant drives are the nominal ones.
  const auto plant = c.plant_actuators();
  EXPECT_DOUBLE_EQ(plant[0].friction.coulomb_Nm, c.actuators[0].friction.coulomb_Nm);
}

TEST(SimRobotConfig, ErrorsNameTheKeyPath) {
  expect_config_error(loading_plant_with("torque_sensor_std_Nm: 0.05", "torque_sensor_std_Nm: -1"),
                      {.element = "plant.noise.torque_sensor_std_Nm", .file = "test.yaml"});
  expect_config_error(loading_plant_with("torque_sensor_std_Nm: 0.05", "torque_sensor_std_Nm: loud"),
                      {.element = "plant.noise.torque_sensor_std_Nm", .file = "test.yaml"});
  expect_config_error(loading_plant_with("torque_sensor_std_Nm: 0.05", "torque_sensor_stdev_Nm: 0.05"),
                      {.element = "plant.noise.torque_sensor_stdev_Nm", .file = "test.yaml"});
  expect_config_error(loading_plant_with("physics_rate_Hz: 4000", "physics_rate_Hz: 4500"),
                      {.element = "plant.timing.physics_rate_Hz", .file = "test.yaml"});
  expect_config_error(loading_plant_with("control_period_s: 0.001", "control_period_s: 0.0011"),
                      {.element = "plant.timing.control_period_s", .file = "test.yaml"});
  expect_config_error(loading_plant_with("mass_kg: 0.3", "mass_kg: [0.3]"),
                      {.element = "plant.tool.mass_kg", .file = "test.yaml"});
  expect_config_error(loading_plant_with("force_bias_N: [0.4, -0.3, 0.6]", "force_bias_N: [0.4, -0.3]"),
                      {.element = "plant.ft_sensor.force_bias_N", .file = "test.yaml"});
  expect_config_error(loading_plant_with("feedback_gain: [0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 0.5]",
                                         "feedback_gain: [0.5, 0.5, 0.5, 0.5, 0.5, 0.5, 1.5]"),
                      {.element = "plant.vendor.torque.feedback_gain[6]", .file = "test.yaml"});
  expect_config_error(loading_plant_with("q_rad: [0.0, 0.26179939,", "q_rad: [0.26179939,"),
                      {.element = "plant.initial.q_rad", .file = "test.yaml"});
  expect_config_error(loading_plant_with("actuator_overrides: {}", "actuator_overrides: {joint_9: {static_Nm: 3}}"),
                      {.element = "plant.actuator_overrides.joint_9", .file = "test.yaml"});
  expect_config_error(loading_plant_with("actuator_overrides: {}", "actuator_overrides: {joint_2: {static_Nm: 1.0}}"),
                      {.element = "plant.actuator_overrides.joint_2.static_Nm", .file = "test.yaml"});
  expect_config_error(loading_plant_with("enabled: false\n    mass_kg: 1.25", "enabled: maybe\n    mass_kg: 1.25"),
                      {.element = "plant.drop_test.enabled", .file = "test.yaml"});
  expect_config_error(
      loading_plant_with("disturbances: []",
                         "disturbances:\n    - {body: forearm_link, profile: wobble, start_s: 1, duration_s: 1}"),
      {.element = "plant.disturbances[0].profile", .file = "test.yaml"});
  expect_config_error(
      loading_plant_with("disturbances: []", "disturbances:\n    - {body: forearm_link, profile: step, start_s: 1}"),
      {.element = "plant.disturbances[0].duration_s", .file = "test.yaml"});
  expect_config_error(loading_plant_with("max_force_N: 200.0", "max_force_N: 2000.0"),
                      {.element = "plant.random_pushes.max_force_N", .file = "test.yaml"});
  expect_config_error(loading_plant_with("rate_Hz: 1000                    # [Hz] sample rate", "rate_Hz: 3000"),
                      {.element = "plant.ft_sensor.rate_Hz", .file = "test.yaml"});
  expect_config_error(loading_plant_with("plant:", "plants:"), {.element = "plants", .file = "test.yaml"});
}

TEST(SimRobotConfig, CodeBuiltConfigGetsDefaults) {
  phri::SimRobotConfig c;
  c.mjcf_path = kRoot + "/robots/kinova_gen3/gen3_plant.xml";
  c.actuators = phri::ActuatorTable::from_yaml_file(kActuatorsYaml);
  c.initial_q_rad.assign(7, 0.0);
  // The per-joint defaults (sensor offsets, vendor gains) missing: the first one checked is named.
  expect_config_error([&] { c.validate(); }, {.mentions = {"expected 7 values (one per joint), got 0"}});
  c.fill_defaults();
  EXPECT_NO_THROW(c.validate());
  EXPECT_DOUBLE_EQ(c.vendor.position_kp_Nm_per_rad[0], 12000.0);
  EXPECT_DOUBLE_EQ(c.vendor.position_kp_Nm_per_rad[6], 3000.0);
  const auto shipped = phri::SimRobotConfig::from_yaml_file(kPlantYaml);
  EXPECT_EQ(c.vendor.position_kd_Nms_per_rad, shipped.vendor.position_kd_Nms_per_rad);
  EXPECT_EQ(c.vendor.torque_velocity_damping_Nms_per_rad, shipped.vendor.torque_velocity_damping_Nms_per_rad);
}

// MuJoCo's XML errors come on several lines ("XML Error: ...\nElement 'joint', line 55\n"): the
// ConfigError carries them as one.
TEST(SimRobotConfig, MujocoErrorsAreOneLine) {
  EXPECT_EQ(phri::mujoco_error_line("XML Error: bad\n\n  Element 'joint', line 55  \n"),
            "XML Error: bad; Element 'joint', line 55");
  EXPECT_EQ(phri::mujoco_error_line(""), "unknown error");
  std::string mjcf = read_file(kRoot + "/robots/kinova_gen3/gen3_plant.xml");
  mjcf = edited(mjcf, "<joint name=\"joint_2\" range=\"-2.24 2.24\"/>", "<joint name=\"joint_2\" bogus=\"1\"/>");
  const std::string path = (std::filesystem::temp_directory_path() / "phri_test_sim_config_broken.xml").string();
  std::ofstream(path) << mjcf;
  auto c = phri::SimRobotConfig::from_yaml_file(kPlantYaml);
  c.mjcf_path = path;
  const auto error = expect_config_error([&] { (void)phri::SimScene::build_mjcf(c); },
                                         {.mentions = {"bogus", "line 55"}, .file = path});
  if (error) {
    EXPECT_EQ(std::string(error->what()).find('\n'), std::string::npos) << error->what();
  }
  std::filesystem::remove(path);
}

TEST(SimRobotConfig, ReadsOptionalSections) {
  std::string yaml = read_file(kPlantYaml);
  yaml.replace(yaml.find("disturbances: []"), std::string("disturbances: []").size(),
               "disturbances:\n"
               "    - {body: forearm_link, point_m: [0, -0.1, 0], frame: local, force_N: [0, 30, 0],\n"
               "       profile: ramp, start_s: 2.0, duration_s: 0.5, rise_s: 0.2}");
  yaml.replace(yaml.find("actuator_overrides: {}"), std::string("actuator_overrides: {}").size(),
               "actuator_overrides: {joint_5: {static_Nm: 1.9, reflected_inertia_kgm2: 0.05}}");
  const auto c = phri::SimRobotConfig::from_yaml_string(yaml, "test.yaml", kRoot + "/configs");
  ASSERT_EQ(c.disturbances.size(), 1u);
  const auto& d = c.disturbances[0];
  EXPECT_EQ(d.body, "forearm_link");
  EXPECT_EQ(d.frame, phri::ExternalForce::Frame::kLocal);
  EXPECT_EQ(d.profile, phri::ExternalForce::Profile::kRamp);
  EXPECT_DOUBLE_EQ(d.force_N.y(), 30.0);
  EXPECT_DOUBLE_EQ(d.rise_s, 0.2);
  const auto plant = c.plant_actuators();
  EXPECT_DOUBLE_EQ(plant[4].friction.static_Nm, 1.9);
  EXPECT_DOUBLE_EQ(plant[4].friction.coulomb_Nm, 1.6);
  EXPECT_DOUBLE_EQ(plant[4].reflected_inertia_kgm2, 0.05);
  EXPECT_DOUBLE_EQ(c.actuators[4].friction.static_Nm, 1.6);  // the controller's table is untouched
}

// ------------------------------------------------------------------------------- transfer function
TEST(DiscreteTransferFunction, KinovaFilterMatchesItsDifferenceEquation) {
  auto h = phri::DiscreteTransferFunction::kinova_high_velocity();
  EXPECT_EQ(h.order(), 2);
  // DC gain: (0.020175 - 0.036975 + 0.016917) / (1 - 1.975063 + 0.97518) = 0.000117 / 0.000117.
  EXPECT_NEAR(h.dc_gain(), 1.0, 1e-9);
  // y[k] = 1.975063 y[k-1] - 0.97518 y[k-2] + 0.020175 x[k] - 0.036975 x[k-1] + 0.016917 x[k-2]
  phri::RandomGenerator rng(3);
  double x1 = 0, x2 = 0, y1 = 0, y2 = 0;
  for (int k = 0; k < 5000; ++k) {
    const double x = rng.normal();
    const double y = 1.975063 * y1 - 0.97518 * y2 + 0.020175 * x - 0.036975 * x1 + 0.016917 * x2;
    EXPECT_NEAR(h.step(x), y, 1e-9 * (1.0 + std::abs(y)));
    x2 = x1;
    x1 = x;
    y2 = y1;
    y1 = y;
  }
  // Steady state: a constant input gives DC gain x input from the first sample on.
  h.reset_to_steady_state(2.0);
  for (int k = 0; k < 10; ++k) EXPECT_NEAR(h.step(2.0), 2.0 * h.dc_gain(), 1e-9);
  // High-frequency gain (z = -1): (b0 - b1 + b2) / (1 - a1 + a2) = 0.074067 / 3.950243.
  h.reset();
  double amplitude = 0.0;
  for (int k = 0; k < 4000; ++k) {
    const double y = h.step(k % 2 == 0 ? 1.0 : -1.0);
    if (k > 3000) amplitude = std::max(amplitude, std::abs(y));
  }
  EXPECT_NEAR(amplitude, 0.074067 / 3.950243, 1e-6);
}

TEST(DiscreteTransferFunction, RejectsBadCoefficients) {
  expect_config_error(
      [] {
        phri::DiscreteTransferFunction({1.0}, {0.0, 1.0});
      },
      {.element = "coefficients", .mentions = {"a0 must be non-zero"}});
  expect_config_error(
      [] {
        phri::DiscreteTransferFunction({1, 1, 1, 1, 1, 1, 1}, {1.0});
      },
      {.element = "coefficients", .mentions = {"order above 5"}});
  phri::DiscreteTransferFunction identity;
  EXPECT_DOUBLE_EQ(identity.step(3.5), 3.5);
}

// The poles of a denominator, by the companion matrix: stable inside the unit circle.
TEST(DiscreteTransferFunction, LargestPoleMagnitude) {
  using phri::DiscreteTransferFunction;
  const std::vector<double> kinova = {1.0, -1.975063, 0.97518};
  // Real roots (1.975063 +- sqrt(1.975063^2 - 4 x 0.97518)) / 2.
  const double root = (1.975063 + std::sqrt(1.975063 * 1.975063 - 4.0 * 0.97518)) / 2.0;
  EXPECT_NEAR(DiscreteTransferFunction::largest_pole_magnitude(kinova), root, 1e-9);
  EXPECT_LT(DiscreteTransferFunction::largest_pole_magnitude(kinova), 1.0);
  // z^2 - 2.1 z + 1.2: complex pair of magnitude sqrt(1.2).
  const std::vector<double> unstable = {1.0, -2.1, 1.2};
  EXPECT_NEAR(DiscreteTransferFunction::largest_pole_magnitude(unstable), std::sqrt(1.2), 1e-9);
  // Scaled by a0, and a pole at -1.5.
  const std::vector<double> scaled = {2.0, 3.0};
  EXPECT_NEAR(DiscreteTransferFunction::largest_pole_magnitude(scaled), 1.5, 1e-12);
  const std::vector<double> constant = {4.0};
  EXPECT_EQ(DiscreteTransferFunction::largest_pole_magnitude(constant), 0.0);
}

// Physical ranges of the plant: each refused with its key path.
TEST(SimRobotConfig, PhysicalRangesNameTheKeyPath) {
  expect_config_error(loading_plant_with("encoder_counts_per_rev: 262144", "encoder_counts_per_rev: 1"),
                      {.element = "plant.noise.encoder_counts_per_rev", .mentions = {"4096"}, .file = "test.yaml"});
  EXPECT_NO_THROW(loading_plant_with("encoder_counts_per_rev: 262144", "encoder_counts_per_rev: 0")());
  expect_config_error(loading_plant_with("denominator: [1.0, -1.975063, 0.97518]", "denominator: [1.0, -2.1, 1.2]"),
                      {.element = "plant.vendor.torque_high_velocity.denominator", .mentions = {"unstable"}, .file = "test.yaml"});
  expect_config_error(loading_plant_with("kp_Nm_per_rad: [12000,", "kp_Nm_per_rad: [1000000,"),
                      {.element = "plant.vendor.position.kp_Nm_per_rad[0]", .file = "test.yaml"});
  expect_config_error(loading_plant_with("integral_limit_Nm: [60, 60, 60, 60, 30,", "integral_limit_Nm: [60, 60, 60, 60, 80,"),
                      {.element = "plant.vendor.position.integral_limit_Nm[4]", .mentions = {"drive maximum"}, .file = "test.yaml"});
  expect_config_error(loading_plant_with("mass_kg: 0.3", "mass_kg: 100"), {.element = "plant.tool.mass_kg", .file = "test.yaml"});
  expect_config_error(loading_plant_with("mass_kg: 1.25", "mass_kg: 100"), {.element = "plant.drop_test.mass_kg", .file = "test.yaml"});
  expect_config_error(loading_plant_with("q_rad: [0.0, 0.26179939,", "q_rad: [0.0, 180,"),
                      {.element = "plant.initial.q_rad[1]", .file = "test.yaml"});
}

// ------------------------------------------------------------------------------------- random
TEST(RandomGenerator, ReproducibleStreamsAndMoments) {
  phri::RandomGenerator a(42, 1), b(42, 1), c(42, 2);
  bool differs = false;
  for (int k = 0; k < 100; ++k) {
    const double x = a.normal();
    EXPECT_EQ(x, b.normal());
    differs = differs || x != c.normal();
  }
  EXPECT_TRUE(differs);
  phri::RandomGenerator r(7);
  const int n = 200000;
  double sum = 0, sum2 = 0, umin = 1, umax = 0;
  for (int k = 0; k < n; ++k) {
    const double x = r.normal();
    sum += x;
    sum2 += x * x;
    const double u = r.uniform();
    umin = std::min(umin, u);
    umax = std::max(umax, u);
  }
  EXPECT_NEAR(sum / n, 0.0, 5.0 / std::sqrt(n));
  EXPECT_NEAR(sum2 / n, 1.0, 0.02);
  EXPECT_GE(umin, 0.0);
  EXPECT_LT(umax, 1.0);
  EXPECT_EQ(r.normal(0.0), 0.0);
}

// fill_normal(count) is count calls of normal(), bit for bit, whatever the counts and a pending spare;
// and both are Box-Muller on the same uniforms within 2 ulp of libm's sine and cosine.
TEST(RandomGenerator, BatchedNormalsAreTheSequenceOfSingleOnes) {
  phri::RandomGenerator batched(9, 3), single(9, 3), uniforms(9, 3);
  std::vector<double> out(40);
  for (int count : {0, 1, 2, 3, 16, 17, 40, 5, 1, 31}) {
    batched.fill_normal(out.data(), count);
    for (int k = 0; k < count; ++k) ASSERT_EQ(out[static_cast<std::size_t>(k)], single.normal()) << count << " " << k;
  }
  // The same sequence from the uniforms with libm: pairs (r cos, r sin).
  phri::RandomGenerator again(9, 3);
  for (int pair = 0; pair < 500; ++pair) {
    const double u1 = 1.0 - uniforms.uniform(), u2 = uniforms.uniform();
    const double radius = std::sqrt(-2.0 * std::log(u1)), angle = 2.0 * std::numbers::pi * u2;
    for (const double expected : {radius * std::cos(angle), radius * std::sin(angle)}) {
      const double x = again.normal();
      EXPECT_LE(std::abs(x - expected), 2.0 * std::abs(radius) * 0x1p-52 + 1e-300) << pair;
    }
  }
}

// ------------------------------------------------------------------------- stick-slip friction
// One inertia I driven by a constant torque u against the friction model, integrated as the
// simulator does: semi-implicit Euler, the explicit friction torque from the state at the step
// start, the presliding damping implicit (as MuJoCo's Euler step treats joint damping):
//   v1 = (I v0 + dt (u + f)) / (I + dt c).
struct SingleJoint {
  double I = 0.3, dt = 0.00025, q = 0.0, qd = 0.0;
  phri::StickSlipFriction friction;
  SingleJoint(double coulomb, double stat)
      : friction(phri::StickSlipFriction::presliding(coulomb, stat, 0.03, 0.00025, 1e-3)) {
    friction.reset(0.0);
  }
  void run(double u, double seconds) {
    for (int k = 0; k < static_cast<int>(std::lround(seconds / dt)); ++k) {
      const double f = friction.update(q, qd);
      const double c = friction.damping();
      qd = (I * qd + dt * (u + f)) / (I + dt * c);
      q += dt * qd;
    }
  }
};

TEST(StickSlipFriction, SticksBelowTheStaticLevelAndSlidesAtTheCoulombLevel) {
  SingleJoint below(2.0, 2.5);
  below.run(2.4, 2.0);  // 96 % of the static level
  // Only the presliding deflection u / k remains: 2.4 / (0.03 * 2000^2) = 2e-5 rad, no drift.
  EXPECT_LT(std::abs(below.q), 2.5e-5);
  EXPECT_LT(std::abs(below.qd), 1e-6);
  EXPECT_FALSE(below.friction.sliding());

  SingleJoint above(2.0, 2.5);
  above.run(2.6, 0.5);
  // Breakaway, then sliding against exactly the Coulomb level: qdd = (2.6 - 2.0) / 0.3 = 2 rad/s^2.
  EXPECT_TRUE(above.friction.sliding());
  const double qd_half = above.qd;
  EXPECT_GT(qd_half, 0.8);
  above.run(2.6, 0.5);
  EXPECT_NEAR(above.qd - qd_half, 2.0 * 0.5, 1e-9);
  // Released: it decelerates at 2.0 / 0.3 rad/s^2, then sticks with no reversal.
  above.run(0.0, 0.5);
  EXPECT_FALSE(above.friction.sliding());
  EXPECT_LT(std::abs(above.qd), 1e-4);
  const double q_stop = above.q;
  above.run(0.0, 1.0);
  EXPECT_NEAR(above.q, q_stop, 1e-5);
}

// --------------------------------------------------------------------------- inertial mismatch
TEST(LinkInertial, PerturbationStaysWithinBoundsAndPhysical) {
  phri::RandomGenerator rng(11);
  // A nearly planar body (I1 + I2 = 1.001 I3) stresses the triangle inequality.
  const phri::LinkInertial planar{1.2, Eigen::Vector3d(0.01, -0.1, 0.02), Eigen::Vector3d(0.5, 0.5005, 1.0)};
  ASSERT_TRUE(planar.is_physical());
  for (int k = 0; k < 2000; ++k) {
    const auto p = planar.perturbed(0.05, 0.05, 0.05, rng);
    EXPECT_TRUE(p.is_physical());
    EXPECT_LE(std::abs(p.mass_kg / planar.mass_kg - 1.0), 0.05 + 1e-12);
    EXPECT_LE((p.com_m - planar.com_m).cwiseAbs().maxCoeff(), 0.05 * planar.com_m.norm() + 1e-12);
    for (int i = 0; i < 3; ++i) EXPECT_LE(p.principal_kgm2[i] / planar.principal_kgm2[i], 1.05 + 1e-12);
  }
  phri::RandomGenerator r1(5), r2(5);
  EXPECT_EQ(planar.perturbed(0.05, 0.05, 0.05, r1).mass_kg, planar.perturbed(0.05, 0.05, 0.05, r2).mass_kg);
}

// --------------------------------------------------------------------------------- disturbances
TEST(ExternalForce, Profiles) {
  phri::ExternalForce f;
  f.start_s = 1.0;
  f.duration_s = 0.5;
  f.profile = phri::ExternalForce::Profile::kStep;
  EXPECT_EQ(f.scale_at(0.999), 0.0);
  EXPECT_EQ(f.scale_at(1.0), 1.0);
  EXPECT_EQ(f.scale_at(1.499), 1.0);
  EXPECT_EQ(f.scale_at(1.5), 0.0);
  f.profile = phri::ExternalForce::Profile::kRamp;
  f.rise_s = 0.2;
  EXPECT_NEAR(f.scale_at(1.1), 0.5, 1e-12);
  EXPECT_NEAR(f.scale_at(1.3), 1.0, 1e-12);
  f.profile = phri::ExternalForce::Profile::kHalfSine;
  EXPECT_NEAR(f.scale_at(1.25), 1.0, 1e-12);
  EXPECT_NEAR(f.scale_at(1.125), std::sin(std::numbers::pi / 4), 1e-12);
}

TEST(RandomPushGenerator, PushesLieOnTheCapsuleAndRespectTheSettings) {
  phri::RandomPushSettings s;
  s.enabled = true;
  s.start_s = 0.5;
  s.min_interval_s = 0.1;
  s.max_interval_s = 0.4;
  s.min_force_N = 10.0;
  s.max_force_N = 200.0;
  s.min_duration_s = 0.05;
  s.max_duration_s = 0.2;
  phri::RandomPushGenerator::LinkSurface a{3, Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 0, -0.2), 0.045};
  phri::RandomPushGenerator::LinkSurface b{5, Eigen::Vector3d(0, 0.1, 0), Eigen::Vector3d(0.1, 0.1, 0), 0.03};
  phri::RandomPushGenerator gen(s, {a, b}, 99), twin(s, {a, b}, 99);
  std::uint32_t pushes = 0;
  double last_end = 0.0;
  for (double t = 0.0; t < 30.0; t += 0.001) {
    const auto* p = gen.active(t);
    const auto* q = twin.active(t);
    ASSERT_EQ(p == nullptr, q == nullptr);
    if (p == nullptr) continue;
    EXPECT_EQ(p->point_local, q->point_local);
    EXPECT_GE(t, 0.5);
    if (p->index != pushes) {
      pushes = p->index;
      EXPECT_GE(p->start_s - last_end, 0.1 - 1e-9);
      last_end = p->start_s + p->duration_s;
      EXPECT_GE(p->peak_force_N, 10.0);
      EXPECT_LE(p->peak_force_N, 200.0);
      EXPECT_GE(p->duration_s, 0.05);
      EXPECT_LE(p->duration_s, 0.2);
      const auto& link = p->body == 3 ? a : b;
      // Distance from the point to the capsule's segment = its radius; the force points inward.
      const Eigen::Vector3d axis = link.p1 - link.p0;
      const double u = std::clamp((p->point_local - link.p0).dot(axis) / axis.squaredNorm(), 0.0, 1.0);
      const Eigen::Vector3d radial = p->point_local - (link.p0 + u * axis);
      EXPECT_NEAR(radial.norm(), link.radius, 1e-12);
      EXPECT_NEAR(p->direction_local.norm(), 1.0, 1e-12);
      EXPECT_LE(p->direction_local.dot(radial), 0.0);
    }
  }
  EXPECT_GT(pushes, 30u);
}

}  // namespace
