// ctest-labels: unit physics integration
// Published data is enough (issue 40): on a generic drive actuators.yaml needs only each joint's
// name, torque limit and speed limit; every other key has a documented default
// (actuator_parameters.hpp, docs/robots.md) and a one-line notice when used. No Kinova key is read
// or checked on a generic drive; a `plant.vendor` section there is an error. A Kinova drive still
// needs its motor data stated. The arm is robots/example_6dof, copied and edited.
#include <phri/config/config.hpp>
#include <phri/config/config_checks.hpp>
#include <phri/config/robot_bundle.hpp>
#include <phri/control/controller.hpp>
#include <phri/robot/actuator_table.hpp>
#include <phri/sim/sim_robot.hpp>

#include "config_error.hpp"
#include "temp_dir.hpp"

#include <mujoco/mujoco.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace {

using phri::test::expect_config_error;

const std::string kExample = std::string(PHRI_SOURCE_DIR) + "/robots/example_6dof";

// Torque and speed limits per joint, as a maker's data sheet gives them (the example's joints;
// the wrists' torque limits low, as a small arm's: the Kinova integral limit of 30 N.m would not fit).
const char* const kMinimalActuators = R"(joints:
  - {name: joint_1, torque_limit_Nm: 95, velocity_limit_rad_s: 2.0944}
  - {name: joint_2, torque_limit_Nm: 95, velocity_limit_rad_s: 2.0944}
  - {name: joint_3, torque_limit_Nm: 95, velocity_limit_rad_s: 2.0944}
  - {name: joint_4, torque_limit_Nm: 95, velocity_limit_rad_s: 2.0944}
  - {name: joint_5, torque_limit_Nm: 20, velocity_limit_rad_s: 3.0543}
  - {name: joint_6, torque_limit_Nm: 20, velocity_limit_rad_s: 3.0543}
)";

