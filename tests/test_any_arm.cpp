// ctest-labels: unit physics integration
// Any arm from its URDF (issue 16), what a robot bundle may now say beyond the Gen3's setup:
//  * no end of arm (`end_of_arm: none`, or no key): the controller carries no payload, the plant
//    has a bare flange and no F/T sensor, and the arm still holds its pose;
//  * gravity and the base placement (`gravity_m_s2`, `base_placement`): the controller's model and
//    the plant agree on them, checked against MuJoCo's own bias forces and site placements;
//  * a tool without an F/T sensor (`end_of_arm: {tool: ...}`): carried by both, no wrench signal;
//  * a base link below the URDF's root (frames.base): placed alike in the model and the plant, and
//    refused when a joint could move it;
//  * an F/T sensor turned about the flange z and set off sideways (end_of_arm.ft_sensor xyz_m,
//    rpy_rad): the same world wrench as a straight mount under the same push, the raw reading
//    turned as MuJoCo's own sensor reads it, the tool's weight removed at rest;
//  * each new key's mistakes are one-line errors naming robot.yaml and the key.
// The arm is robots/example_6dof, copied and its robot.yaml edited.
#include <phri/config/config.hpp>
#include <phri/config/robot_bundle.hpp>
#include <phri/control/controller.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/sim/sim_robot.hpp>
#include <phri/sim/sim_scene.hpp>

#include "config_error.hpp"
#include "hand_push.hpp"
#include "temp_dir.hpp"

#include <mujoco/mujoco.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <vector>

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

// ------------------------------------------------------------------ model against plant
struct Agreement {
  double gravity_Nm = 0.0;  ///< max |g_model(q) - MuJoCo's qfrc_bias| at rest
  double gravity_max_Nm = 0.0;
  double flange_m = 0.0;    ///< |flange (model) - flange site (plant)|
};

// The controller's model (its options: chain, payloads, base placement, gravity) against the plant
// at the plant's present posture, at rest: MuJoCo's bias force is then the gravity torque alone.
Agreement model_against_plant(const phri::ControllerSettings& settings, const phri::SimRobot& robot) {
  const phri::Model model = phri::Model::from_urdf_file(settings.urdf_path, phri::Controller::model_options(settings));
  phri::Data data(model);
  const Eigen::VectorXd q = robot.truth().q_rad;
  const Eigen::VectorXd g = phri::compute_gravity(model, data, q);
  const mjModel* m = robot.mujoco_model();
  const mjData* d = robot.mujoco_data();
  Agreement a;
  for (int i = 0; i < model.nv(); ++i) {
    const int joint = mj_name2id(m, mjOBJ_JOINT, model.joint(i).name.c_str());
    EXPECT_GE(joint, 0);
    a.gravity_Nm = std::max(a.gravity_Nm, std::abs(d->qfrc_bias[m->jnt_dofadr[joint]] - g[i]));
  }
  a.gravity_max_Nm = g.cwiseAbs().maxCoeff();
  phri::forward_kinematics(model, data, q);
  phri::update_frame_placements(model, data);
  const Eigen::Vector3d flange = data.frame_placements[static_cast<std::size_t>(model.frame_id("flange"))].translation();
  a.flange_m = (flange - site_position(robot, "flange")).norm();
  return a;
}

// Read, step, write for `seconds`: the flange's largest drift, and whether a wrench ever came.
struct Held {
  double drift_m = 0.0;
  bool wrench_ever_valid = false;
  phri::CycleStatus status = phri::CycleStatus::kOk;
};
Held hold_pose(const phri::Config& config, double seconds) {
  phri::SimRobot robot(config.plant);
  phri::Controller cycle(config.controller);
  phri::RobotCommand command(robot.dof());
  const Eigen::Vector3d start = site_position(robot, "flange");
  Held out;
  for (long k = 0; k < std::lround(seconds / robot.period_s()); ++k) {
    const phri::RobotState& state = robot.read();
    out.wrench_ever_valid |= state.wrench.valid;
    cycle.step(state, command);
    EXPECT_EQ(robot.write(command), phri::WriteStatus::kOk) << "cycle " << k;
    out.drift_m = std::max(out.drift_m, (site_position(robot, "flange") - start).norm());
  }
  out.status = cycle.status();
  return out;
}

// ------------------------------------------------------------------ a tool, no F/T sensor
// end_of_arm: {tool: {...}} with no ft_sensor: the tool sits on the flange (its COM in the flange
// frame); the controller carries it as its one payload, the plant as a body welded at the flange
// site; no adapter, no F/T sensor, no wrench signal.
const std::string kToolOnly = "{tool: {mass_kg: 0.8, com_m: [0.01, -0.02, 0.06], inertia_kgm2: [2.0e-3, 2.5e-3, 1.5e-3]}}";

