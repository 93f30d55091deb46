// ctest-labels: unit integration
// Robot bundles (robots/<robot>/robot.yaml, config/robot_bundle.hpp): the Gen3's bundle gives the run
// exactly the settings configs/demo.yaml spells out key by key (so the Gen3's figures do not move);
// each class of mistake in a robot.yaml is a one-line ConfigError naming robot.yaml and the key path;
// a generated arm's bundle with no plant section runs on the plant generated from its URDF.
#include <phri/config/config.hpp>
#include <phri/config/robot_bundle.hpp>
#include <phri/control/controller.hpp>
#include <phri/lowlevel/custom_torque_controller.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/sim/sim_robot.hpp>

#include "config_error.hpp"
#include "generated_arm.hpp"
#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <sstream>

namespace {

using phri::test::expect_config_error;

const std::string kRoot = PHRI_SOURCE_DIR;
const std::string kDemo = kRoot + "/configs/demo.yaml";
const std::string kGen3 = kRoot + "/robots/kinova_gen3";

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// demo.yaml with its explicit `robot:` map replaced by `robot: <value>`.
std::string demo_with_robot(const std::string& value) {
  std::string yaml = read_file(kDemo);
  const std::size_t begin = yaml.find("\nrobot:");
  const std::size_t end = yaml.find("\nplant:");
  yaml.replace(begin, end - begin, "\nrobot: " + value + "\n");
  return yaml;
}

void expect_same_payloads(const std::vector<phri::Payload>& a, const std::vector<phri::Payload>& b) {
  ASSERT_EQ(a.size(), b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(a[i].name, b[i].name);
    EXPECT_EQ(a[i].frame, b[i].frame);
    EXPECT_EQ(a[i].inertia.mass, b[i].inertia.mass);
    EXPECT_EQ(a[i].inertia.com, b[i].inertia.com);
    EXPECT_EQ(a[i].inertia.inertia_com, b[i].inertia.inertia_com);
  }
}

void expect_same_robot(const phri::Config& bundled, const phri::Config& spelled_out) {
  const phri::ControllerSettings &a = bundled.controller, &b = spelled_out.controller;
  EXPECT_EQ(std::filesystem::canonical(a.urdf_path), std::filesystem::canonical(b.urdf_path));
  EXPECT_EQ(std::filesystem::canonical(a.actuators_path), std::filesystem::canonical(b.actuators_path));
  EXPECT_EQ(std::filesystem::canonical(a.collision_path), std::filesystem::canonical(b.collision_path));
  EXPECT_EQ(a.end_effector_frame, b.end_effector_frame);
  EXPECT_EQ(a.ft_sensor_mount.matrix(), b.ft_sensor_mount.matrix());
  expect_same_payloads(a.payloads, b.payloads);
  EXPECT_EQ(a.wrench.tool_mass_kg, b.wrench.tool_mass_kg);
  EXPECT_EQ(a.wrench.tool_com_m, b.wrench.tool_com_m);
  // The dead band the QP gets: per joint from the bundle, by actuator size from demo.yaml.
  EXPECT_EQ(phri::Controller(a).qp().compliance_deadband(), phri::Controller(b).qp().compliance_deadband());
  // The same model (chain, frames, payloads).
  const phri::Model ma = phri::Model::from_urdf_file(a.urdf_path, phri::Controller::model_options(a));
  const phri::Model mb = phri::Model::from_urdf_file(b.urdf_path, phri::Controller::model_options(b));
  EXPECT_EQ(ma.tip_link(), mb.tip_link());
  EXPECT_EQ(ma.total_mass(), mb.total_mass());
  const phri::SimRobotConfig &p = bundled.plant, &q = spelled_out.plant;
  EXPECT_EQ(std::filesystem::canonical(p.arm_file()), std::filesystem::canonical(q.arm_file()));
  EXPECT_EQ(p.ft_sensor.flange_site, q.ft_sensor.flange_site);
  EXPECT_EQ(p.ft_sensor.sensor_mount.matrix(), q.ft_sensor.sensor_mount.matrix());
  EXPECT_EQ(p.ft_sensor.flange_side_mass_kg, q.ft_sensor.flange_side_mass_kg);
  EXPECT_EQ(p.ft_sensor.flange_side_com_m, q.ft_sensor.flange_side_com_m);
  EXPECT_EQ(p.ft_sensor.flange_side_inertia_kgm2, q.ft_sensor.flange_side_inertia_kgm2);
  EXPECT_EQ(p.tool.mass_kg, q.tool.mass_kg);
  EXPECT_EQ(p.tool.com_m, q.tool.com_m);
  EXPECT_EQ(p.tool.inertia_kgm2, q.tool.inertia_kgm2);
  EXPECT_EQ(p.initial_q_rad, q.initial_q_rad);
  EXPECT_EQ(p.dof(), q.dof());
}

TEST(RobotBundle, TheGen3BundleGivesWhatTheDemoSpellsOut) {
  const phri::Config spelled_out = phri::Config::from_yaml_file(kDemo);
  expect_same_robot(phri::Config::from_yaml_string(demo_with_robot("../robots/kinova_gen3"), "bundled.yaml",
                                                   kRoot + "/configs"),
                    spelled_out);
  // `phri run --robot DIR`: the folder replaces the file's robot.
  expect_same_robot(phri::Config::from_yaml_file(kDemo, kGen3), spelled_out);
}

// ------------------------------------------------------------------------------ hostile robot.yaml
// A copy of the Gen3 bundle with robot.yaml edited (`from` -> `to`), in its own folder.
std::string gen3_bundle_with(const std::string& from, const std::string& to) {
  static int count = 0;
  const std::string folder = phri::test::temp_path("phri_test_robot_bundle", "bundle_" + std::to_string(count++));
  std::filesystem::create_directories(folder);
  for (const char* file : {"gen3.urdf", "actuators.yaml", "collision.yaml", "gen3_plant.xml"}) {
    std::filesystem::copy_file(kGen3 + "/" + file, folder + "/" + file);
  }
  std::string yaml = read_file(kGen3 + "/robot.yaml");
  const std::size_t at = yaml.find(from);
  if (at == std::string::npos) throw std::runtime_error("test bug: '" + from + "' not in robot.yaml");
  yaml.replace(at, from.size(), to);
  std::ofstream(folder + "/robot.yaml") << yaml;
  return folder;
}

void expect_bundle_error(const std::string& from, const std::string& to, const std::string& key,
                         const std::vector<std::string>& mentions = {}) {
  const std::string folder = gen3_bundle_with(from, to);
  const auto error = expect_config_error([&] { (void)phri::RobotBundle::from_folder(folder); },
                                         {.element = key, .mentions = mentions, .file = folder + "/robot.yaml"});
  if (error) {
    EXPECT_EQ(std::string(error->what()).find('\n'), std::string::npos);
  }
}

TEST(RobotBundle, MistakesNameRobotYamlAndTheKeyPath) {
  expect_bundle_error("name: kinova_gen3", "name: kinova_gen3\ncolour: red", "colour", {"unknown"});
  expect_bundle_error("urdf: gen3.urdf", "urdf: gen4.urdf", "urdf", {"not found"});
  expect_bundle_error("  end_effector: end_effector_link", "  effector: end_effector_link", "frames.effector");
  expect_bundle_error("    mass_kg: 0.3 ", "    mass_kg: 0 ", "end_of_arm.tool.mass_kg", {"> 0"});
  expect_bundle_error("    mass_kg: 0.3 ", "    mass_kg: 300 ", "end_of_arm.tool.mass_kg");
  expect_bundle_error("inertia_kgm2: [3.4e-4, 7.3e-4, 8.9e-4]", "inertia_kgm2: [3.4e-4, 7.3e-4, 8.9e-2]",
                      "end_of_arm.tool.inertia_kgm2", {"triangle"});
  expect_bundle_error("home_q_rad: [0.0, 0.26179939,", "home_q_rad: [0.26179939,", "home_q_rad");
  expect_bundle_error("home_q_rad: [0.0,", "home_q_rad: [90.0,", "home_q_rad[0]");
  expect_bundle_error("compliance_deadband_Nm: [1.0,", "compliance_deadband_Nm: [-1.0,", "compliance_deadband_Nm[0]");
  expect_bundle_error("drive: kinova", "drive: franka", "drive", {"kinova"});
  expect_bundle_error("  mjcf: gen3_plant.xml", "  mjcf: gen3_plant.xml\n  balance_inertia: true", "plant.balance_inertia");
  expect_bundle_error("locked_joints: []", "locked_joints: {a: 1}", "locked_joints");
  // H(z) of the custom loop: a pole on or outside the unit circle, a missing half, a0 = 0.
  expect_bundle_error("denominator: [1.0, -1.975063, 0.97518]", "denominator: [1.0, -2.0, 1.0]",
                      "custom_loop_filter.denominator", {"unit circle"});
  expect_bundle_error("denominator: [1.0, -1.975063, 0.97518]", "denominator: [1.0, 0.5, -1.2]",
                      "custom_loop_filter.denominator", {"unit circle"});
  expect_bundle_error("  denominator: [1.0, -1.975063, 0.97518]", "", "custom_loop_filter.denominator");
  expect_bundle_error("denominator: [1.0, -1.975063, 0.97518]", "denominator: [0.0, 1.0]", "custom_loop_filter.denominator",
                      {"a0"});
  expect_config_error([] { (void)phri::RobotBundle::from_folder("/nonexistent"); }, {.mentions = {"robot.yaml"}});
  // Through a run YAML: a folder without robot.yaml names the key `robot`.
  expect_config_error([] { (void)phri::Config::from_yaml_string(demo_with_robot("../robots"), "t.yaml", kRoot + "/configs"); },
                      {.element = "robot", .mentions = {"robot.yaml"}});
}

// Checked against the URDF's model at load, named at the robot.yaml key that causes them.
TEST(RobotBundle, FramesChainDrivesAndHomeAreCheckedAgainstTheUrdf) {
  expect_bundle_error("  end_effector: end_effector_link", "  end_effector: hand_link", "frames.end_effector", {"hand_link"});
  expect_bundle_error("  tip: bracelet_link", "  tip: nowhere", "frames.tip", {"nowhere"});
  expect_bundle_error("  base: base_link", "  base: end_effector_link", "frames.tip", {"not below base"});
  // A base below joints that move: they would carry it, the base is fixed in the world.
  expect_bundle_error("  base: base_link", "  base: forearm_link", "frames.base", {"joint_4", "fixed in the world"});
  // Those joints locked, a shorter chain is a valid choice, but then the drives no longer match it.
  {
    const std::string folder = gen3_bundle_with("  base: base_link", "  base: forearm_link");
    std::string yaml = read_file(folder + "/robot.yaml");
    const std::string key = "locked_joints: []";
    yaml.replace(yaml.find(key), key.size(), "locked_joints: [joint_1, joint_2, joint_3, joint_4]");
    std::ofstream(folder + "/robot.yaml") << yaml;
    expect_config_error([&] { (void)phri::RobotBundle::from_folder(folder); },
                        {.element = "actuators", .mentions = {"joint_5"}, .file = folder + "/robot.yaml"});
  }
  expect_bundle_error("locked_joints: []", "locked_joints: [joint_9]", "locked_joints", {"joint_9"});
  expect_bundle_error("home_q_rad: [0.0, 0.26179939,", "home_q_rad: [0.0, 2.5,", "home_q_rad[1]", {"joint_2", "2.24"});
  // A run through the CLI's path gets the same error.
  const std::string folder = gen3_bundle_with("  end_effector: end_effector_link", "  end_effector: hand_link");
  expect_config_error([&] { (void)phri::Config::from_yaml_file(kDemo, folder); }, {.element = "frames.end_effector"});
}

// The bundle's H(z) reaches the custom torque loop: with H = 1 the filter term is lambda e on the
// first update; with the Gen3 bundle's (Kinova's) it is lambda b0 e, as with the library's default.
TEST(RobotBundle, TheCustomLoopFilterComesFromTheBundle) {
  const phri::RobotBundle gen3 = phri::RobotBundle::from_folder(kGen3);
  phri::ControllerSettings settings;
  gen3.apply_to(settings);
  const phri::ActuatorTable drives = phri::ActuatorTable::from_yaml_file(gen3.actuators_path);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(7), error = Eigen::VectorXd::Constant(7, 2.0);
  auto first_filter_term = [&](const phri::CustomTorqueSettings& custom) {
    phri::CustomTorqueController loop(drives, custom);
    loop.reset(zero, zero, zero, zero, zero);
    return loop.update(error, zero, zero, zero), Eigen::VectorXd(loop.filter_term());
  };
  const double lambda = settings.custom_torque.transfer_gain;
  EXPECT_EQ(first_filter_term(settings.custom_torque), first_filter_term(phri::CustomTorqueSettings{}));
  EXPECT_NEAR(first_filter_term(settings.custom_torque)[0], lambda * 0.020175 * 2.0, 1e-12);
  phri::CustomTorqueSettings identity = settings.custom_torque;
  identity.filter_numerator = {1.0};
  identity.filter_denominator = {1.0};
  EXPECT_NEAR(first_filter_term(identity)[3], lambda * 2.0, 1e-12);
  identity.filter_denominator.clear();
  EXPECT_THROW(phri::CustomTorqueController(drives, identity), phri::ConfigError);
}

// Kinova's H(z) is a Kinova datum: a generic drive's custom loop has no filter term unless its
// bundle states an H(z) (robots/ur5e states none: a 2 N.m torque error gives 0 from the filter and
// only the integrator's first step; stated, H = 1 gives lambda e).
TEST(RobotBundle, AGenericDriveGetsNoKinovaFilterUnlessItsBundleStatesOne) {
  const std::string ur5e = kRoot + "/robots/ur5e";
  const phri::RobotBundle bundle = phri::RobotBundle::from_folder(ur5e);
  ASSERT_EQ(bundle.drive, phri::DriveKind::kGeneric);
  const phri::ActuatorTable drives = phri::ActuatorTable::from_yaml_file(bundle.actuators_path);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(6), error = Eigen::VectorXd::Constant(6, 2.0);
  auto first_update = [&](const phri::RobotBundle& b) {
    phri::ControllerSettings settings;
    b.apply_to(settings);
    phri::CustomTorqueController loop(drives, settings.custom_torque);
    loop.reset(zero, zero, zero, zero, zero);
    loop.update(error, zero, zero, zero);
    return std::pair{Eigen::VectorXd(loop.filter_term()), settings.custom_torque};
  };
  const auto [unstated, custom] = first_update(bundle);
  EXPECT_EQ(unstated, Eigen::VectorXd::Zero(6));
  EXPECT_NE(first_update(phri::RobotBundle::from_folder(kGen3)).first[0], 0.0);  // the Gen3 keeps Kinova's

  const std::string folder = phri::test::temp_path("phri_test_robot_bundle", "ur5e_with_filter");
  std::filesystem::remove_all(folder);
  std::filesystem::copy(ur5e, folder, std::filesystem::copy_options::recursive);
  std::ofstream(folder + "/robot.yaml", std::ios::app) << "\ncustom_loop_filter: {numerator: [1.0], denominator: [1.0]}\n";
  const Eigen::VectorXd stated = first_update(phri::RobotBundle::from_folder(folder)).first;
  EXPECT_NEAR(stated[5], custom.transfer_gain * 2.0, 1e-12);
  std::filesystem::remove_all(folder);
}

// `collision: fitted` (robots/example_6dof): the controller gets capsules fitted from the URDF, no
// pair on adjacent bodies, none within the damper's influence distance at the home posture.
TEST(RobotBundle, FittedCollisionCapsulesReachTheController) {
  const phri::RobotBundle bundle = phri::RobotBundle::from_folder(kRoot + "/robots/example_6dof");
  EXPECT_TRUE(bundle.collision_path.empty());
  ASSERT_FALSE(bundle.collision_yaml.empty());
  phri::ControllerSettings settings;
  bundle.apply_to(settings);
  const phri::Controller cycle(settings);
  const std::optional<phri::CollisionModel> collision = phri::Controller::collision_model(settings, cycle.model());
  ASSERT_TRUE(collision);
  EXPECT_GT(collision->num_pairs(), 0);
  phri::Data data(cycle.model());
  const Eigen::VectorXd home = Eigen::Map<const Eigen::VectorXd>(bundle.home_q_rad.data(), 6);
  phri::forward_kinematics(cycle.model(), data, home);
  phri::CollisionData distances(cycle.model(), *collision);
  phri::compute_collision_distances(cycle.model(), data, *collision, distances, false);
  for (int k = 0; k < collision->num_pairs(); ++k) {
    const auto& pair = collision->pairs()[static_cast<std::size_t>(k)];
    EXPECT_GT(std::abs(collision->capsules()[static_cast<std::size_t>(pair.first)].body -
                       collision->capsules()[static_cast<std::size_t>(pair.second)].body), 1);
    EXPECT_GE(distances.distance[k], phri::WholeBodyQpSettings{}.collision.influence_distance);
  }
  std::printf("example_6dof: %zu fitted capsules, %d pairs\n", collision->capsules().size(), collision->num_pairs());
}

// ----------------------------------------------------------------------------- a generated arm
TEST(RobotBundle, AGeneratedArmRunsOnItsGeneratedPlantWithNoPlantSection) {
  const phri::test::GeneratedArm arm = phri::test::make_arm({.dof = 6, .prismatic_joint = -1, .gripper = true, .seed = 5});
  const std::string folder = phri::test::temp_path("phri_test_robot_bundle", "generated_6dof");
  std::filesystem::create_directories(folder);
  std::ofstream(folder + "/arm.urdf") << arm.urdf;
  // Its drives: the Gen3's actuator entries, renamed (large ones first).
  std::string drives = read_file(kGen3 + "/actuators.yaml");
  drives = drives.substr(0, drives.find("\n  - name: joint_7"));  // joints 1..6 of the Gen3 file
  std::ofstream(folder + "/actuators.yaml") << drives << "\n";
  std::ostringstream robot;
  robot << "name: generated\nurdf: arm.urdf\nactuators: actuators.yaml\n"
        << "frames: {tip: flange, end_effector: flange}\nlocked_joints: [left_finger_joint, right_finger_joint]\n"
        << "home_q_rad: [";
  for (std::size_t i = 0; i < arm.home_q.size(); ++i) robot << (i ? ", " : "") << arm.home_q[i];
  robot << "]\ncompliance_deadband_Nm: [1, 1, 1, 0.4, 0.4, 0.4]\ndrive: kinova\n"
        << "end_of_arm:\n  ft_sensor: {offset_m: 0.05, flange_side: {mass_kg: 0.2, com_m: [0, 0, 0.02], inertia_kgm2: [1e-4, 1e-4, 1e-4]}}\n"
        << "  tool: {mass_kg: 0.4, com_m: [0, 0, 0.04], inertia_kgm2: [5e-4, 5e-4, 5e-4]}\n";
  std::ofstream(folder + "/robot.yaml") << robot.str();
  const std::string run = "robot: " + folder + "\nrun: {duration_s: 2}\nfsm: {startup: {enabled: false}}\n"
                          "logging: {enabled: false}\ngamepad: {enabled: false}\n";
  const phri::Config config = phri::Config::from_yaml_string(run, "generated_run.yaml", folder);
  EXPECT_TRUE(config.plant.mjcf_path.empty());
  EXPECT_EQ(config.plant.urdf_path, folder + "/arm.urdf");
  phri::SimRobot robot_plant(config.plant);
  phri::Controller cycle(config.controller);
  ASSERT_EQ(cycle.model().nq(), 6);
  EXPECT_NEAR(cycle.model().total_mass(), phri::Model::from_urdf_file(folder + "/arm.urdf", [&] {
                phri::ModelOptions o;
                o.tip_link = "flange";
                o.locked_joints = {"left_finger_joint", "right_finger_joint"};
                return o;
              }()).total_mass() + 0.6, 1e-12);
  phri::RobotCommand command(6);
  const Eigen::VectorXd start = robot_plant.truth().q_rad;
  double drift = 0.0;
  for (int k = 0; k < 1500; ++k) {
    cycle.step(robot_plant.read(), command);
    robot_plant.write(command);
    drift = std::max(drift, (robot_plant.truth().q_rad - start).cwiseAbs().maxCoeff());
  }
  std::printf("generated 6-DoF arm with a locked gripper, from its bundle: joint drift max %.2e rad over 1.5 s\n", drift);
  EXPECT_EQ(cycle.status(), phri::CycleStatus::kOk);
  EXPECT_LT(drift, 1e-3);
}

}  // namespace
