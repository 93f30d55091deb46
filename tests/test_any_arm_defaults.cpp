// ctest-labels: unit physics integration
// Nothing of the Gen3 left as a library default (issue 16):
//  * actuators.yaml's `size` (Kinova's large/small actuators) is optional: without it the compliance
//    dead band is 1 % of the drive's torque limit and the emulated Kinova gains follow the drive's
//    maximum torque (the Gen3's classes reproduced by that rule); an arm whose drives state no size
//    loads, holds its pose and runs;
//  * WholeBodyQpSettings and StateEncoderSettings name no end-effector frame (the Gen3's
//    end_effector_link was their default): empty is refused, the Controller sets it;
//  * robot.yaml's `payloads`: bodies on any link, carried alike by the controller's model and the
//    generated plant (gravity torques against MuJoCo's bias force at rest), the arm holding its pose.
// The arm is robots/example_6dof, copied and edited.
#include <phri/config/config.hpp>
#include <phri/config/robot_bundle.hpp>
#include <phri/control/controller.hpp>
#include <phri/dashboard/state_encoder.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/robot/actuator_table.hpp>
#include <phri/sim/sim_robot.hpp>
#include <phri/sim/sim_scene.hpp>

#include "config_error.hpp"
#include "temp_dir.hpp"

#include <mujoco/mujoco.h>

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