TEST(AnyArm, AToolWithoutAnFtSensorIsCarriedByTheControllerAndThePlant) {
  const std::string folder = example_bundle("tool_only", kToolOnly);
  const phri::Config config = run_config(folder);
  EXPECT_TRUE(config.plant.has_end_of_arm);
  EXPECT_FALSE(config.plant.ft_sensor_present());
  ASSERT_EQ(config.controller.payloads.size(), 1u);
  EXPECT_EQ(config.controller.payloads[0].name, "tool");
  EXPECT_EQ(config.controller.payloads[0].inertia.com, Eigen::Vector3d(0.01, -0.02, 0.06));  // on the flange: no offset
  EXPECT_EQ(config.controller.ft_sensor_mount.matrix(), Eigen::Matrix4d::Identity());
  EXPECT_EQ(config.controller.wrench.tool_mass_kg, 0.0);  // no F/T reading to remove it from

  const phri::SimRobot robot(config.plant);
  const phri::Controller cycle(config.controller);
  phri::ModelOptions chain;
  chain.tip_link = "flange";
  chain.locked_joints = {"left_finger_joint", "right_finger_joint"};
  const double bare = phri::Model::from_urdf_file(folder + "/example_6dof.urdf", chain).total_mass();
  const mjModel* m = robot.mujoco_model();
  const double plant_moving = m->body_subtreemass[mj_name2id(m, mjOBJ_BODY, "link_1")];
  std::printf("tool without F/T sensor: moving mass %.4f kg in the controller's model, %.4f kg in the plant (bare arm %.4f kg)\n",
              cycle.model().total_mass(), plant_moving, bare);
  EXPECT_NEAR(cycle.model().total_mass(), bare + 0.8, 1e-12);
  EXPECT_NEAR(plant_moving, bare + 0.8, 1e-12);
  const int tool = mj_name2id(m, mjOBJ_BODY, phri::SimScene::kToolBody);
  ASSERT_GE(tool, 0);
  EXPECT_EQ(std::string(mj_id2name(m, mjOBJ_BODY, m->body_parentid[tool])), "flange");  // the flange site's body
  EXPECT_LT(mj_name2id(m, mjOBJ_BODY, phri::SimScene::kAdapterBody), 0);
  EXPECT_EQ(m->nsensor, 0);

  // The tool's weight: the same torques in the controller's model and the plant, and they matter.
  const Agreement with_tool = model_against_plant(config.controller, robot);
  phri::ControllerSettings unaware = config.controller;
  unaware.set_end_of_arm(std::nullopt);
  const Agreement without_tool = model_against_plant(unaware, robot);
  std::printf("tool without F/T sensor: |g_model - qfrc_bias| max %.2e N.m (%.2f N.m with the tool left out of the model)\n",
              with_tool.gravity_Nm, without_tool.gravity_Nm);
  EXPECT_LT(with_tool.gravity_Nm, 1e-9);
  EXPECT_LT(with_tool.flange_m, 1e-12);
  EXPECT_GT(without_tool.gravity_Nm, 0.3);

  const Held held = hold_pose(config, 3.0);
  std::printf("tool without F/T sensor: flange drift max %.3f mm over 3 s\n", 1e3 * held.drift_m);
  EXPECT_LT(held.drift_m, 1e-3);
  EXPECT_FALSE(held.wrench_ever_valid);
  EXPECT_EQ(held.status, phri::CycleStatus::kOk);
}

TEST(AnyArm, AnFtSourceWithAToolButNoSensorIsRefused) {
  const std::string folder = example_bundle("tool_only_ft", kToolOnly);
  for (const char* source : {"ft", "fused"}) {
    SCOPED_TRACE(source);
    const auto error = expect_config_error(
        [&] { (void)run_config(folder, std::string("controller: {external_torque_source: ") + source + "}\n"); },
        {.element = "controller.external_torque_source", .mentions = {"F/T sensor", "a tool without a sensor"},
         .file = "any_arm_run.yaml"});
    if (error) {
      EXPECT_EQ(std::string(error->what()).find('\n'), std::string::npos) << error->what();
    }
  }
}

// A plant YAML's `tool` without `ft_sensor`: the tool names the flange site it sits on.
std::string example_plant_yaml(const std::string& more) {
  return "plant:\n  robot: {urdf: " + kExample + "/example_6dof.urdf, locked_joints: [left_finger_joint, right_finger_joint], "
         "actuators: " + kExample + "/actuators.yaml}\n  initial: {q_rad: [0.07, 0.59, -0.19, 0.49, -0.12, 0.39]}\n" + more;
}

