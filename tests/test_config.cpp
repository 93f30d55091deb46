// ctest-labels: unit
// phri::Config: configs/demo.yaml loads into the settings of every piece (paths resolved, plant
// file merged with the overrides, the timeline sorted), and each class of mistake is a
// phri::ConfigError naming the key path.
#include <phri/app/loop_clock.hpp>
#include <phri/config/config.hpp>
#include <phri/core/error.hpp>

#include "config_error.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;
const std::string kDemo = kRoot + "/configs/demo.yaml";

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

phri::Config load_edited(const std::string& from, const std::string& to) {
  std::string yaml = read_file(kDemo);
  const auto pos = yaml.find(from);
  if (pos == std::string::npos) throw std::runtime_error("test bug: '" + from + "' not in demo.yaml");
  yaml.replace(pos, from.size(), to);
  return phri::Config::from_yaml_string(yaml, "test.yaml", kRoot + "/configs");
}

// Loading demo.yaml with `from` replaced by `to`, as a callable for expect_config_error.
std::function<void()> loading_demo_with(const std::string& from, const std::string& to) {
  return [from, to] { load_edited(from, to); };
}

using phri::test::expect_config_error;

TEST(Config, LoadsTheDemo) {
  const phri::Config c = phri::Config::from_yaml_file(kDemo);
  EXPECT_EQ(c.source, kDemo);
  // Robot files: resolved against configs/, and they exist.
  for (const std::string& path : {c.controller.urdf_path, c.controller.actuators_path, c.controller.collision_path,
                                  c.plant.mjcf_path, c.plant.actuators_path}) {
    EXPECT_TRUE(std::filesystem::path(path).is_absolute()) << path;
    EXPECT_TRUE(std::filesystem::is_regular_file(path)) << path;
  }
  EXPECT_EQ(std::filesystem::path(c.controller.urdf_path).filename(), "gen3.urdf");
  ASSERT_EQ(c.controller.payloads.size(), 2u);
  EXPECT_DOUBLE_EQ(c.controller.payloads[1].inertia.com.z(), 0.115);
  // Plant: plant_gen3.yaml (initial posture, noise) + the overrides (mismatch, disturbances).
  EXPECT_EQ(c.plant.dof(), 7);
  EXPECT_NEAR(c.plant.initial_q_rad[3], -2.26892803, 1e-12);
  EXPECT_DOUBLE_EQ(c.plant.noise.torque_sensor_std_Nm, 0.05);
  EXPECT_TRUE(c.plant.mismatch.enabled);
  EXPECT_EQ(c.plant.mismatch.seed, 7u);  // kept from the file: maps merge key by key
  ASSERT_EQ(c.plant.disturbances.size(), 4u);
  EXPECT_EQ(c.plant.disturbances[0].body, "forearm_link");
  EXPECT_EQ(c.plant.disturbances[3].force_N.y(), 10.0);
  // Controller.
  EXPECT_DOUBLE_EQ(c.controller.observer_gain, 50.0);
  EXPECT_EQ(c.controller.initial_compliance, phri::ComplianceMode::kNullSpace);
  EXPECT_EQ(c.controller.initial_loop, phri::LowLevelMode::kPosition);  // the start-up runs in Position
  EXPECT_DOUBLE_EQ(c.controller.compliance.touch_threshold, 8.0);
  EXPECT_DOUBLE_EQ(c.controller.wrench_trigger_filter_s, 0.01);
  EXPECT_DOUBLE_EQ(c.controller.qp.collision.safety_distance, 0.015);
  EXPECT_DOUBLE_EQ(c.controller.qp.joint_influence_fraction, 0.1);
  EXPECT_DOUBLE_EQ(c.controller.custom_torque.transfer_gain, 5.0);
  // FSM and timeline.
  EXPECT_EQ(c.fsm.torque_loop, phri::LowLevelMode::kCurrent);
  EXPECT_EQ(c.fsm.first_scenario, phri::Scenario::kStatic);
  EXPECT_EQ(c.fsm.static_scenario.posture_q_rad, phri::paper_posture_target());
  EXPECT_DOUBLE_EQ(c.fsm.dynamic_scenario.vertical_angular_frequency_rad_s, 3.0);
  EXPECT_FALSE(c.fsm.dynamic_scenario.compliance.has_value());
  ASSERT_EQ(c.fsm.timeline.size(), 10u);
  EXPECT_EQ(c.fsm.timeline.front().event, phri::Event::kFullBodyCompliance);
  EXPECT_EQ(c.fsm.timeline.back().event, phri::Event::kStop);
  for (std::size_t i = 1; i < c.fsm.timeline.size(); ++i) EXPECT_LE(c.fsm.timeline[i - 1].time_s, c.fsm.timeline[i].time_s);
  // Logging, gamepad, run.
  EXPECT_TRUE(c.logging_enabled);
  EXPECT_EQ(c.logging.path, "phri_demo.csv");
  EXPECT_EQ(c.logging.dof, 7);
  EXPECT_TRUE(c.gamepad.enabled);
  EXPECT_DOUBLE_EQ(c.gamepad.mapping.trigger_release, 0.3);
  EXPECT_EQ(c.run.pacing, phri::LoopClock::Pacing::kRealTime);
  EXPECT_GT(c.run.duration_s, 32.0);
}

