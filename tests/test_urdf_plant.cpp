// ctest-labels: unit physics
// The plant generated from the URDF (sim/urdf_plant.hpp) against independent references:
// the Gen3's hand-written plant (gen3_plant.xml), MuJoCo's own URDF import (mj_loadXML on the
// .urdf) and the random chains' hand-built MJCF (tests/support/random_chain.hpp) - M(q) and the
// bias forces qfrc_bias(q, qd) as MuJoCo computes them - and phri's model for locked joints;
// the URDF cases the plant must refuse or warn about; a SimRobot running on a generated plant.
#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/model.hpp>
#include <phri/sim/mujoco_handles.hpp>
#include <phri/sim/sim_robot.hpp>
#include <phri/sim/urdf_plant.hpp>

#include "config_error.hpp"
#include "random_chain.hpp"
#include "temp_dir.hpp"

#include <mujoco/mujoco.h>

#include <gtest/gtest.h>

#include <atomic>
#include <fstream>
#include <random>
#include <sstream>
#include <thread>

namespace {

using phri::test::expect_config_error;

const std::string kGen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";

std::string read_file(const std::string& path) {
  std::ifstream f(path);
  std::stringstream s;
  s << f.rdbuf();
  return s.str();
}

phri::MjModelPtr load_text(const std::string& xml) {
  std::string error;
  phri::MjModelPtr m = phri::load_mjcf_text(xml, error);
  EXPECT_TRUE(m) << error;
  return m;
}

phri::MjModelPtr generated(const std::string& urdf, phri::UrdfPlantOptions options = {}) {
  return load_text(phri::UrdfPlant::generate_from_string(urdf, options, "test.urdf").mjcf);
}

// MuJoCo's own URDF import (fixed links kept as bodies, as the generator does).
phri::MjModelPtr imported_by_mujoco(std::string urdf) {
  const std::size_t robot = urdf.find('>', urdf.find("<robot")) + 1;
  urdf.insert(robot, "<mujoco><compiler fusestatic=\"false\" discardvisual=\"true\"/></mujoco>");
  const std::string path = phri::test::temp_path("phri_test_urdf_plant", "imported.urdf");
  std::ofstream(path) << urdf;
  char error[1024] = "";
  phri::MjModelPtr m(mj_loadXML(path.c_str(), nullptr, error, sizeof(error)));
  EXPECT_TRUE(m) << error;
  return m;
}

struct Dynamics {
  Eigen::MatrixXd mass_matrix;
  Eigen::VectorXd bias;  // C(q, qd) qd + g(q)
};

// M and qfrc_bias of `m` at (q, qd), joints matched by name to `joint_names`.
Dynamics dynamics_of(const mjModel* m, const std::vector<std::string>& joint_names, const Eigen::VectorXd& q,
                     const Eigen::VectorXd& qd) {
  const int n = static_cast<int>(joint_names.size());
  EXPECT_EQ(m->nv, n);
  std::vector<int> dof(static_cast<std::size_t>(n));
  phri::MjDataPtr d(mj_makeData(m));
  for (int i = 0; i < n; ++i) {
    const int j = mj_name2id(m, mjOBJ_JOINT, joint_names[static_cast<std::size_t>(i)].c_str());
    EXPECT_GE(j, 0) << joint_names[static_cast<std::size_t>(i)];
    d->qpos[m->jnt_qposadr[j]] = q[i];
    d->qvel[m->jnt_dofadr[j]] = qd[i];
    dof[static_cast<std::size_t>(i)] = m->jnt_dofadr[j];
  }
  mj_forward(m, d.get());
  Eigen::MatrixXd full(m->nv, m->nv);
  mj_fullM(m, full.data(), d->qM);  // symmetric: row/column major alike
  Dynamics out{Eigen::MatrixXd(n, n), Eigen::VectorXd(n)};
  for (int i = 0; i < n; ++i) {
    out.bias[i] = d->qfrc_bias[dof[static_cast<std::size_t>(i)]];
    for (int k = 0; k < n; ++k) out.mass_matrix(i, k) = full(dof[static_cast<std::size_t>(i)], dof[static_cast<std::size_t>(k)]);
  }
  return out;
}

std::vector<std::string> joint_names(int n, const std::string& prefix = "joint_") {
  std::vector<std::string> names;
  for (int i = 1; i <= n; ++i) names.push_back(prefix + std::to_string(i));
  return names;
}

void expect_same_dynamics(const mjModel* a, const mjModel* b, const std::vector<std::string>& names, double tolerance,
                          std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const int n = static_cast<int>(names.size());
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd q(n), qd(n);
    for (int i = 0; i < n; ++i) {
      q[i] = 1.5 * unit(rng);
      qd[i] = 2.0 * unit(rng);
    }
    const Dynamics x = dynamics_of(a, names, q, qd), y = dynamics_of(b, names, q, qd);
    const double scale = 1.0 + x.mass_matrix.cwiseAbs().maxCoeff() + x.bias.cwiseAbs().maxCoeff();
    EXPECT_LT((x.mass_matrix - y.mass_matrix).cwiseAbs().maxCoeff(), tolerance * scale);
    EXPECT_LT((x.bias - y.bias).cwiseAbs().maxCoeff(), tolerance * scale);
  }
}