TEST(AnyArm, APlantYamlCarriesAToolWithoutAnFtSensor) {
  const std::string tool = "  tool: {flange_site: flange, mass_kg: 0.8, com_m: [0.01, -0.02, 0.06], inertia_kgm2: [2.0e-3, 2.5e-3, 1.5e-3]}\n";
  const phri::SimRobotConfig plant = phri::SimRobotConfig::from_yaml_string(example_plant_yaml(tool), "plant.yaml", kExample);
  EXPECT_TRUE(plant.has_end_of_arm);
  EXPECT_FALSE(plant.ft_sensor_present());
  ASSERT_TRUE(plant.end_of_arm().has_value());
  EXPECT_FALSE(plant.end_of_arm()->has_ft_sensor);
  EXPECT_EQ(plant.end_of_arm()->tool.mass_kg, 0.8);
  const phri::SimRobot robot(plant);
  EXPECT_GE(mj_name2id(robot.mujoco_model(), mjOBJ_BODY, phri::SimScene::kToolBody), 0);
  EXPECT_FALSE(robot.state().wrench.valid);

  const std::string sensor =
      "  ft_sensor: {flange_site: flange, sensor_offset_m: 0.065, flange_side_mass_kg: 0.27, flange_side_com_m: [0, 0, 0.03], "
      "flange_side_inertia_kgm2: [2.0e-4, 2.0e-4, 2.2e-4]}\n";
  const struct {
    std::string more, key;
  } cases[] = {
      {"  tool: {mass_kg: 0.8, com_m: [0, 0, 0.06], inertia_kgm2: [2.0e-3, 2.5e-3, 1.5e-3]}\n", "plant.tool.flange_site"},
      {sensor, "plant.tool"},
      {sensor + tool, "plant.tool.flange_site"},  // the sensor's section places the tool
      {"  tool: {flange_site: nowhere, mass_kg: 0.8, com_m: [0, 0, 0.06], inertia_kgm2: [2.0e-3, 2.5e-3, 1.5e-3]}\n", "plant.tool.flange_site"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.more);
    const auto error = expect_config_error(
        [&] { phri::SimRobot r(phri::SimRobotConfig::from_yaml_string(example_plant_yaml(c.more), "plant.yaml", kExample)); },
        {.element = c.key});
    if (error) {
      EXPECT_EQ(std::string(error->what()).find('\n'), std::string::npos) << error->what();
    }
  }
}

// ------------------------------------------------------------ a base below the URDF's root
// The example arm standing on a pedestal: a new root link (5 kg) with base_link below it, offset
// and tilted (joint `pedestal_joint`, fixed unless `joint` says otherwise); frames.base stays
// base_link. base_placement places base_link in the world for the controller's model; the plant
// must move the URDF's root so that base_link lands there too.
std::string pedestal_bundle(const std::string& name, const std::string& joint, const std::string& extra,
                            const std::string& locked = "") {
  const std::string folder = example_bundle(name, std::nullopt, extra);
  std::string urdf = read_file(folder + "/example_6dof.urdf");
  const std::string limit = joint == "fixed" ? "" : "<axis xyz=\"0 0 1\"/><limit lower=\"-1\" upper=\"1\" effort=\"40\" velocity=\"1\"/>";
  const std::string pedestal =
      "<link name=\"pedestal\"><inertial><origin xyz=\"0 0 0.2\"/><mass value=\"5\"/>"
      "<inertia ixx=\"0.1\" ixy=\"0\" ixz=\"0\" iyy=\"0.1\" iyz=\"0\" izz=\"0.05\"/></inertial></link>\n"
      "<joint name=\"pedestal_joint\" type=\"" + joint + "\"><parent link=\"pedestal\"/><child link=\"base_link\"/>"
      "<origin xyz=\"0.12 -0.05 0.4\" rpy=\"0.3 -0.2 0.6\"/>" + limit + "</joint>\n";
  urdf.insert(urdf.find("<link name=\"base_link\">"), pedestal);
  std::ofstream(folder + "/example_6dof.urdf") << urdf;
  if (!locked.empty()) {
    std::string robot = read_file(folder + "/robot.yaml");
    const std::string key = "locked_joints: [left_finger_joint, right_finger_joint]";
    robot.replace(robot.find(key), key.size(), "locked_joints: [left_finger_joint, right_finger_joint, " + locked + "]");
    std::ofstream(folder + "/robot.yaml") << robot;
  }
  return folder;
}

const std::string kTilted = "gravity_m_s2: [1.2, -0.7, -9.6]\nbase_placement: {xyz_m: [0.3, -0.2, 0.5], rpy_rad: [0.4, -0.3, 0.8]}\n";