TEST(Config, EveryDemoKeyIsCommented) {
  // The reference file documents each key on its line (or, for list items, on the list's line).
  std::istringstream in(read_file(kDemo));
  std::string line;
  int number = 0;
  while (std::getline(in, line)) {
    ++number;
    const auto first = line.find_first_not_of(' ');
    if (first == std::string::npos || line[first] == '#') continue;
    if (line[first] == '-' ) continue;  // list items: documented by their list's comment
    EXPECT_NE(line.find('#'), std::string::npos) << "demo.yaml:" << number << " has no comment: " << line;
  }
}

// Named by a path relative to the working directory, as `phri run --config configs/demo.yaml`
// does: every input file (the plant's too, resolved twice: here and by the plant's loader) exists.
TEST(Config, RelativeConfigPathFromTheWorkingDirectory) {
  const std::filesystem::path before = std::filesystem::current_path();
  std::filesystem::current_path(kRoot);
  try {
    const phri::Config c = phri::Config::from_yaml_file("configs/demo.yaml");
    for (const std::string& path : {c.controller.urdf_path, c.controller.actuators_path, c.controller.collision_path,
                                    c.plant.mjcf_path, c.plant.actuators_path}) {
      EXPECT_TRUE(std::filesystem::is_regular_file(path)) << path;
    }
  } catch (const phri::ConfigError& e) {
    ADD_FAILURE() << e.what();
  }
  std::filesystem::current_path(before);
}

TEST(Config, MinimalFileTakesTheDefaults) {
  const std::string yaml =
      "robot: {urdf: ../robots/kinova_gen3/gen3.urdf, actuators: ../robots/kinova_gen3/actuators.yaml, end_effector_frame: end_effector_link}\n"
      "plant: {file: plant_gen3.yaml}\n";
  const phri::Config c = phri::Config::from_yaml_string(yaml, "minimal.yaml", kRoot + "/configs");
  EXPECT_TRUE(c.controller.collision_path.empty());  // no collision key: no self-collision constraint
  EXPECT_FALSE(c.plant.mismatch.enabled);
  EXPECT_TRUE(c.fsm.timeline.empty());
  EXPECT_DOUBLE_EQ(c.controller.observer_gain, phri::ControllerSettings{}.observer_gain);
  EXPECT_TRUE(c.controller.payloads.empty());  // the library knows no arm's end of arm
  EXPECT_EQ(c.controller.ft_sensor_mount.matrix(), Eigen::Matrix4d::Identity());
  EXPECT_EQ(c.controller.wrench.tool_mass_kg, 0.0);
  EXPECT_EQ(c.fsm.startup.home_q_rad, phri::paper_posture_target());
}