// ------------------------------------------------------------------------------------ Gen3
TEST(UrdfPlant, Gen3GeneratedMatchesTheHandWrittenPlant) {
  phri::UrdfPlantOptions options;
  options.urdf_path = kGen3 + "gen3.urdf";
  const phri::GeneratedPlant plant = phri::UrdfPlant::generate(options);
  EXPECT_TRUE(plant.warnings.empty());
  const phri::MjModelPtr generated_gen3 = load_text(plant.mjcf);
  char error[1024] = "";
  const phri::MjModelPtr hand_written(mj_loadXML((kGen3 + "gen3_plant.xml").c_str(), nullptr, error, sizeof(error)));
  ASSERT_TRUE(hand_written) << error;
  std::mt19937 rng(16);
  // The hand-written file rounds some rpy (3.1416 for pi) exactly as the URDF does: same numbers.
  expect_same_dynamics(generated_gen3.get(), hand_written.get(), joint_names(7), 1e-12, rng);
  // Every link has a site at its frame (the flange site the scene needs among them).
  EXPECT_GE(mj_name2id(generated_gen3.get(), mjOBJ_SITE, "end_effector_link"), 0);
  EXPECT_GE(mj_name2id(generated_gen3.get(), mjOBJ_SITE, "bracelet_link"), 0);
}

// ------------------------------------------------------------------------------ random chains
TEST(UrdfPlant, RandomChainsMatchMujocosOwnUrdfImportAndTheHandBuiltMjcf) {
  std::mt19937 rng(1606);
  for (int dof : {1, 3, 6, 7, 9}) {
    const phri::test::RandomChain chain = phri::test::make_random_chain(dof, rng);
    SCOPED_TRACE(chain.urdf);
    const phri::MjModelPtr plant = generated(chain.urdf);
    const phri::MjModelPtr reference = load_text(chain.mjcf);
    expect_same_dynamics(plant.get(), reference.get(), joint_names(dof), 1e-11, rng);
    // MuJoCo diagonalises a full inertia to ~1e-10 only (tools/mjcf_principal_inertia.py).
    const phri::MjModelPtr imported = imported_by_mujoco(chain.urdf);
    expect_same_dynamics(plant.get(), imported.get(), joint_names(dof), 1e-8, rng);
    // Slide joints for the prismatic ones, limits from the URDF.
    for (int i = 0; i < plant->njnt; ++i) {
      const int k = mj_name2id(imported.get(), mjOBJ_JOINT, mj_id2name(plant.get(), mjOBJ_JOINT, i));
      EXPECT_EQ(plant->jnt_type[i], imported->jnt_type[k]);
      EXPECT_EQ(plant->jnt_limited[i], imported->jnt_limited[k]);
      EXPECT_EQ(plant->jnt_range[2 * i + 1], imported->jnt_range[2 * k + 1]);
    }
  }
}