TEST(AnyArm, ABaseBelowTheUrdfsRootIsPlacedAlikeInTheControllerModelAndThePlant) {
  const std::string folder = pedestal_bundle("pedestal", "fixed", kTilted);
  const phri::Config config = run_config(folder);
  EXPECT_EQ(config.plant.base_link, "base_link");
  const phri::SimRobot robot(config.plant);
  const Agreement a = model_against_plant(config.controller, robot);
  std::printf("base below the URDF's root (tilted, shifted, gravity off the vertical): |g_model - qfrc_bias| max %.2e N.m "
              "(|g| max %.2f N.m), flange %.1e m apart\n", a.gravity_Nm, a.gravity_max_Nm, a.flange_m);
  EXPECT_LT(a.gravity_Nm, 1e-9);
  EXPECT_GT(a.gravity_max_Nm, 1.0);
  EXPECT_LT(a.flange_m, 1e-12);
  // base_link itself where base_placement says.
  const mjModel* m = robot.mujoco_model();
  const mjData* d = robot.mujoco_data();
  const int base = mj_name2id(m, mjOBJ_BODY, "base_link");
  Eigen::Matrix3d rotation;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) rotation(r, c) = d->xmat[9 * base + 3 * r + c];
  }
  EXPECT_LT((Eigen::Vector3d(d->xpos[3 * base], d->xpos[3 * base + 1], d->xpos[3 * base + 2]) -
             config.controller.base_placement.translation()).norm(), 1e-14);
  EXPECT_LT((rotation - config.controller.base_placement.linear()).norm(), 1e-14);

  // The plant placing the URDF's root there instead (what it did before it knew the base link):
  // the arm stands 0.4 m off and tilted, and the torques disagree.
  phri::SimRobotConfig root_placed = config.plant;
  root_placed.base_link.clear();
  const phri::SimRobot wrong(root_placed);
  const Agreement b = model_against_plant(config.controller, wrong);
  std::printf("the same with the plant placing the URDF's root instead: |g_model - qfrc_bias| max %.2f N.m, flange %.3f m apart\n",
              b.gravity_Nm, b.flange_m);
  EXPECT_GT(b.flange_m, 0.1);
  EXPECT_GT(b.gravity_Nm, 0.1);
}

TEST(AnyArm, ABaseAJointCouldMoveIsRefusedUnlessTheJointIsLocked) {
  const std::string folder = pedestal_bundle("pedestal_revolute", "revolute", kTilted);
  const auto error = expect_config_error([&] { (void)phri::RobotBundle::from_folder(folder); },
                                         {.element = "frames.base", .mentions = {"pedestal_joint", "fixed in the world"},
                                          .file = folder + "/robot.yaml"});
  if (error) {
    EXPECT_EQ(std::string(error->what()).find('\n'), std::string::npos) << error->what();
  }

  // Locked (welded at 0 in both): the pedestal is rigid again, and both agree.
  const std::string locked = pedestal_bundle("pedestal_locked", "revolute", kTilted, "pedestal_joint");
  const phri::Config config = run_config(locked);
  const phri::SimRobot robot(config.plant);
  const Agreement a = model_against_plant(config.controller, robot);
  EXPECT_LT(a.gravity_Nm, 1e-9);
  EXPECT_LT(a.flange_m, 1e-12);

  // A plant made in code, the joint neither locked nor fixed: refused where the plant is made.
  phri::SimRobotConfig plant = config.plant;
  plant.locked_joints = {"left_finger_joint", "right_finger_joint"};
  const auto plant_error = expect_config_error([&] { phri::SimRobot r(plant); },
                                               {.element = "base_link", .mentions = {"base_link", "fixed in the world"}});
  if (plant_error) {
    EXPECT_EQ(std::string(plant_error->what()).find('\n'), std::string::npos) << plant_error->what();
  }
}

// ------------------------------------------------------------ an F/T sensor turned and moved
// The sensor mounted a quarter turn about the flange z and 22 mm sideways (xyz_m, rpy_rad) against
// the straight mount (offset_m), both carrying the same physical tool: the turned mount's tool
// COM and principal moments are the straight one's restated in its turned, shifted sensor frame
// (flange frame: COM [0, 0, 0.115] and moments [3.4e-4, 7.3e-4, 8.9e-4] about x, y, z either way).
const double kQuarterTurn = 1.5707963267948966;
const Eigen::Vector3d kTurnedXyz(0.02, -0.01, 0.065);
const std::string kFlangeSide = "flange_side: {mass_kg: 0.26931, com_m: [0.0, 0.0, 0.03], inertia_kgm2: [2.0e-4, 2.0e-4, 2.2e-4]}";
const std::string kStraightMount = "\n  ft_sensor: {offset_m: 0.065, " + kFlangeSide +
                                   "}\n  tool: {mass_kg: 0.3, com_m: [0.0, 0.0, 0.05], inertia_kgm2: [3.4e-4, 7.3e-4, 8.9e-4]}";