// robots/example_6dof copied with `drive: <drive>` and the minimal actuators.yaml.
std::string bundle(const std::string& name, const std::string& drive) {
  const std::string folder = phri::test::temp_path("phri_test_published_data", name);
  std::filesystem::create_directories(folder);
  std::filesystem::copy_file(kExample + "/example_6dof.urdf", folder + "/example_6dof.urdf",
                             std::filesystem::copy_options::overwrite_existing);
  std::ofstream(folder + "/actuators.yaml") << kMinimalActuators;
  std::ifstream in(kExample + "/robot.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string robot = text.str();
  const std::size_t at = robot.find("drive: kinova");
  EXPECT_NE(at, std::string::npos);
  robot.replace(at, std::string("drive: kinova").size(), "drive: " + drive);
  std::ofstream(folder + "/robot.yaml") << robot;
  return folder;
}

phri::Config run_config(const std::string& folder, const std::string& more = "") {
  const std::string run = "robot: " + folder + "\nrun: {duration_s: 3}\nfsm: {startup: {enabled: false}}\n"
                          "logging: {enabled: false}\ngamepad: {enabled: false}\n" + more;
  return phri::Config::from_yaml_string(run, "published_data_run.yaml", folder);
}

TEST(PublishedData, TorqueAndSpeedLimitsAloneLoadWithTheDocumentedDefaults) {
  const phri::ActuatorTable table = phri::ActuatorTable::from_yaml_string(kMinimalActuators, "actuators.yaml");
  ASSERT_EQ(table.size(), 6);
  for (int i = 0; i < table.size(); ++i) {
    const phri::ActuatorParameters& a = table[i];
    EXPECT_EQ(a.gear_ratio, 100.0);
    EXPECT_EQ(a.torque_constant_Nm_per_A, 0.1);
    EXPECT_NEAR(a.reflected_inertia_kgm2, 0.01, 1e-15);  // at the joint
    EXPECT_NEAR(a.rotor_inertia_kgm2, 0.01 / (100.0 * 100.0), 1e-18);
    // 1.1 x the torque limit over K_T G_r = 10 N.m/A, computed by hand.
    EXPECT_NEAR(a.current_limit_A, 1.1 * a.torque_limit_Nm / 10.0, 1e-12);
    EXPECT_EQ(a.friction.coulomb_Nm, 0.0);
    EXPECT_EQ(a.friction.static_Nm, 0.0);
    EXPECT_EQ(a.friction.viscous_Nms_per_rad, 0.0);
  }
  const std::vector<std::string> notices = table.notices("actuators.yaml");
  for (const std::string& n : notices) std::printf("notice: %s\n", n.c_str());
  ASSERT_EQ(notices.size(), 6u);  // one line per key defaulted
  for (const char* key : {"gear_ratio", "torque_constant_Nm_per_A", "rotor_inertia_kgm2", "reflected_inertia_kgm2",
                          "current_limit_A", "friction"}) {
    EXPECT_TRUE(std::any_of(notices.begin(), notices.end(), [&](const std::string& n) {
      return n.find(std::string(key) + " not given (joint_1, joint_2, joint_3, joint_4, joint_5, joint_6)") != std::string::npos;
    })) << key;
  }
  // A stated key is neither defaulted nor noticed; reflected inertia follows a stated rotor inertia.
  const phri::ActuatorTable stated = phri::ActuatorTable::from_yaml_string(
      "joints:\n  - {name: j, torque_limit_Nm: 10, velocity_limit_rad_s: 1, gear_ratio: 50, rotor_inertia_kgm2: 2.0e-5}\n");
  EXPECT_NEAR(stated[0].reflected_inertia_kgm2, 2.0e-5 * 50 * 50, 1e-15);
  const std::vector<std::string> fewer = stated.notices("a.yaml");
  EXPECT_EQ(fewer.size(), 4u);  // torque constant, reflected inertia, current limit, friction
}

TEST(PublishedData, AGenericArmFromPublishedDataLoadsNoticesItsDefaultsAndHoldsItsPose) {
  const std::string folder = bundle("generic_minimal", "generic");
  // A run YAML with a plant section (no Kinova key): the Kinova integral limit (30 N.m on the
  // wrists, above their 22 N.m drive maximum) is not checked on a generic drive.
  const phri::Config config = run_config(folder, "plant: {seed: 3}\n");
  EXPECT_EQ(config.plant.drive, phri::DriveKind::kGeneric);
  const std::vector<std::string> warnings = phri::config_warnings(config);
  EXPECT_EQ(std::count_if(warnings.begin(), warnings.end(),
                          [](const std::string& w) { return w.find("not given") != std::string::npos; }),
            6);
  phri::SimRobot robot(config.plant);
  phri::Controller cycle(config.controller);
  phri::RobotCommand command(robot.dof());
  const int site = mj_name2id(robot.mujoco_model(), mjOBJ_SITE, "flange");
  ASSERT_GE(site, 0);
  const Eigen::Vector3d start(robot.mujoco_data()->site_xpos + 3 * site);
  double drift = 0.0;
  for (int k = 0; k < 1500; ++k) {
    cycle.step(robot.read(), command);
    ASSERT_EQ(robot.write(command), phri::WriteStatus::kOk) << "cycle " << k;
    drift = std::max(drift, (Eigen::Vector3d(robot.mujoco_data()->site_xpos + 3 * site) - start).norm());
  }
  std::printf("generic arm from published data: flange drift max %.3f mm over 1.5 s\n", 1e3 * drift);
  EXPECT_EQ(cycle.status(), phri::CycleStatus::kOk);
  EXPECT_LT(drift, 1e-3);
}

TEST(PublishedData, AVendorSectionOnAGenericDriveIsAnError) {
  const std::string folder = bundle("generic_vendor", "generic");
  expect_config_error([&] { run_config(folder, "plant: {vendor: {position: {integral_limit_Nm: [1, 1, 1, 1, 1, 1]}}}\n"); },
                      {.element = "plant.vendor", .mentions = {"generic"}, .file = "published_data_run.yaml"});
}

TEST(PublishedData, AKinovaDriveStillNeedsItsMotorData) {
  const std::string folder = bundle("kinova_minimal", "kinova");
  expect_config_error([&] { phri::RobotBundle::from_folder(folder); },
                      {.element = "joints[0].gear_ratio", .mentions = {"kinova"}});
}

}  // namespace