// A 7-DoF arm with a two-finger gripper branch whose joints are locked (welded at 0 in the plant,
// fixed at 0 in the controller's model): MuJoCo's M and bias equal phri's CRBA and RNEA.
TEST(UrdfPlant, LockedGripperFingersAreWeldedAsInTheControllersModel) {
  std::mt19937 rng(7);
  std::string urdf = phri::test::make_random_chain(7, rng).urdf;
  const char* inertial =
      "<inertial><origin xyz=\"0.01 0 0.02\" rpy=\"0.3 0.2 0.1\"/><mass value=\"0.08\"/><inertia ixx=\"2e-5\" ixy=\"0\" "
      "ixz=\"0\" iyy=\"3e-5\" iyz=\"0\" izz=\"4e-5\"/></inertial>";
  for (const char* side : {"left", "right"}) {
    urdf.insert(urdf.rfind("</robot>"),
                std::string("<link name=\"") + side + "_finger\">" + inertial + "</link><joint name=\"" + side +
                    "_finger_joint\" type=\"prismatic\"><parent link=\"link_7\"/><child link=\"" + side +
                    "_finger\"/><origin xyz=\"0 0.02 0.1\"/><axis xyz=\"0 1 0\"/><limit lower=\"0\" upper=\"0.04\" "
                    "effort=\"20\" velocity=\"0.1\"/></joint>");
  }
  phri::UrdfPlantOptions options;
  options.locked_joints = {"left_finger_joint", "right_finger_joint"};
  const phri::MjModelPtr plant = generated(urdf, options);
  ASSERT_EQ(plant->nv, 7);
  phri::ModelOptions model_options;
  model_options.tip_link = "tool";
  model_options.locked_joints = options.locked_joints;
  const phri::Model model = phri::Model::from_urdf_string(urdf, model_options);
  phri::Data data(model);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  for (int trial = 0; trial < 5; ++trial) {
    Eigen::VectorXd q(7), qd(7);
    for (int i = 0; i < 7; ++i) {
      q[i] = unit(rng);
      qd[i] = unit(rng);
    }
    const Dynamics mujoco = dynamics_of(plant.get(), joint_names(7), q, qd);
    phri::crba(model, data, q);
    EXPECT_LT((mujoco.mass_matrix - data.mass_matrix).cwiseAbs().maxCoeff(), 1e-11);
    EXPECT_LT((mujoco.bias - phri::nonlinear_effects(model, data, q, qd)).cwiseAbs().maxCoeff(), 1e-10);
  }
}

TEST(UrdfPlant, ARootNamedWorldIsTheWorldBody) {
  std::mt19937 rng(3);
  std::string urdf = phri::test::make_random_chain(3, rng).urdf;
  urdf.insert(urdf.find("<link name=\"base\"/>"), "<link name=\"world\"/><joint name=\"world_to_base\" type=\"fixed\">"
                                                  "<parent link=\"world\"/><child link=\"base\"/><origin xyz=\"0 0 0.5\"/></joint>");
  const phri::MjModelPtr plant = generated(urdf);
  EXPECT_EQ(plant->nv, 3);
  EXPECT_EQ(plant->body_parentid[mj_name2id(plant.get(), mjOBJ_BODY, "base")], 0);
}

// ------------------------------------------------------------------------------ refused / warned
std::string gen3_with(const std::string& from, const std::string& to) {
  std::string urdf = read_file(kGen3 + "gen3.urdf");
  urdf.replace(urdf.find(from), from.size(), to);
  return urdf;
}