const std::string kTurnedMount = "\n  ft_sensor: {xyz_m: [0.02, -0.01, 0.065], rpy_rad: [0, 0, 1.5707963267948966], " + kFlangeSide +
                                 "}\n  tool: {mass_kg: 0.3, com_m: [0.01, 0.02, 0.05], inertia_kgm2: [7.3e-4, 3.4e-4, 8.9e-4]}";
const Eigen::Vector3d kStraightPushPoint(0.0, 0.0, 0.05);  // the tool's COM, in each mount's tool (sensor) frame
const Eigen::Vector3d kTurnedPushPoint(0.01, 0.02, 0.05);

using Wrench = Eigen::Matrix<double, 6, 1>;

// The run with the plant's sensor noise and offsets and its encoders' quantum off: the arm at rest
// holds still (the tool's reading is its weight to round-off), and the controller's model sees the
// plant's posture exactly.
phri::Config quiet_sensor_config(const std::string& folder) {
  phri::Config config = run_config(folder);
  config.plant.ft_sensor.force_std_N = 0.0;
  config.plant.ft_sensor.torque_std_Nm = 0.0;
  phri::SimRobotConfig::Noise& noise = config.plant.noise;
  noise.torque_sensor_std_Nm = noise.velocity_std_rad_s = noise.current_std_A = noise.encoder_counts_per_rev = 0.0;
  std::fill(noise.torque_sensor_offset_Nm.begin(), noise.torque_sensor_offset_Nm.end(), 0.0);
  return config;
}

struct PushRun {
  std::vector<Wrench> estimate_world;  ///< the controller's, each cycle
  std::vector<Wrench> sensor_truth;    ///< MuJoCo's force/torque sensor at the sensor site, each cycle
  std::vector<Wrench> sensor_read;     ///< what the controller was given (RobotState::wrench_sensor)
  std::vector<Wrench> applied_world;   ///< the push (force; moment about the flange site), world axes
  std::vector<Eigen::Matrix3d> sensor_axes_plant, sensor_axes_model;
  std::vector<Eigen::Vector3d> sensor_origin_plant, sensor_origin_model;
  Eigen::Vector3d bias_force = Eigen::Vector3d::Zero();
};

// `force_N` [world] at `point` of the tool (its frame) from 0.6 s on, ramped over 50 ms, for 1 s.
PushRun push_on_the_tool(const std::string& folder, const Eigen::Vector3d& point, const Eigen::Vector3d& force_N, double seconds = 2.0) {
  phri::Config config = quiet_sensor_config(folder);
  config.plant.disturbances.push_back(phri::test::hand_push("tool", point, force_N, 0.6, 1.0));
  phri::SimRobot robot(config.plant);
  phri::Controller cycle(config.controller);
  phri::RobotCommand command(robot.dof());
  const mjModel* m = robot.mujoco_model();
  const mjData* d = robot.mujoco_data();
  const int tool = mj_name2id(m, mjOBJ_BODY, phri::SimScene::kToolBody);
  PushRun run;
  for (long k = 0; k < std::lround(seconds / robot.period_s()); ++k) {
    // The sample read, the plant's truth and the push at that instant, then the controller's step.
    const phri::RobotState& state = robot.read();
    run.sensor_read.push_back(state.wrench_sensor);
    run.sensor_truth.push_back(robot.truth().wrench_sensor);
    run.sensor_axes_plant.push_back(robot.truth().sensor_rotation);
    run.sensor_origin_plant.push_back(robot.truth().sensor_position_m);
    const double scale = config.plant.disturbances[0].scale_at(state.time_s);
    const Eigen::Matrix3d tool_axes = Eigen::Map<const Eigen::Matrix<mjtNum, 3, 3, Eigen::RowMajor>>(d->xmat + 9 * tool);
    const Eigen::Vector3d at = Eigen::Map<const Eigen::Vector3d>(d->xpos + 3 * tool) + tool_axes * point;
    Wrench applied;
    applied << scale * force_N, (at - site_position(robot, "flange")).cross(scale * force_N);
    run.applied_world.push_back(applied);
    cycle.step(state, command);
    run.estimate_world.push_back(cycle.wrench().wrench_world());
    const Eigen::Isometry3d& sensor = cycle.data().frame_placements[static_cast<std::size_t>(cycle.sensor_frame())];
    run.sensor_axes_model.push_back(sensor.linear());
    run.sensor_origin_model.push_back(sensor.translation());
    EXPECT_EQ(robot.write(command), phri::WriteStatus::kOk) << "cycle " << k;
  }
  EXPECT_EQ(cycle.status(), phri::CycleStatus::kOk);
  run.bias_force = cycle.wrench().bias().head<3>();
  return run;
}

