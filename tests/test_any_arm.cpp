// ctest-labels: unit physics integration
// Any arm from its URDF (issue 16), what a robot bundle may now say beyond the Gen3's setup:
//  * no end of arm (`end_of_arm: none`, or no key): the controller carries no payload, the plant
//    has a bare flange and no F/T sensor, and the arm still holds its pose;
//  * gravity and the base placement (`gravity_m_s2`, `base_placement`): the controller's model and
//    the plant agree on them, checked against MuJoCo's own bias forces and site placements;
//  * each new key's mistakes are one-line errors naming robot.yaml and the key.
// The arm is robots/example_6dof, copied and its robot.yaml edited.
#include <phri/app/config.hpp>
#include <phri/app/robot_bundle.hpp>
#include <phri/control/controller.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/sim/sim_robot.hpp>
#include <phri/sim/sim_scene.hpp>

#include "config_error.hpp"
#include "temp_dir.hpp"

#include <mujoco/mujoco.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>

namespace {

using phri::test::expect_config_error;

const std::string kExample = std::string(PHRI_SOURCE_DIR) + "/robots/example_6dof";

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// robots/example_6dof copied to a folder of its own, its robot.yaml's `end_of_arm` section replaced
// by `end_of_arm` (the text after the key, "" to leave the key out; nullopt keeps the Gen3's F/T
// sensor and tool the example carries) and `extra` appended.
std::string example_bundle(const std::string& name, const std::optional<std::string>& end_of_arm, const std::string& extra = "") {
  const std::string folder = phri::test::temp_path("phri_test_any_arm", name);
  std::filesystem::create_directories(folder);
  for (const char* file : {"example_6dof.urdf", "actuators.yaml"}) {
    std::filesystem::copy_file(kExample + "/" + file, folder + "/" + file, std::filesystem::copy_options::overwrite_existing);
  }
  std::string robot = read_file(kExample + "/robot.yaml");
  const std::size_t begin = robot.find("\nend_of_arm:");
  const std::size_t end = robot.find("\nplant:");
  if (end_of_arm) robot.replace(begin, end - begin, end_of_arm->empty() ? std::string("\n") : "\nend_of_arm: " + *end_of_arm + "\n");
  std::ofstream(folder + "/robot.yaml") << robot << extra;
  return folder;
}

phri::Config run_config(const std::string& folder, const std::string& more = "") {
  const std::string run = "robot: " + folder + "\nrun: {duration_s: 3}\nfsm: {startup: {enabled: false}}\n"
                          "logging: {enabled: false}\ngamepad: {enabled: false}\n" + more;
  return phri::Config::from_yaml_string(run, "any_arm_run.yaml", folder);
}

Eigen::Vector3d site_position(const phri::SimRobot& robot, const std::string& site) {
  const int id = mj_name2id(robot.mujoco_model(), mjOBJ_SITE, site.c_str());
  EXPECT_GE(id, 0) << site;
  const mjtNum* p = robot.mujoco_data()->site_xpos + 3 * id;
  return Eigen::Vector3d(p[0], p[1], p[2]);
}

// ----------------------------------------------------------------------------- no end of arm
TEST(AnyArm, WithoutAnEndOfArmTheArmCarriesNothingAndHoldsItsPose) {
  for (const std::string& key : {std::string(), std::string("none")}) {
    SCOPED_TRACE(key.empty() ? "no end_of_arm key" : "end_of_arm: none");
    const std::string folder = example_bundle(key.empty() ? "bare_no_key" : "bare_none", key);
    const phri::Config config = run_config(folder);
    EXPECT_FALSE(config.plant.has_end_of_arm);
    EXPECT_TRUE(config.controller.payloads.empty());
    EXPECT_EQ(config.controller.wrench.tool_mass_kg, 0.0);
    phri::SimRobot robot(config.plant);
    phri::Controller cycle(config.controller);
    // Independent reference: the URDF's own chain, loaded with no options but the chain's.
    phri::ModelOptions chain;
    chain.tip_link = "flange";
    chain.locked_joints = {"left_finger_joint", "right_finger_joint"};
    EXPECT_DOUBLE_EQ(cycle.model().total_mass(), phri::Model::from_urdf_file(folder + "/example_6dof.urdf", chain).total_mass());
    EXPECT_LT(mj_name2id(robot.mujoco_model(), mjOBJ_BODY, phri::SimScene::kToolBody), 0);  // a bare flange
    // As `phri run` steps it: read, step, write; the flange must stay put (no payload mismatch to
    // fight: neither side carries one).
    phri::RobotCommand command(robot.dof());
    const Eigen::Vector3d start = site_position(robot, "flange");
    double drift = 0.0;
    bool wrench_ever_valid = false;
    for (int k = 0; k < 3000; ++k) {
      const phri::RobotState& state = robot.read();
      wrench_ever_valid |= state.wrench.valid;
      cycle.step(state, command);
      ASSERT_EQ(robot.write(command), phri::WriteStatus::kOk) << "cycle " << k;
      drift = std::max(drift, (site_position(robot, "flange") - start).norm());
    }
    std::printf("bare flange (%s): flange drift max %.3f mm over 3 s\n", key.empty() ? "no key" : "none", 1e3 * drift);
    EXPECT_FALSE(wrench_ever_valid);  // no F/T sensor, no F/T sample
    EXPECT_EQ(cycle.status(), phri::CycleStatus::kOk);
    EXPECT_LT(drift, 1e-3);
  }
}

TEST(AnyArm, AnFtSourceWithoutAnFtSensorIsRefused) {
  const std::string folder = example_bundle("bare_ft", "none");
  expect_config_error([&] { (void)run_config(folder, "controller: {external_torque_source: ft}\n"); },
                      {.element = "controller.external_torque_source", .mentions = {"F/T sensor"}, .file = "any_arm_run.yaml"});
}

// ------------------------------------------------------------------ gravity and base placement
// On a tilted, shifted base under a gravity off the vertical: at rest MuJoCo's bias force is the
// gravity torque alone, which the controller's model must give too (same payloads, same placement).
TEST(AnyArm, GravityAndBasePlacementAgreeBetweenTheControllerModelAndThePlant) {
  const std::string extra = "gravity_m_s2: [1.2, -0.7, -9.6]\nbase_placement: {xyz_m: [0.3, -0.2, 0.5], rpy_rad: [0.4, -0.3, 0.8]}\n";
  const std::string folder = example_bundle("tilted", std::nullopt, extra);
  const phri::Config config = run_config(folder);
  ASSERT_TRUE(config.plant.has_end_of_arm);
  phri::SimRobot robot(config.plant);
  const phri::Model model = phri::Model::from_urdf_file(config.controller.urdf_path, phri::Controller::model_options(config.controller));
  phri::Data data(model);
  const Eigen::VectorXd q = robot.truth().q_rad;
  const Eigen::VectorXd& g = phri::compute_gravity(model, data, q);
  const mjModel* m = robot.mujoco_model();
  const mjData* d = robot.mujoco_data();
  EXPECT_NEAR(m->opt.gravity[0], 1.2, 0.0);
  double worst = 0.0;
  for (int i = 0; i < model.nv(); ++i) {
    const int joint = mj_name2id(m, mjOBJ_JOINT, model.joint(i).name.c_str());
    ASSERT_GE(joint, 0);
    worst = std::max(worst, std::abs(d->qfrc_bias[m->jnt_dofadr[joint]] - g[i]));
  }
  std::printf("tilted base, gravity (1.2, -0.7, -9.6): |g_model - qfrc_bias| max %.2e N.m (|g| max %.2f N.m)\n", worst,
              g.cwiseAbs().maxCoeff());
  EXPECT_LT(worst, 1e-9);
  EXPECT_GT(g.cwiseAbs().maxCoeff(), 1.0);  // not a trivial comparison
  // The flange where both put it.
  phri::forward_kinematics(model, data, q);
  phri::update_frame_placements(model, data);
  const Eigen::Vector3d flange_model = data.frame_placements[static_cast<std::size_t>(model.frame_id("flange"))].translation();
  EXPECT_LT((flange_model - site_position(robot, "flange")).norm(), 1e-12);
  // And the base is really moved: the flange is not where the upright arm has it.
  const phri::Config upright = run_config(example_bundle("upright", std::nullopt));
  phri::SimRobot upright_robot(upright.plant);
  EXPECT_GT((site_position(upright_robot, "flange") - site_position(robot, "flange")).norm(), 0.1);
}

// ------------------------------------------------------------------------------ mistakes
TEST(AnyArm, MistakesInTheNewKeysAreOneLineErrorsNamingTheKey) {
  const struct {
    std::string end_of_arm, extra, key;
  } cases[] = {
      {"nothing", "", "end_of_arm"},
      {"none", "gravity_m_s2: [0, 0, -98.1]\n", "gravity_m_s2[2]"},   // g for a tenth of it
      {"none", "gravity_m_s2: [25, 0, -25]\n", "gravity_m_s2"},       // each within range, |g| not
      {"none", "gravity_m_s2: [0, -9.81]\n", "gravity_m_s2"},
      {"none", "base_placement: {xyz: [0, 0, 1]}\n", "base_placement.xyz"},
      {"none", "base_placement: {rpy_rad: [0, 0, 90]}\n", "base_placement.rpy_rad[2]"},  // degrees
  };
  int n = 0;
  for (const auto& c : cases) {
    SCOPED_TRACE(c.key);
    const std::string folder = example_bundle("mistake_" + std::to_string(n++), c.end_of_arm, c.extra);
    const auto error = expect_config_error([&] { (void)phri::RobotBundle::from_folder(folder); },
                                           {.element = c.key, .file = folder + "/robot.yaml"});
    if (error) {
      EXPECT_EQ(std::string(error->what()).find('\n'), std::string::npos) << error->what();
    }
  }
}

}  // namespace