TEST(Config, InlinePlantResolvesItsPathsAgainstThisFile) {
  std::string plant_file = read_file(kRoot + "/configs/plant_gen3.yaml");
  // Indent the plant file's section under our own `plant:` key.
  const std::string body = plant_file.substr(plant_file.find("plant:\n") + 7);
  const std::string yaml =
      "robot: {urdf: ../robots/kinova_gen3/gen3.urdf, actuators: ../robots/kinova_gen3/actuators.yaml, end_effector_frame: end_effector_link}\n"
      "plant:\n" + body;
  const phri::Config c = phri::Config::from_yaml_string(yaml, "inline.yaml", kRoot + "/configs");
  EXPECT_TRUE(std::filesystem::is_regular_file(c.plant.mjcf_path)) << c.plant.mjcf_path;
  EXPECT_NEAR(c.plant.noise.torque_sensor_offset_Nm[0], 0.15, 1e-12);
}

TEST(Config, UnknownKeysNameTheirPath) {
  expect_config_error(loading_demo_with("robot:                                   # the controller's",
                                        "colour: red\nrobot:                                   # the controller's"),
                      {.element = "colour", .mentions = {"unknown key"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("    collision:                           # the same damper",
                                        "    collision:\n      flavour: 1\n    # "),
                      {.element = "controller.qp.collision.flavour", .mentions = {"unknown key"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("  seed: 1 ", "  colour: 1\n  seed: 1 "),
                      {.element = "plant.colour", .mentions = {"unknown key"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("  - {at: 8.0, event: full_body_compliance}",
                                        "  - {at: 8.0, event: full_body_compliance, when: now}"),
                      {.element = "events[0].when", .mentions = {"unknown key"}, .file = "test.yaml"});
}

TEST(Config, DeclaredConstraintsAreCheckedAtLoad) {
  const std::string posture = "    - {type: posture, name: posture}     # the null-space task\n";
  const phri::Config ok = load_edited(
      posture, posture + "  constraints:\n    - {type: plane, name: table, frame: end_effector, offset_m: 0.05}\n");
  ASSERT_EQ(ok.controller.constraints.size(), 1u);
  EXPECT_EQ(ok.controller.constraints[0].type, "plane");
  EXPECT_EQ(ok.controller.constraints[0].numbers.at("offset_m"), std::vector<double>{0.05});
  expect_config_error(loading_demo_with(posture, posture + "  constraints:\n    - {type: plane, name: t, ofset_m: 0.05}\n"),
                      {.element = "controller.constraints[0].ofset_m", .mentions = {"unknown key for a plane constraint"},
                       .file = "test.yaml"});
  expect_config_error(loading_demo_with(posture, posture + "  constraints:\n    - {type: joint_limits, name: j}\n"),
                      {.element = "controller.constraints[0].type", .mentions = {"always on"}, .file = "test.yaml"});
}

TEST(Config, WrongTypesNameTheirPath) {
  expect_config_error(loading_demo_with("observer_gain: 50.0", "observer_gain: fast"),
                      {.element = "controller.observer_gain", .mentions = {"expected a number"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("  enabled: true                          # no pad", "  enabled: maybe  #"),
                      {.element = "gamepad.enabled", .mentions = {"true or false"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("home_q_rad: [0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57]", "home_q_rad: 0.58"),
                      {.element = "fsm.startup.home_q_rad", .file = "test.yaml"});
  expect_config_error(loading_demo_with("initial_mode: null_space", "initial_mode: floppy"),
                      {.element = "controller.compliance.initial_mode", .mentions = {"one of"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("{at: 12.0, event: dual_compliance}", "{at: 12.0, event: double_compliance}"),
                      {.element = "events[1].event", .mentions = {"unknown event"}, .file = "test.yaml"});
}

TEST(Config, ExternalTorqueSourceIsChosenByName) {
  EXPECT_EQ(load_edited("external_torque_source: observer", "external_torque_source: fused").controller.external_torque_source,
            phri::ExternalTorqueSource::kFused);
  EXPECT_EQ(load_edited("external_torque_source: observer", "external_torque_source: ft").controller.external_torque_source,
            phri::ExternalTorqueSource::kForceTorqueSensor);
  expect_config_error(loading_demo_with("external_torque_source: observer", "external_torque_source: both"),
                      {.element = "controller.external_torque_source", .mentions = {"one of"}, .file = "test.yaml"});
}

TEST(Config, SectionOfTheWrongKind) {
  const std::string head =
      "robot: {urdf: ../robots/kinova_gen3/gen3.urdf, actuators: ../robots/kinova_gen3/actuators.yaml, end_effector_frame: end_effector_link}\n"
      "plant: {file: plant_gen3.yaml}\n";
  for (const auto& [text, key] : {std::pair<std::string, std::string>{"controller: {compliance: 3}", "controller.compliance"},
                                  {"events: {at: 1}", "events"},
                                  {"fsm: [1, 2]", "fsm"}}) {
    SCOPED_TRACE(text);
    expect_config_error([&] { phri::Config::from_yaml_string(head + text + "\n", "t.yaml", kRoot + "/configs"); },
                        {.element = key, .file = "t.yaml"});
  }
}

TEST(Config, OutOfRangeValuesNameTheirPath) {
  expect_config_error(
      loading_demo_with("posture_damping: 9.0", "posture_damping: -9.0"),
      {.element = "controller.compliance.posture_damping", .mentions = {"must be in"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("observer_gain: 50.0", "observer_gain: 0"),
                      {.element = "controller.observer_gain", .mentions = {"> 0"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("velocity_limit_fraction: 0.9", "velocity_limit_fraction: 1.5"),
                      {.element = "controller.qp.velocity_limit_fraction", .file = "test.yaml"});
  expect_config_error(loading_demo_with("      amortization: 1.8                  # [-] M >= 1 (overdamped)",
                                        "      amortization: 0.5"),
                      {.element = "controller.qp.joint_limits.amortization", .file = "test.yaml"});
  expect_config_error(loading_demo_with("transfer_gain: 5.0", "transfer_gain: -1"),
                      {.element = "low_level.custom.transfer_gain", .file = "test.yaml"});
  expect_config_error(loading_demo_with("trigger_filter_s: 0.01", "trigger_filter_s: -0.01"),
                      {.element = "controller.compliance.trigger_filter_s", .file = "test.yaml"});
  expect_config_error(loading_demo_with("integral_limit_fraction: 0.05", "integral_limit_fraction: 2"),
                      {.element = "low_level.custom.integral_limit_fraction", .file = "test.yaml"});
  expect_config_error(loading_demo_with("stiffness_step: 1.25", "stiffness_step: 0.8"),
                      {.element = "fsm.stiffness_step", .file = "test.yaml"});
  expect_config_error(loading_demo_with("buffer_rows: 16384", "buffer_rows: 4"),
                      {.element = "logging.buffer_rows", .file = "test.yaml"});
  expect_config_error(loading_demo_with("{at: 34.0, event: stop}", "{at: 99.0, event: stop}"),
                      {.element = "events[9].at", .mentions = {"after the end of the run"}, .file = "test.yaml"});
  expect_config_error(
      loading_demo_with("{at: 8.0, event: full_body_compliance}", "{at: -1, event: full_body_compliance}"),
      {.element = "events[0].at", .file = "test.yaml"});
  expect_config_error(loading_demo_with("torque_loop: custom", "torque_loop: position"),
                      {.element = "low_level.torque_loop", .mentions = {"one of"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("pacing: real_time", "pacing: leisurely"),
                      {.element = "run.pacing", .file = "test.yaml"});
  // ... inside the plant file's section, through the override.
  expect_config_error(loading_demo_with("  seed: 1 ", "  noise: {torque_sensor_std_Nm: -1}\n  seed: 1 "),
                      {.element = "plant.noise.torque_sensor_std_Nm", .file = "test.yaml"});
}

// Values that loaded and then meant nothing (issue 37): each refused naming its key; the ends of
// the ranges still load.
TEST(Config, NonsenseValuesNameTheirKey) {
  expect_config_error(loading_demo_with("safety_distance_m: 0.015", "safety_distance_m: 0"),
                      {.element = "controller.qp.collision.safety_distance_m", .mentions = {"> 0"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("velocity_limit_fraction: 0.9", "velocity_limit_fraction: 1e-9"),
                      {.element = "controller.qp.velocity_limit_fraction", .mentions = {"[0.05, 1]"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("bias_samples: 200", "bias_samples: 0"),
                      {.element = "controller.wrench.bias_samples", .mentions = {"[1, 1000000]"}, .file = "test.yaml"});
  EXPECT_DOUBLE_EQ(load_edited("safety_distance_m: 0.015", "safety_distance_m: 0.001").controller.qp.collision.safety_distance, 0.001);
  EXPECT_DOUBLE_EQ(load_edited("velocity_limit_fraction: 0.9", "velocity_limit_fraction: 0.05").controller.qp.velocity_limit_fraction, 0.05);
  EXPECT_EQ(load_edited("bias_samples: 200", "bias_samples: 1").controller.wrench.bias_samples, 1);
}

// The reader's bounds (tests/test_yaml_reader.cpp) on a whole configuration: an alias bomb added
// to the demo is refused at load, naming the file.
TEST(Config, AnAliasBombIsRefusedAtLoad) {
  std::string bomb = "lol: &l0 [lol, lol, lol, lol, lol, lol, lol, lol, lol]\n";
  for (int level = 1; level < 9; ++level) {
    const std::string n = std::to_string(level), previous = std::to_string(level - 1);
    bomb.append("lol").append(n).append(": &l").append(n).append(" [");
    for (int i = 0; i < 9; ++i) bomb.append(i == 0 ? "*l" : ", *l").append(previous);
    bomb.append("]\n");
  }
  expect_config_error(loading_demo_with("run:                                     # the run itself", bomb + "run:"),
                      {.mentions = {"alias bomb"}, .file = "test.yaml"});
}

// Sizes that would exhaust memory before the run starts: run.duration_s (one cycle time per period
// is kept) and logging.buffer_rows (the log ring, ~700 B a row).
TEST(Config, RunLengthAndLogRingAreCapped) {
  expect_config_error(loading_demo_with("duration_s: 35.5", "duration_s: 1e9"),
                      {.element = "run.duration_s", .mentions = {"at most 3600 s"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("duration_s: 35.5", "duration_s: 3600.5"),
                      {.element = "run.duration_s", .mentions = {"at most 3600 s"}, .file = "test.yaml"});
  EXPECT_DOUBLE_EQ(load_edited("duration_s: 35.5", "duration_s: 3600").run.duration_s, 3600.0);
  expect_config_error(loading_demo_with("buffer_rows: 16384", "buffer_rows: 4194304"),
                      {.element = "logging.buffer_rows", .mentions = {"100 MiB"}, .file = "test.yaml"});
  const std::size_t max_rows = phri::log_ring_max_rows();
  EXPECT_LE(max_rows * sizeof(phri::LogRow), phri::kLogRingMaxBytes);
  EXPECT_GT(2 * max_rows * sizeof(phri::LogRow), phri::kLogRingMaxBytes);
  EXPECT_EQ(load_edited("buffer_rows: 16384", "buffer_rows: " + std::to_string(max_rows)).logging.capacity_rows, max_rows);
  expect_config_error(loading_demo_with("buffer_rows: 16384", "buffer_rows: " + std::to_string(max_rows + 1)),
                      {.element = "logging.buffer_rows", .file = "test.yaml"});
}

// Physical ranges and the checks against the robot the file names (the corpus,
// tests/config_corpus, covers every one end to end through `phri run`).
TEST(Config, PhysicalRangesNameTheKeyPath) {
  // The discrete observer rings for K T > 1 and diverges for K T > 2.
  expect_config_error(loading_demo_with("observer_gain: 50.0", "observer_gain: 2500.0"),
                      {.element = "controller.observer_gain", .mentions = {"period_s", "< 1"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("mass_kg: 0.3                       # [kg]", "mass_kg: 100 #"),
                      {.element = "robot.payloads[1].mass_kg", .file = "test.yaml"});
  expect_config_error(loading_demo_with("mass_kg: 0.26931", "mass_kg: .nan"),
                      {.element = "robot.payloads[0].mass_kg", .mentions = {"finite"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("# torque_limit_Nm: [95, 95, 95, 95, 26, 45, 26]",
                                        "torque_limit_Nm: [500, 95, 95, 95, 26, 45, 26] #"),
                      {.element = "controller.qp.torque_limit_Nm[0]", .mentions = {"drive maximum"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("# velocity_limit_rad_s: [2.09,", "velocity_limit_rad_s: [120,"),
                      {.element = "controller.qp.velocity_limit_rad_s[0]", .file = "test.yaml"});
  expect_config_error(loading_demo_with("transfer_gain: 5.0", "transfer_gain: 500"),
                      {.element = "low_level.custom.transfer_gain", .file = "test.yaml"});
  expect_config_error(loading_demo_with("posture_damping: 9.0", "posture_damping: 5000"),
                      {.element = "controller.compliance.posture_damping", .file = "test.yaml"});
}

TEST(Config, EndEffectorFrameMustBeMovedByEveryJoint) {
  expect_config_error(loading_demo_with("end_effector_frame: end_effector_link", "end_effector_frame: base_link"),
                      {.element = "robot.end_effector_frame", .mentions = {"not moved by any joint"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("end_effector_frame: end_effector_link", "end_effector_frame: forearm_link"),
                      {.element = "robot.end_effector_frame", .mentions = {"upstream"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("end_effector_frame: end_effector_link", "end_effector_frame: nowhere"),
                      {.element = "robot.end_effector_frame", .mentions = {"no frame"}, .file = "test.yaml"});
  EXPECT_NO_THROW(load_edited("end_effector_frame: end_effector_link", "end_effector_frame: bracelet_link"));
}

TEST(Config, PosturesWithinTheJointLimitsAndClearOfCollision) {
  const std::string posture = "posture_q_rad: [0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57]";
  const std::string home = "home_q_rad: [0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57]";
  expect_config_error(loading_demo_with(home, "home_q_rad: [0.0, 0.58, 3.14, -2.8, 0.0, 0.85, 1.57]"),
                      {.element = "fsm.startup.home_q_rad[3]", .mentions = {"joint_4", "2.57"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with(posture, "posture_q_rad: [0.0, 0.58, 3.14, -1.84, 0.0, 2.5, 1.57]"),
                      {.element = "fsm.static.posture_q_rad[5]", .mentions = {"joint_6"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("  seed: 1 ", "  initial: {q_rad: [0, 3.0, 0, 0, 0, 0, 0]}\n  seed: 1 "),
                      {.element = "plant.initial.q_rad[1]", .mentions = {"joint_2"}, .file = "test.yaml"});
  // Folded: the wrist on the base, within every joint limit.
  expect_config_error(loading_demo_with(posture, "posture_q_rad: [0.0, 2.2, 0.0, 2.5, 0.0, 2.0, 0.0]"),
                      {.element = "fsm.static.posture_q_rad", .mentions = {"self-collision", "base_link"}, .file = "test.yaml"});
  // Without a collision model, only the limits are checked.
  std::string yaml = read_file(kDemo);
  yaml.replace(yaml.find(posture), posture.size(), "posture_q_rad: [0.0, 2.2, 0.0, 2.5, 0.0, 2.0, 0.0]");
  const std::string collision = "collision: ../robots/kinova_gen3/collision.yaml";
  yaml.replace(yaml.find(collision), collision.size(), "collision: ''");
  EXPECT_NO_THROW(phri::Config::from_yaml_string(yaml, "test.yaml", kRoot + "/configs"));
}

TEST(Config, InconsistentPairsNameTheKeyThatMustChange) {
  expect_config_error(
      loading_demo_with("safety_distance_m: 0.015", "safety_distance_m: 0.03"),
      {.element = "controller.qp.collision.safety_distance_m", .mentions = {"d_s < d_i"}, .file = "test.yaml"});
  expect_config_error(
      loading_demo_with("safety_fraction: 0.01", "safety_fraction: 0.2"),
      {.element = "controller.qp.joint_limits.safety_fraction", .mentions = {"d_s < d_i"}, .file = "test.yaml"});
  expect_config_error(
      loading_demo_with("release_threshold: 4.0", "release_threshold: 8.0"),
      {.element = "controller.compliance.release_threshold", .mentions = {"touch_threshold"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("trigger_release: 0.3", "trigger_release: 0.6"),
                      {.element = "gamepad.trigger_release", .file = "test.yaml"});
  expect_config_error(
      loading_demo_with("horizontal_turn_acceleration_m_s2: 0.5", "horizontal_turn_acceleration_m_s2: 0.01"),
      {.element = "fsm.dynamic.horizontal_speed_m_s", .mentions = {"span"}, .file = "test.yaml"});
  expect_config_error(
      loading_demo_with("posture_q_rad: [0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57]", "posture_q_rad: [0.0, 0.58, 3.14]"),
      {.element = "fsm.static.posture_q_rad", .mentions = {"expected 7 numbers"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("period_s: 0.001", "period_s: 0.002"),
                      {.element = "controller.period_s", .mentions = {"plant"}, .file = "test.yaml"});
}

// yaml-cpp keeps the first of two equal keys silently, and the loaders took `key:` (null) as
// absent, i.e. the default: both are refused at load, naming the key path.
TEST(Config, DuplicateKeysAndExplicitNullsAreRefused) {
  expect_config_error(loading_demo_with("observer_gain: 50.0", "observer_gain: 50.0\n  observer_gain: 5000.0"),
                      {.element = "controller.observer_gain", .mentions = {"duplicate key"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("run:                                     # the run itself",
                                        "run:\n  pacing: lockstep\nrun:"),
                      {.element = "run", .mentions = {"duplicate key"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("  - {at: 8.0, event: full_body_compliance}",
                                        "  - {at: 8.0, at: 9.0, event: full_body_compliance}"),
                      {.element = "events[0].at", .mentions = {"duplicate key"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("observer_gain: 50.0", "observer_gain:"),
                      {.element = "controller.observer_gain", .mentions = {"null"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("observer_gain: 50.0", "observer_gain: ~"),
                      {.element = "controller.observer_gain", .mentions = {"null"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("ramp_s: 2.0", "ramp_s: null"),
                      {.element = "fsm.dynamic.ramp_s", .mentions = {"null"}, .file = "test.yaml"});
  // ... and in the plant file named by `plant.file` (a copy of plant_gen3.yaml with a duplicate).
  const std::string plant = read_file(kRoot + "/configs/plant_gen3.yaml");
  const std::string copy = (std::filesystem::temp_directory_path() / "phri_test_config_plant_dup.yaml").string();
  {
    std::string edited = plant;
    edited.replace(edited.find("  seed: 1 "), 10, "  seed: 2\n  seed: 1 ");
    std::ofstream(copy) << edited;
  }
  expect_config_error(loading_demo_with("file: plant_gen3.yaml", "file: " + copy),
                      {.element = "plant.seed", .mentions = {"duplicate key"}, .file = copy});
  std::filesystem::remove(copy);
}

TEST(Config, FilesAndSyntax) {
  expect_config_error(
      loading_demo_with("urdf: ../robots/kinova_gen3/gen3.urdf", "urdf: ../robots/kinova_gen3/nothing.urdf"),
      {.element = "robot.urdf", .mentions = {"file not found"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("file: plant_gen3.yaml", "file: no_plant.yaml"),
                      {.element = "plant.file", .mentions = {"file not found"}, .file = "test.yaml"});
  expect_config_error(loading_demo_with("robot:                                   # the controller's model",
                                        "robots:                                  # typo"),
                      {.element = "robots", .mentions = {"unknown key"}, .file = "test.yaml"});
  expect_config_error([&] { phri::Config::from_yaml_string("robot: [unclosed", "broken.yaml", kRoot + "/configs"); },
                      {.mentions = {"invalid YAML"}, .file = "broken.yaml"});
  const std::string absent = kRoot + "/configs/absent.yaml";
  expect_config_error([&] { phri::Config::from_yaml_file(absent); }, {.file = absent});
  // A missing required section.
  expect_config_error(
      [&] { phri::Config::from_yaml_string("plant: {file: plant_gen3.yaml}\n", "t.yaml", kRoot + "/configs"); },
      {.element = "robot", .file = "t.yaml"});
}

}  // namespace