TEST(AnyArm, AnFtSensorTurnedAndMovedOnTheFlangeGivesTheSameWorldWrench) {
  const phri::Config turned_config = run_config(example_bundle("ft_turned", kTurnedMount));
  // The mount reaches both: the controller's settings and the plant's.
  const Eigen::Matrix3d R = Eigen::AngleAxisd(kQuarterTurn, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  EXPECT_LT((turned_config.controller.ft_sensor_mount.linear() - R).norm(), 1e-15);
  EXPECT_LT((turned_config.controller.ft_sensor_mount.translation() - kTurnedXyz).norm(), 1e-15);
  EXPECT_LT((turned_config.plant.ft_sensor.sensor_mount.matrix() - turned_config.controller.ft_sensor_mount.matrix()).norm(), 1e-15);

  const Eigen::Vector3d push(6.0, -4.0, 8.0);  // [N], world
  const PushRun straight = push_on_the_tool(example_bundle("ft_straight", kStraightMount), kStraightPushPoint, push);
  const PushRun turned = push_on_the_tool(example_bundle("ft_turned_run", kTurnedMount), kTurnedPushPoint, push);
  ASSERT_EQ(straight.estimate_world.size(), turned.estimate_world.size());
  // The sensor's displacement on the flange, in the straight sensor's (= the flange's) axes.
  const Eigen::Vector3d shift = kTurnedXyz - Eigen::Vector3d(0.0, 0.0, 0.065);
  // Windows: the arm at rest before the push, and held still under it (0.7 s after it has risen).
  auto still = [](std::size_t k) { return k < 600 || (k >= 1300 && k < 1580); };
  struct Max {
    double value = 0.0;
    void operator()(double x) { value = std::max(value, x); }
  } force_diff, moment_diff, moment_diff_still, scale, raw_diff, raw_scale, read_diff, axes_plant, axes_model,
      axes_model_rest, origin_model, origin_model_rest, estimate_vs_push;
  for (std::size_t k = 0; k < straight.estimate_world.size(); ++k) {
    const Wrench dw = turned.estimate_world[k] - straight.estimate_world[k];
    force_diff(dw.head<3>().cwiseAbs().maxCoeff());
    moment_diff(dw.tail<3>().cwiseAbs().maxCoeff());
    if (still(k)) moment_diff_still(dw.tail<3>().cwiseAbs().maxCoeff());
    scale(straight.estimate_world[k].cwiseAbs().maxCoeff());
    // MuJoCo's own sensor on the turned site reads the straight one's wrench turned into its axes,
    // the moment taken about its shifted origin: f' = R^T f, m' = R^T (m - shift x f).
    const Wrench& w = straight.sensor_truth[k];
    Wrench expected;
    expected << R.transpose() * w.head<3>(), R.transpose() * (w.tail<3>() - shift.cross(w.head<3>()));
    raw_diff((turned.sensor_truth[k] - expected).cwiseAbs().maxCoeff());
    raw_scale(w.cwiseAbs().maxCoeff());
    read_diff((turned.sensor_read[k] - turned.sensor_truth[k]).cwiseAbs().maxCoeff());
    // The plant's sensor site is the straight one's turned by R; the controller's model puts its
    // sensor frame where the plant's site is.
    axes_plant((turned.sensor_axes_plant[k] - straight.sensor_axes_plant[k] * R).norm());
    const double axes = (turned.sensor_axes_model[k] - turned.sensor_axes_plant[k]).norm();
    const double origin = (turned.sensor_origin_model[k] - turned.sensor_origin_plant[k]).norm();
    axes_model(axes);
    origin_model(origin);
    if (k < 600) {
      axes_model_rest(axes);
      origin_model_rest(origin);
    }
    if (k >= 1300 && k < 1580) estimate_vs_push((turned.estimate_world[k] - turned.applied_world[k]).cwiseAbs().maxCoeff());
  }
  std::printf("turned F/T mount vs straight, world wrench estimate: force %.1e N, moment %.1e N.m held still (%.1e N.m "
              "while the arm moves; of %.2f); MuJoCo's sensor vs R^T-turned %.1e (of %.2f), read vs truth %.1e; plant "
              "site axes vs straight x R %.1e; model sensor frame vs plant site: axes %.1e origin %.1e m at rest (%.1e, "
              "%.1e while moving); estimate vs the push held %.1e\n",
              force_diff.value, moment_diff_still.value, moment_diff.value, scale.value, raw_diff.value, raw_scale.value,
              read_diff.value, axes_plant.value, axes_model_rest.value, origin_model_rest.value, axes_model.value,
              origin_model.value, estimate_vs_push.value);
  EXPECT_GT(scale.value, 5.0);  // the push came through
  EXPECT_LT(force_diff.value, 1e-9);
  EXPECT_LT(moment_diff_still.value, 1e-8);
  // While the wrench changes, the estimator's per-axis median of three (in sensor axes) can pick
  // another sample on a turned, shifted axis (m' mixes m and f): single cycles, bounded.
  EXPECT_LT(moment_diff.value, 5e-3);
  EXPECT_LT(raw_diff.value, 1e-9);
  EXPECT_EQ(read_diff.value, 0.0);  // noise and bias off: the reading is MuJoCo's
  EXPECT_LT(axes_plant.value, 1e-12);
  EXPECT_LT(axes_model_rest.value, 1e-12);
  EXPECT_LT(origin_model_rest.value, 1e-12);
  // Moving, MuJoCo's site pose is the one before its last physics step's integration.
  EXPECT_LT(axes_model.value, 5e-5);
  EXPECT_LT(origin_model.value, 5e-5);
  EXPECT_LT(estimate_vs_push.value, 2e-3);
  EXPECT_LT(turned.bias_force.norm(), 1e-9);
}

// At rest with no push, the estimator removes the turned tool's weight: the bias it learns is the
// sensor's (none here) and the estimate stays at zero, at postures where gravity has a large
// component across the sensor's z (where a mount turned about z changes the load the sensor reads).
TEST(AnyArm, AnFtSensorTurnedOnTheFlangeHasItsToolsWeightRemoved) {
  const std::string folder = example_bundle("ft_turned_rest", kTurnedMount);
  const phri::Config base = quiet_sensor_config(folder);
  const std::vector<std::vector<double>> postures = {base.plant.initial_q_rad, {0.01, 0.48, 1.34, 1.2, 1.6, 0.44},
                                                     {0.3, 0.2, 1.0, 0.5, -1.2, 1.5}};
  int across = 0;  // postures where a straight reading of the mount would be wrong
  for (const std::vector<double>& q : postures) {
    phri::Config config = base;
    config.plant.initial_q_rad = q;
    phri::SimRobot robot(config.plant);
    phri::Controller cycle(config.controller);
    phri::RobotCommand command(robot.dof());
    double estimate = 0.0;
    for (long k = 0; k < 1000; ++k) {
      cycle.step(robot.read(), command);
      EXPECT_EQ(robot.write(command), phri::WriteStatus::kOk);
      if (k >= 300) estimate = std::max(estimate, cycle.wrench().wrench_world().cwiseAbs().maxCoeff());
    }
    // What the sensor reads at rest is the tool's weight in its axes, about its origin (MuJoCo).
    const Eigen::Matrix3d axes = robot.truth().sensor_rotation;
    const Eigen::Vector3d g_sensor = axes.transpose() * config.plant.gravity_m_s2;
    const Eigen::Vector3d com(0.01, 0.02, 0.05);
    Wrench weight;
    weight << 0.3 * g_sensor, com.cross(0.3 * g_sensor);
    // A mount read as straight (the sensor's axes taken as the flange's) would expect another load.
    const Eigen::Matrix3d R = Eigen::AngleAxisd(kQuarterTurn, Eigen::Vector3d::UnitZ()).toRotationMatrix();
    const Eigen::Vector3d g_flange = R * g_sensor;
    Wrench as_if_straight;
    as_if_straight << 0.3 * g_flange, com.cross(0.3 * g_flange);
    const double reading = (robot.truth().wrench_sensor - weight).cwiseAbs().maxCoeff();
    const double bias = cycle.wrench().bias().cwiseAbs().maxCoeff();
    std::printf("turned F/T mount at rest, q5 %.2f: |g across the sensor z| %.2f m/s^2, MuJoCo reading vs the weight %.2e, "
                "bias %.2e, estimate %.2e (a straight reading of the mount: %.2f off)\n",
                q[4], g_sensor.head<2>().norm(), reading, bias, estimate, (as_if_straight - weight).cwiseAbs().maxCoeff());
    EXPECT_EQ(cycle.status(), phri::CycleStatus::kOk);
    // Noise off, the arm holds still: the reading is the weight, the bias nothing, to round-off.
    EXPECT_LT(reading, 1e-9);
    EXPECT_LT(bias, 1e-9);
    EXPECT_LT(estimate, 1e-9);
    if (g_sensor.head<2>().norm() > 3.0) {
      ++across;
      EXPECT_GT((as_if_straight - weight).cwiseAbs().maxCoeff(), 100 * std::max(bias, 1e-4));
    }
  }
  EXPECT_GE(across, 2);
}

// Both offset_m and xyz_m, a non-finite or degree-sized rpy, |xyz| beyond 0.5 m: one-line errors
// naming robot.yaml (or the plant YAML) and the key.
TEST(AnyArm, FtSensorMountMistakesAreOneLineErrorsNamingTheKey) {
  const std::string tool = "}\n  tool: {mass_kg: 0.3, com_m: [0.0, 0.0, 0.05], inertia_kgm2: [3.4e-4, 7.3e-4, 8.9e-4]}";
  struct MountCase {
    std::string mount, key, mention;
  };
  const MountCase cases[] = {
      {"offset_m: 0.065, xyz_m: [0, 0, 0.065]", "end_of_arm.ft_sensor.xyz_m", "not both"},
      {"xyz_m: [0.4, 0.0, 0.4]", "end_of_arm.ft_sensor.xyz_m", "|xyz| = 0.565685 m: at most 0.5"},
      {"xyz_m: [0.0, 0.0, 0.7]", "end_of_arm.ft_sensor.xyz_m[2]", "0.5"},
      {"xyz_m: [0.0, 0.0]", "end_of_arm.ft_sensor.xyz_m", "expected 3 numbers"},
      {"offset_m: 0.065, rpy_rad: [0, .nan, 0]", "end_of_arm.ft_sensor.rpy_rad[1]", "finite"},
      {"offset_m: 0.065, rpy_rad: [.inf, 0, 0]", "end_of_arm.ft_sensor.rpy_rad[0]", "finite"},
      {"offset_m: 0.065, rpy_rad: [0, 0, 90]", "end_of_arm.ft_sensor.rpy_rad[2]", "must be in"},  // degrees
      {"rpy_rad: [0, 0, 1]", "end_of_arm.ft_sensor.offset_m", "missing"},               // no offset at all
  };
  int n = 0;
  for (const auto& c : cases) {
    SCOPED_TRACE(c.mount);
    const std::string folder = example_bundle("ft_mistake_" + std::to_string(n++), "\n  ft_sensor: {" + c.mount + ", " + kFlangeSide + tool);
    const auto error = expect_config_error([&] { (void)phri::RobotBundle::from_folder(folder); },
                                           {.element = c.key, .mentions = {c.mention}, .file = folder + "/robot.yaml"});
    if (error) {
      EXPECT_EQ(std::string(error->what()).find('\n'), std::string::npos) << error->what();
    }
  }
  // The plant YAML's ft_sensor section: the same keys with the sensor_ prefix of its offset.
  const std::string sensor = "  ft_sensor: {flange_site: flange, flange_side_mass_kg: 0.27, flange_side_com_m: [0, 0, 0.03], "
                             "flange_side_inertia_kgm2: [2.0e-4, 2.0e-4, 2.2e-4], ";
  const std::string plant_tool = "}\n  tool: {mass_kg: 0.8, com_m: [0, 0, 0.06], inertia_kgm2: [2.0e-3, 2.5e-3, 1.5e-3]}\n";
  const MountCase plant_cases[] = {
      {"sensor_offset_m: 0.065, sensor_xyz_m: [0, 0, 0.065]", "plant.ft_sensor.sensor_xyz_m", "not both"},
      {"sensor_xyz_m: [0.3, 0.3, 0.3]", "plant.ft_sensor.sensor_xyz_m", "at most 0.5"},
      {"sensor_offset_m: 0.065, sensor_rpy_rad: [.nan, 0, 0]", "plant.ft_sensor.sensor_rpy_rad[0]", "finite"},
  };
  for (const auto& c : plant_cases) {
    SCOPED_TRACE(c.mount);
    const auto error = expect_config_error(
        [&] { (void)phri::SimRobotConfig::from_yaml_string(example_plant_yaml(sensor + c.mount + plant_tool), "plant.yaml", kExample); },
        {.element = c.key, .mentions = {c.mention}, .file = "plant.yaml"});
    if (error) {
      EXPECT_EQ(std::string(error->what()).find('\n'), std::string::npos) << error->what();
    }
  }
  // A plant YAML's turned mount is the bundle's: the same scene pose of the sensor site.
  const phri::SimRobotConfig plant = phri::SimRobotConfig::from_yaml_string(
      example_plant_yaml(sensor + "sensor_xyz_m: [0.02, -0.01, 0.065], sensor_rpy_rad: [0, 0, 1.5707963267948966]" + plant_tool),
      "plant.yaml", kExample);
  const phri::Config bundled = run_config(example_bundle("ft_turned_plant", kTurnedMount));
  EXPECT_EQ(plant.ft_sensor.sensor_mount.matrix(), bundled.plant.ft_sensor.sensor_mount.matrix());
}

}  // namespace