namespace {

using phri::test::expect_config_error;

const std::string kExample = std::string(PHRI_SOURCE_DIR) + "/robots/example_6dof";
const std::string kGen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3";

std::string read_file(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

// Every `size: ...` line of an actuators.yaml removed.
std::string without_sizes(const std::string& actuators) {
  return std::regex_replace(actuators, std::regex("\n[ ]*size: [a-z]+[^\n]*"), "");
}

// robots/example_6dof copied to a folder of its own: its actuators.yaml without sizes when
// `sizeless`, `drop` (a robot.yaml line's start) removed, `extra` appended to robot.yaml.
std::string example_bundle(const std::string& name, bool sizeless, const std::string& drop = "", const std::string& extra = "") {
  const std::string folder = phri::test::temp_path("phri_test_any_arm_defaults", name);
  std::filesystem::create_directories(folder);
  std::filesystem::copy_file(kExample + "/example_6dof.urdf", folder + "/example_6dof.urdf",
                             std::filesystem::copy_options::overwrite_existing);
  const std::string actuators = read_file(kExample + "/actuators.yaml");
  std::ofstream(folder + "/actuators.yaml") << (sizeless ? without_sizes(actuators) : actuators);
  std::string robot = read_file(kExample + "/robot.yaml");
  if (!drop.empty()) {
    const std::size_t begin = robot.find("\n" + drop);
    EXPECT_NE(begin, std::string::npos) << drop;
    if (begin != std::string::npos) robot.erase(begin, robot.find('\n', begin + 1) - begin);
  }
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

// Read, step, write for `seconds` as `phri run` does: the flange's largest drift.
struct Held {
  double drift_m = 0.0;
  phri::CycleStatus status = phri::CycleStatus::kOk;
  Eigen::VectorXd deadband;
};
Held hold_pose(const phri::Config& config, double seconds) {
  phri::SimRobot robot(config.plant);
  phri::Controller cycle(config.controller);
  phri::RobotCommand command(robot.dof());
  const Eigen::Vector3d start = site_position(robot, "flange");
  Held out;
  for (long k = 0; k < std::lround(seconds / robot.period_s()); ++k) {
    const phri::RobotState& state = robot.read();
    cycle.step(state, command);
    EXPECT_EQ(robot.write(command), phri::WriteStatus::kOk) << "cycle " << k;
    out.drift_m = std::max(out.drift_m, (site_position(robot, "flange") - start).norm());
  }
  out.status = cycle.status();
  out.deadband = cycle.qp().settings().compliance_deadband;
  return out;
}

// ------------------------------------------------------------------------- actuator size
TEST(AnyArmDefaults, WithoutSizeTheDeadBandAndVendorGainsComeFromTheDrivesOwnData) {
  const phri::ActuatorTable sized = phri::ActuatorTable::from_yaml_file(kGen3 + "/actuators.yaml");
  const phri::ActuatorTable sizeless =
      phri::ActuatorTable::from_yaml_string(without_sizes(read_file(kGen3 + "/actuators.yaml")), "sizeless.yaml");
  ASSERT_EQ(sized.size(), 7);
  ASSERT_EQ(sizeless.size(), 7);
  for (int i = 0; i < 7; ++i) {
    SCOPED_TRACE(i);
    ASSERT_TRUE(sized[i].size.has_value());
    EXPECT_FALSE(sizeless[i].size.has_value());
    // The class by the drive's maximum torque is the stated one on every Gen3 joint.
    EXPECT_EQ(sizeless[i].size_class(), *sized[i].size);
    EXPECT_EQ(sized[i].size_class(), *sized[i].size);
  }
  // The dead band: the sizes' 1.0 / 0.4 with a size (unchanged), 1 % of the torque limit without.
  const std::string sizeless_file = phri::test::temp_path("phri_test_any_arm_defaults", "gen3_sizeless_actuators.yaml");
  std::ofstream(sizeless_file) << without_sizes(read_file(kGen3 + "/actuators.yaml"));
  auto controller_deadband = [&](const std::string& actuators) {
    phri::ControllerSettings settings;  // the Gen3's arm, bare, no bundle: the library's defaults
    settings.urdf_path = kGen3 + "/gen3.urdf";
    settings.actuators_path = actuators;
    settings.end_effector_frame = "end_effector_link";
    settings.tip_link = "bracelet_link";
    return Eigen::VectorXd(phri::Controller(settings).qp().settings().compliance_deadband);
  };
  const Eigen::VectorXd by_size = controller_deadband(kGen3 + "/actuators.yaml");
  const Eigen::VectorXd by_data = controller_deadband(sizeless_file);
  Eigen::VectorXd expected_size(7), expected_data(7);
  expected_size << 1.0, 1.0, 1.0, 1.0, 0.4, 0.4, 0.4;
  expected_data << 0.95, 0.95, 0.95, 0.95, 0.26, 0.45, 0.26;
  EXPECT_EQ(by_size, expected_size);
  EXPECT_LT((by_data - expected_data).cwiseAbs().maxCoeff(), 1e-15) << by_data.transpose();
  std::printf("Gen3 drives: dead band by size [%s] N.m, by 1%% of the torque limit [%.2f %.2f %.2f %.2f %.2f %.2f %.2f] N.m\n",
              "1 1 1 1 0.4 0.4 0.4", by_data[0], by_data[1], by_data[2], by_data[3], by_data[4], by_data[5], by_data[6]);
  // The plant's Kinova gains: the same with or without the sizes.
  phri::SimRobotConfig a, b;
  a.actuators = sized;
  b.actuators = sizeless;
  a.fill_defaults();
  b.fill_defaults();
  EXPECT_EQ(a.vendor.position_kp_Nm_per_rad, b.vendor.position_kp_Nm_per_rad);
  EXPECT_EQ(a.vendor.position_kd_Nms_per_rad, b.vendor.position_kd_Nms_per_rad);
  EXPECT_EQ(a.vendor.position_ki_Nm_per_rad_s, b.vendor.position_ki_Nm_per_rad_s);
  EXPECT_EQ(a.vendor.position_integral_limit_Nm, b.vendor.position_integral_limit_Nm);
  EXPECT_EQ(a.vendor.torque_velocity_damping_Nms_per_rad, b.vendor.torque_velocity_damping_Nms_per_rad);
  EXPECT_EQ(a.elasticity.stiffness_Nm_per_rad, b.elasticity.stiffness_Nm_per_rad);
  EXPECT_EQ(a.vendor.position_kp_Nm_per_rad, (std::vector<double>{12000, 12000, 12000, 12000, 3000, 3000, 3000}));

  // A smaller drive (max torque 0.05 * 100 * 10 = 50 N.m): the small class; its dead band 1 % of 20 N.m.
  const phri::ActuatorTable small = phri::ActuatorTable::from_yaml_string(
      "joints:\n  - {name: j, gear_ratio: 100, torque_constant_Nm_per_A: 0.05, rotor_inertia_kgm2: 1e-6, "
      "reflected_inertia_kgm2: 0.01, current_limit_A: 10, torque_limit_Nm: 20, velocity_limit_rad_s: 2, "
      "friction: {coulomb_Nm: 1, viscous_Nms_per_rad: 1, static_Nm: 1, velocity_threshold_rad_s: 0.1, "
      "acceleration_threshold_rad_s2: 1}}\n");
  EXPECT_EQ(small[0].size_class(), phri::ActuatorSize::kSmall);
  EXPECT_DOUBLE_EQ(small[0].default_compliance_deadband_Nm(1.0, 0.4), 0.2);
  // A size that is neither: one line naming the key.
  const auto error = expect_config_error(
      [&] {
        (void)phri::ActuatorTable::from_yaml_string("joints:\n  - {name: j, size: medium}\n", "actuators.yaml");
      },
      {.element = "joints[0].size", .mentions = {"medium"}, .file = "actuators.yaml"});
  if (error) {
    EXPECT_EQ(std::string(error->what()).find('\n'), std::string::npos) << error->what();
  }
}

TEST(AnyArmDefaults, AnArmWhoseDrivesStateNoSizeLoadsAndHoldsItsPose) {
  // No size and no compliance_deadband_Nm in robot.yaml: the dead band from the drives' limits.
  const std::string folder = example_bundle("sizeless", true, "compliance_deadband_Nm:");
  const phri::RobotBundle bundle = phri::RobotBundle::from_folder(folder);
  EXPECT_EQ(bundle.compliance_deadband_Nm.size(), 0);
  const phri::Config config = run_config(folder);
  const Held held = hold_pose(config, 3.0);
  std::printf("example arm, drives without size: flange drift max %.3f mm over 3 s, dead band [%s]\n", 1e3 * held.drift_m,
              [&] {
                std::ostringstream s;
                s << held.deadband.transpose();
                return s.str();
              }()
                  .c_str());
  EXPECT_LT(held.drift_m, 1e-3);
  EXPECT_EQ(held.status, phri::CycleStatus::kOk);
  Eigen::VectorXd expected(6);
  expected << 0.95, 0.95, 0.95, 0.95, 0.26, 0.45;
  EXPECT_LT((held.deadband - expected).cwiseAbs().maxCoeff(), 1e-15);
  // The robot.yaml's own dead band still wins over the drives' default.
  const phri::Config stated = run_config(example_bundle("sizeless_stated", true));
  Eigen::VectorXd robot_yaml(6);
  robot_yaml << 1.0, 1.0, 1.0, 1.0, 0.4, 0.4;
  EXPECT_EQ(stated.controller.qp.compliance_deadband, robot_yaml);
}

// ------------------------------------------------------------------ end-effector frame
TEST(AnyArmDefaults, NoLibrarySettingNamesAnArmsEndEffectorFrame) {
  EXPECT_EQ(phri::WholeBodyQpSettings{}.end_effector_frame, "");
  EXPECT_EQ(phri::StateEncoderSettings{}.end_effector_frame, "");
  EXPECT_EQ(phri::ControllerSettings{}.end_effector_frame, "");
  // Left empty: refused, naming the key (no silent fallback on the Gen3's frame).
  const phri::Model model = phri::Model::from_urdf_file(kGen3 + "/gen3.urdf");
  const auto error = expect_config_error([&] { phri::WholeBodyQp qp(model, nullptr, phri::WholeBodyQpSettings{}); },
                                         {.element = "end_effector_frame", .mentions = {"empty"}, .file = "WholeBodyQpSettings"});
  if (error) {
    EXPECT_EQ(std::string(error->what()).find('\n'), std::string::npos) << error->what();
  }
  // The Controller sets the robot's: the example arm's flange.
  const phri::Config config = run_config(example_bundle("frame", false));
  const phri::Controller cycle(config.controller);
  EXPECT_EQ(cycle.qp().settings().end_effector_frame, "flange");
}

// ------------------------------------------------------------------------------ payloads
// Bodies on three links beyond the URDF and the end of arm: a valve block on the forearm (link_3),
// a camera on the flange, a sensor on a locked finger; all off their link's origin.
const std::string kPayloads =
    "payloads:\n"
    "  - {name: valve_block, link: link_3, mass_kg: 1.5, com_m: [0.04, -0.03, 0.10], inertia_kgm2: [4.0e-3, 3.0e-3, 2.0e-3]}\n"
    "  - {name: camera, link: flange, mass_kg: 0.4, com_m: [0.06, 0.0, 0.02], inertia_kgm2: [6.0e-4, 5.0e-4, 4.0e-4]}\n"
    "  - {link: left_finger, mass_kg: 0.1, com_m: [0.0, 0.01, 0.02], inertia_kgm2: [2.0e-5, 2.0e-5, 1.0e-5]}\n";

struct Agreement {
  double gravity_Nm = 0.0;      ///< max |g_model(q) - MuJoCo's qfrc_bias| at rest
  double gravity_max_Nm = 0.0;  ///< max |g_model(q)|
};

// The controller's model (its options: chain, payloads, placement) against the plant at the
// plant's posture, at rest: MuJoCo's bias force is then the gravity torque alone.
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
  return a;
}

TEST(AnyArmDefaults, PayloadsOnLinksAreCarriedAlikeByTheControllersModelAndThePlant) {
  const std::string folder = example_bundle("payloads", false, "", kPayloads);
  const phri::RobotBundle bundle = phri::RobotBundle::from_folder(folder);
  ASSERT_EQ(bundle.payloads.size(), 3u);
  EXPECT_EQ(bundle.payloads[2].name, "payload_2");  // a name by default
  const phri::Config config = run_config(folder);
  // The end of arm's two payloads (F/T adapter, tool), then the bundle's three on their links.
  ASSERT_EQ(config.controller.payloads.size(), 5u);
  EXPECT_EQ(config.controller.payloads[2].frame, "link_3");
  EXPECT_EQ(config.controller.payloads[2].inertia.com, Eigen::Vector3d(0.04, -0.03, 0.10));
  ASSERT_EQ(config.plant.payloads.size(), 3u);

  const phri::SimRobot robot(config.plant);
  const phri::Controller cycle(config.controller);
  const phri::Config without = run_config(example_bundle("no_payloads", false));
  const phri::Controller bare(without.controller);
  const mjModel* m = robot.mujoco_model();
  const double plant_moving = m->body_subtreemass[mj_name2id(m, mjOBJ_BODY, "link_1")];
  std::printf("payloads 2.0 kg on link_3, flange, left_finger: moving mass %.4f kg in the controller's model, %.4f kg in the plant "
              "(%.4f kg without them)\n", cycle.model().total_mass(), plant_moving, bare.model().total_mass());
  EXPECT_NEAR(cycle.model().total_mass(), bare.model().total_mass() + 2.0, 1e-12);
  EXPECT_NEAR(plant_moving, bare.model().total_mass() + 2.0, 1e-12);
  for (const char* link : {"link_3", "flange", "left_finger"}) {
    SCOPED_TRACE(link);
    bool found = false;
    for (int b = 0; b < m->nbody; ++b) {
      const std::string name = mj_id2name(m, mjOBJ_BODY, b) ? mj_id2name(m, mjOBJ_BODY, b) : "";
      if (name.rfind(phri::SimScene::kPayloadBodyPrefix, 0) == 0 &&
          std::string(mj_id2name(m, mjOBJ_BODY, m->body_parentid[b])) == link) {
        found = true;
      }
    }
    EXPECT_TRUE(found);  // welded into the link's own body
  }

  // Gravity torques at rest: the controller's model against MuJoCo's bias force, and they matter.
  const Agreement with = model_against_plant(config.controller, robot);
  phri::ControllerSettings unaware = config.controller;
  unaware.payloads.resize(2);  // the end of arm only
  const Agreement without_payloads = model_against_plant(unaware, robot);
  std::printf("payloads: |g_model - qfrc_bias| max %.2e N.m (|g| max %.2f N.m; %.2f N.m with the payloads left out of the model)\n",
              with.gravity_Nm, with.gravity_max_Nm, without_payloads.gravity_Nm);
  EXPECT_LT(with.gravity_Nm, 1e-9);
  EXPECT_GT(without_payloads.gravity_Nm, 1.0);

  const Held held = hold_pose(config, 3.0);
  std::printf("payloads: flange drift max %.3f mm over 3 s\n", 1e3 * held.drift_m);
  EXPECT_LT(held.drift_m, 1e-3);
  EXPECT_EQ(held.status, phri::CycleStatus::kOk);
}

TEST(AnyArmDefaults, PayloadMistakesAreOneLineErrorsNamingTheKey) {
  const std::string ok = "mass_kg: 1.0, com_m: [0, 0, 0.1], inertia_kgm2: [1.0e-3, 1.0e-3, 1.0e-3]";
  const struct {
    std::string payloads, key;
  } cases[] = {
      {"[{link: nowhere, " + ok + "}]", "payloads[0].link"},
      {"[{link: link_3, mass_kg: 0, com_m: [0, 0, 0.1], inertia_kgm2: [1.0e-3, 1.0e-3, 1.0e-3]}]", "payloads[0].mass_kg"},
      {"[{link: link_3, mass_kg: 1000, com_m: [0, 0, 0.1], inertia_kgm2: [1.0e-3, 1.0e-3, 1.0e-3]}]", "payloads[0].mass_kg"},
      {"[{link: link_3, mass_kg: 1, com_m: [0, 0, 100], inertia_kgm2: [1.0e-3, 1.0e-3, 1.0e-3]}]", "payloads[0].com_m[2]"},
      {"[{link: link_3, mass_kg: 1, com_m: [0, 0, 0.1], inertia_kgm2: [1.0e-3, 1.0e-3, 5.0e-3]}]", "payloads[0].inertia_kgm2"},
      {"[{link: link_3, mass_kg: 1, com_m: [0, 0, 0.1], inertia_kgm2: [1.0e-3, 1.0e-3, -1.0e-3]}]", "payloads[0].inertia_kgm2[2]"},
      {"[{link: link_3, " + ok + ", colour: red}]", "payloads[0].colour"},
      {"[{" + ok + "}]", "payloads[0].link"},
      {"[{name: a, link: link_3, " + ok + "}, {name: a, link: link_2, " + ok + "}]", "payloads[1].name"},
      {"{link: link_3, " + ok + "}", "payloads"},
  };
  int n = 0;
  for (const auto& c : cases) {
    SCOPED_TRACE(c.payloads);
    const std::string folder = example_bundle("payload_mistake_" + std::to_string(n++), false, "", "payloads: " + c.payloads + "\n");
    const auto error = expect_config_error([&] { (void)phri::RobotBundle::from_folder(folder); },
                                           {.element = c.key, .file = folder + "/robot.yaml"});
    if (error) {
      EXPECT_EQ(std::string(error->what()).find('\n'), std::string::npos) << error->what();
    }
  }
  // A plant made in code with a link its MJCF lacks: refused where the plant is made.
  phri::Config config = run_config(example_bundle("payload_plant", false, "", kPayloads));
  config.plant.payloads[1].link = "nowhere";
  expect_config_error([&] { phri::SimRobot r(config.plant); }, {.element = "payloads[1].link", .mentions = {"nowhere"}});
}

}  // namespace