TEST(UrdfPlant, TriangleInequalityNeedsBalanceInertiaAndThenWarns) {
  const std::string urdf =
      gen3_with("ixx=\"0.011088\" ixy=\"5E-06\" ixz=\"0\" iyy=\"0.001072\" iyz=\"-0.000691\" izz=\"0.011255\"",
                "ixx=\"0.00368\" ixy=\"0\" ixz=\"0\" iyy=\"0.00796\" iyz=\"0\" izz=\"0.01274\"");
  expect_config_error([&] { (void)phri::UrdfPlant::generate_from_string(urdf, {}, "odd.urdf"); },
                      {.element = "link 'half_arm_1_link' <inertial>", .mentions = {"triangle", "balance_inertia"}});
  phri::UrdfPlantOptions options;
  options.balance_inertia = true;
  const phri::GeneratedPlant plant = phri::UrdfPlant::generate_from_string(urdf, options, "odd.urdf");
  ASSERT_EQ(plant.warnings.size(), 1u);
  EXPECT_NE(plant.warnings[0].find("half_arm_1_link"), std::string::npos);
  const phri::MjModelPtr m = load_text(plant.mjcf);
  ASSERT_TRUE(m);
  // MuJoCo balanced it: the moments it simulates satisfy the inequality.
  const int body = mj_name2id(m.get(), mjOBJ_BODY, "half_arm_1_link");
  const mjtNum* i = m->body_inertia + 3 * body;
  EXPECT_GE(i[0] + i[1], i[2] * (1.0 - 1e-9));
  EXPECT_GE(i[0] + i[2], i[1] * (1.0 - 1e-9));
  EXPECT_GE(i[1] + i[2], i[0] * (1.0 - 1e-9));
}

TEST(UrdfPlant, LoopsTyposAndUnsupportedJointsAreOneLineErrors) {
  auto generating = [](const std::string& urdf) {
    return [urdf] { (void)phri::UrdfPlant::generate_from_string(urdf, {}, "bad.urdf"); };
  };
  std::string loop = read_file(kGen3 + "gen3.urdf");
  loop.insert(loop.rfind("</robot>"), "<joint name=\"closing\" type=\"continuous\"><parent link=\"bracelet_link\"/>"
                                      "<child link=\"shoulder_link\"/><axis xyz=\"0 0 1\"/></joint>");
  expect_config_error(generating(loop), {.mentions = {"kinematic loop", "shoulder_link"}, .file = "bad.urdf"});
  expect_config_error(generating(gen3_with("<mass value=\"0.9302\"", "<mass value=\"0.9302kg\"")),
                      {.mentions = {"forearm_link", "0.9302kg"}, .file = "bad.urdf"});
  expect_config_error(generating(gen3_with("<joint name=\"joint_3\" type=\"continuous\"", "<joint name=\"joint_3\" type=\"floating\"")),
                      {.element = "joint 'joint_3'", .mentions = {"floating"}});
  phri::UrdfPlantOptions missing;
  missing.urdf_path = "/nonexistent.urdf";
  expect_config_error([&] { (void)phri::UrdfPlant::generate(missing); },
                      {.mentions = {"/nonexistent.urdf"}});
}

// The parser's message handler is process-wide: the controller's model and the plant generator
// loading at once on two threads must each get their own parse error (and never crash).
TEST(UrdfPlant, ConcurrentLoadsKeepTheirOwnParserMessages) {
  const std::string model_typo = gen3_with("<mass value=\"1.3773\"", "<mass value=\"1.3773kg\"");
  const std::string plant_typo = gen3_with("<mass value=\"0.364\"", "<mass value=\"0.364g\"");
  std::atomic<int> model_right{0}, plant_right{0};
  std::thread model_thread([&] {
    for (int k = 0; k < 200; ++k) {
      try {
        (void)phri::Model::from_urdf_string(model_typo);
      } catch (const phri::ConfigError& e) {
        model_right += std::string(e.what()).find("1.3773kg") != std::string::npos;
      }
    }
  });
  for (int k = 0; k < 200; ++k) {
    try {
      (void)phri::UrdfPlant::generate_from_string(plant_typo, {}, "plant.urdf");
    } catch (const phri::ConfigError& e) {
      plant_right += std::string(e.what()).find("0.364g") != std::string::npos;
    }
  }
  model_thread.join();
  EXPECT_EQ(model_right.load(), 200);
  EXPECT_EQ(plant_right.load(), 200);
}

}  // namespace
