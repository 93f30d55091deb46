// ctest-labels: physics
// Power and force limiting (control/power_force_limit.hpp, ISO/TS 15066 Annex A.3): the permissible
// speed against the reference notes' worked example, the reflected mass against the minimum kinetic
// energy of the motions that move the point along u at 1 m/s (measured by finite differences of the
// forward kinematics), and the constraint in closed loop on the plant: a point's true speed stays
// within its permissible speed while the arm is driven to a far target.
#include <phri/config/config.hpp>
#include <phri/control/controller.hpp>
#include <phri/control/power_force_limit.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/app/fsm.hpp>
#include <phri/app/run_session.hpp>
#include <phri/sim/sim_robot.hpp>
#include <phri/trajectory/dynamic_trajectory.hpp>

#include "gen3_settings.hpp"
#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <Eigen/Cholesky>

#include <fstream>
#include <iterator>
#include <random>
#include <sstream>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;

TEST(PowerForceLimit, PermissibleSpeedOfTheWorkedExample) {
  // Hand: k 75 000 N/m, m_H 0.6 kg, robot 5 kg: mu 0.536 kg; transient 280 N -> v_max 1.40 m/s.
  const phri::BodyRegion hand{"hand_fingers", 75000.0, 0.6, 140.0, 2.0};
  EXPECT_NEAR(phri::reduced_mass(5.0, 0.6), 0.5357, 1e-4);
  EXPECT_NEAR(phri::permissible_speed(hand, 5.0), 1.40, 0.005);
  // Energy form: 1/2 mu v_max^2 = F^2 / (2 k).
  const double v = phri::permissible_speed(hand, 5.0);
  EXPECT_NEAR(0.5 * phri::reduced_mass(5.0, 0.6) * v * v, 280.0 * 280.0 / (2.0 * 75000.0), 1e-9);
}

// A planar two-link arm with point masses m1, m2 at the ends of links l1, l2 (joints about z):
//   M = [m1 l1^2 + m2 (l1^2 + l2^2 + 2 l1 l2 c2),  m2 (l2^2 + l1 l2 c2);  m2 (l2^2 + l1 l2 c2),  m2 l2^2]
//   J (tip, x y) = [-l1 s1 - l2 s12, -l2 s12;  l1 c1 + l2 c12, l2 c12]
// and the reflected mass at the tip along u (in the plane) is 1 / (u^T J M^-1 J^T u); with the
// rotor inertia I_r on both joints, M + I_r.
TEST(PowerForceLimit, ReflectedMassOfATwoLinkArmIsItsClosedForm) {
  const double l1 = 0.4, l2 = 0.3, m1 = 2.0, m2 = 1.5, rotor = 0.05;
  auto link = [](const std::string& name, double mass, double x) {
    return "<link name=\"" + name + "\"><inertial><origin xyz=\"" + std::to_string(x) +
           " 0 0\"/><mass value=\"" + std::to_string(mass) +
           "\"/><inertia ixx=\"1e-12\" iyy=\"1e-12\" izz=\"1e-12\" ixy=\"0\" ixz=\"0\" iyz=\"0\"/></inertial></link>";
  };
  const std::string urdf =
      "<robot name=\"two_link\"><link name=\"base\"/>" + link("upper", m1, l1) + link("fore", m2, l2) +
      "<joint name=\"j1\" type=\"continuous\"><parent link=\"base\"/><child link=\"upper\"/><axis xyz=\"0 0 1\"/></joint>"
      "<joint name=\"j2\" type=\"continuous\"><parent link=\"upper\"/><child link=\"fore\"/><origin xyz=\"" +
      std::to_string(l1) + " 0 0\"/><axis xyz=\"0 0 1\"/></joint></robot>";
  const phri::Model model = phri::Model::from_urdf_string(urdf);
  ASSERT_EQ(model.nq(), 2);
  phri::Data data(model);
  for (const auto& [q1, q2] : {std::pair{0.3, 0.9}, std::pair{-1.1, 2.2}, std::pair{0.7, -0.4}}) {
    Eigen::VectorXd q(2);
    q << q1, q2;
    phri::compute_all_terms(model, data, q, Eigen::VectorXd::Zero(2));
    const double c2 = std::cos(q2), s1 = std::sin(q1), c1 = std::cos(q1), s12 = std::sin(q1 + q2), c12 = std::cos(q1 + q2);
    Eigen::Matrix2d m;
    m << m1 * l1 * l1 + m2 * (l1 * l1 + l2 * l2 + 2 * l1 * l2 * c2) + rotor, m2 * (l2 * l2 + l1 * l2 * c2),
        m2 * (l2 * l2 + l1 * l2 * c2), m2 * l2 * l2 + rotor;
    Eigen::Matrix2d j;
    j << -l1 * s1 - l2 * s12, -l2 * s12, l1 * c1 + l2 * c12, l2 * c12;
    Eigen::MatrixXd jv(3, 2);
    const Eigen::Vector3d tip = data.body_placements[1] * Eigen::Vector3d(l2, 0.0, 0.0);
    phri::body_point_linear_jacobian(model, data, 1, tip, jv);
    EXPECT_LT((jv.topRows<2>() - j).norm(), 1e-12);
    Eigen::MatrixXd inertia = data.mass_matrix;
    inertia.diagonal().array() += rotor;
    EXPECT_LT((inertia - m).norm(), 1e-9);
    phri::SmallCholesky llt(inertia.rows());
    ASSERT_TRUE(llt.compute(inertia));
    Eigen::VectorXd scratch(2), solved(2);
    for (const double angle : {0.0, 0.8, 2.0}) {
      const Eigen::Vector2d u2(std::cos(angle), std::sin(angle));
      const double closed = 1.0 / u2.dot(j * m.inverse() * j.transpose() * u2);
      EXPECT_NEAR(phri::reflected_mass(jv, llt, Eigen::Vector3d(u2.x(), u2.y(), 0.0), scratch, solved), closed, 1e-9 * closed);
    }
  }
}

TEST(PowerForceLimit, ReflectedMassIsTheLeastKineticEnergyOfAUnitSpeedAlongU) {
  const phri::Model model = phri::Model::from_urdf_file(kRoot + "/robots/kinova_gen3/gen3.urdf");
  phri::Data data(model);
  Eigen::VectorXd q(7);
  q << 0.2, 0.6, 3.0, -1.8, 0.3, 0.9, 1.5;
  phri::compute_all_terms(model, data, q, Eigen::VectorXd::Zero(7));
  const int body = model.num_bodies() - 1;  // the last link's body
  const Eigen::Vector3d local(0.0, 0.02, 0.05);
  auto point_at = [&](const Eigen::VectorXd& at) {
    phri::Data d(model);
    phri::forward_kinematics(model, d, at);
    return Eigen::Vector3d(d.body_placements[static_cast<std::size_t>(body)] * local);
  };
  Eigen::MatrixXd j(3, 7);
  phri::body_point_linear_jacobian(model, data, body, point_at(q), j);
  Eigen::VectorXd rotor = Eigen::VectorXd::Constant(7, 0.3);
  Eigen::MatrixXd inertia = data.mass_matrix;
  inertia.diagonal() += rotor;
  phri::SmallCholesky llt(inertia.rows());
  ASSERT_TRUE(llt.compute(inertia));
  const Eigen::Vector3d u = Eigen::Vector3d(0.3, -0.5, 0.8).normalized();
  Eigen::VectorXd scratch(7), solved(7);
  const double m_u = phri::reflected_mass(j, llt, u, scratch, solved);
  // Any joint velocity moving the point along u at 1 m/s (u . dp/dt by central differences of the
  // forward kinematics) has at least 1/2 m_u of kinetic energy; the least one has exactly that.
  std::mt19937 random(7);
  std::normal_distribution<double> normal;
  double least = 1e9;
  for (int k = 0; k < 2000; ++k) {
    Eigen::VectorXd qd(7);
    for (int i = 0; i < 7; ++i) qd[i] = normal(random);
    const double h = 1e-6;
    const double along = u.dot(point_at(q + h * qd) - point_at(q - h * qd)) / (2 * h);
    if (std::abs(along) < 0.05) continue;
    qd /= along;
    least = std::min(least, 0.5 * qd.dot(inertia * qd));
  }
  const Eigen::VectorXd best = inertia.llt().solve(j.transpose() * u) * m_u;  // (M + I_r)^-1 J^T u m_u
  const double h = 1e-6;
  EXPECT_NEAR(u.dot(point_at(q + h * best) - point_at(q - h * best)) / (2 * h), 1.0, 1e-6);
  EXPECT_NEAR(0.5 * best.dot(inertia * best), 0.5 * m_u, 1e-9 * m_u);
  EXPECT_GE(least, 0.5 * m_u * (1.0 - 1e-6));
  std::printf("reflected mass along u at the bracelet: %.3f kg (least sampled energy x 2: %.3f kg)\n", m_u, 2 * least);
}

// A region whose permissible speed is about 0.08 m/s for the Gen3's wrist, so that driving the end
// effector at the governor's 0.25 m/s meets it (not a region of the standard: a test load).
phri::BodyRegion slow_region() { return {"test_slow", 75000.0, 0.6, 8.0, 2.0}; }

double worst_true_ratio(const phri::Controller& cycle, const phri::SimRobot& robot, phri::PowerForceLimitConstraint& probe,
                        phri::Data& data, Eigen::MatrixXd& a, Eigen::VectorXd& l, Eigen::VectorXd& u) {
  const Eigen::VectorXd& q = robot.truth().q_rad;
  const Eigen::VectorXd& qd = robot.truth().qd_rad_s;
  phri::compute_all_terms(cycle.model(), data, q, qd);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(q.size());
  const phri::ConstraintContext context{cycle.model(), data, q, qd, zero, zero, zero, zero};
  probe.fill_rows(context, a, l, u);
  return probe.worst_ratio();
}

double drive_far(bool limited, phri::LowLevelMode loop = phri::LowLevelMode::kCurrent) {
  phri::SimRobotConfig config = phri::SimRobotConfig::from_yaml_file(kRoot + "/configs/plant_gen3.yaml");
  config.initial_q_rad = {0, 0.58, 3.14, -1.84, 0, 0.85, 1.57};
  config.mismatch.enabled = true;
  phri::SimRobot robot(config);
  phri::ControllerSettings settings = phri::test::gen3_controller_settings(phri::ComplianceMode::kStiff, loop);
  phri::PowerForceLimitSettings pfl;
  pfl.regions.region = slow_region();
  if (limited) settings.qp.power_force_limit = pfl;
  phri::Controller cycle(settings);
  // The same figures on the plant's true state, through a probe of its own.
  const phri::CollisionModel capsules = *phri::Controller::collision_model(settings, cycle.model());
  Eigen::VectorXd rotor(7);
  for (int i = 0; i < 7; ++i) rotor[i] = cycle.actuators()[i].reflected_inertia_kgm2;
  phri::PowerForceLimitConstraint probe(cycle.model(), capsules, rotor, pfl);
  phri::Data data(cycle.model());
  Eigen::MatrixXd a(probe.num_rows(), 7);
  Eigen::VectorXd l(probe.num_rows()), u(probe.num_rows());
  phri::RobotCommand command(7);
  phri::ControllerTargets targets(7);
  double worst = 0.0;
  for (int k = 0; k < 3000; ++k) {
    if (k == 300) {
      Eigen::Isometry3d far = cycle.qp().end_effector().target_pose();
      far.translation() += Eigen::Vector3d(0.0, -0.3, -0.1);
      targets.has_pose = true;
      targets.pose.pose = far;
    }
    cycle.step(robot.read(), targets, command);
    targets.clear();
    robot.write(command);
    if (k > 300) worst = std::max(worst, worst_true_ratio(cycle, robot, probe, data, a, l, u));
  }
  EXPECT_EQ(cycle.status(), phri::CycleStatus::kOk);
  return worst;
}

// The Gen3's QP with the constraint for `region`, started holding the demo's home posture (the
// QP alone: its acceleration is realised by the test, qd += qdd dt, q += qd dt).
struct QpRig {
  explicit QpRig(const phri::BodyRegion& region)
      : model(phri::Model::from_urdf_file(kRoot + "/robots/kinova_gen3/gen3.urdf")),
        capsules(phri::CollisionModel::from_yaml_file(kRoot + "/robots/kinova_gen3/collision.yaml", model)),
        data(model), qp(model, &capsules, settings(region)), q(7), qd(Eigen::VectorXd::Zero(7)),
        tau_ext(Eigen::VectorXd::Zero(7)) {
    q << 0, 0.58, 3.14, -1.84, 0, 0.85, 1.57;
    phri::compute_all_terms(model, data, q, qd);
    qp.end_effector().reset_gains(phri::Vector6d::Constant(400), phri::Vector6d::Constant(40), 1e4, phri::Vector6d::Zero());
    qp.posture().reset_gains(20, 9, 1, 0);
    qp.posture().set_target(q);
    qp.end_effector().hold_current_pose(data);
  }
  static phri::WholeBodyQpSettings settings(const phri::BodyRegion& region) {
    phri::WholeBodyQpSettings s;
    s.end_effector_frame = "end_effector_link";
    phri::PowerForceLimitSettings limit;
    limit.regions.region = region;
    s.power_force_limit = limit;
    return s;
  }
  // One cycle: the QP on the state, its acceleration realised; false when the QP failed.
  bool step() {
    phri::compute_all_terms(model, data, q, qd);
    if (qp.update(model, data, q, qd, tau_ext, 0.001) != phri::WholeBodyQpStatus::kOk) return false;
    qd += 0.001 * qp.desired_acceleration();
    q += 0.001 * qd;
    return true;
  }
  phri::Model model;
  phri::CollisionModel capsules;
  phri::Data data;
  phri::WholeBodyQp qp;
  Eigen::VectorXd q, qd, tau_ext;
};

// The QP alone, its acceleration realised exactly (qd += qdd dt, q += qd dt): every point within its
// permissible speed (the constraint's first-order bound, paper eq. sec-order-vel-damp's form).
TEST(PowerForceLimit, TheQpHoldsEachPointWithinItsPermissibleSpeedWhenItsAccelerationIsRealised) {
  QpRig rig(slow_region());
  const Eigen::Vector3d start = rig.qp.end_effector().target_pose().translation();
  Eigen::Isometry3d far = rig.qp.end_effector().target_pose();
  far.translation() += Eigen::Vector3d(0.0, -0.3, -0.1);
  rig.qp.end_effector().set_target(far);
  double worst = 0.0;
  for (int k = 0; k < 2500; ++k) {
    ASSERT_TRUE(rig.step());
    worst = std::max(worst, rig.qp.power_force_limit()->worst_ratio());
  }
  const double moved = (rig.qp.end_effector().pose().translation() - start).norm();
  std::printf("power and force limit, QP alone: worst v / v_max %.4f, the end effector moved %.0f mm in 2.5 s\n", worst,
              1e3 * moved);
  EXPECT_LT(worst, 1.01);
  EXPECT_GT(moved, 0.1) << "slowed, not stopped";
}

// The paper's dynamic scenario (trajectory/dynamic_trajectory.hpp, peak ~0.32 m/s) under a region
// whose v_max (~0.2 m/s at the tool, ~0.03-0.2 m/s along the arm) binds, the QP's acceleration
// realised exactly: while the constraint acts, every point stays within 1 % of its v_max.
TEST(PowerForceLimit, TheQpHoldsEveryPointWithinItsPermissibleSpeedThroughTheDynamicScenario) {
  QpRig rig({"face", 75000.0, 4.4, 65.0, 1.0});  // configs/iso_ts_15066_regions.yaml's face
  phri::DynamicTrajectory scenario;
  scenario.start(rig.qp.end_effector().target_pose());
  phri::PoseReference reference;
  double worst = 0.0, fastest_reference = 0.0;
  int binding = 0;
  for (int k = 0; k < 8000; ++k) {
    scenario.evaluate(0.001 * k, reference);
    fastest_reference = std::max(fastest_reference, reference.velocity.head<3>().norm());
    rig.qp.end_effector().set_target(reference.pose, reference.velocity, reference.acceleration);
    ASSERT_TRUE(rig.step());
    const double ratio = rig.qp.power_force_limit()->worst_ratio();
    worst = std::max(worst, ratio);
    if (ratio > 0.99) ++binding;
  }
  std::printf("power and force limit, dynamic scenario (reference up to %.2f m/s), QP alone: worst v / v_max %.4f, "
              "%d of 8000 cycles at > 0.99\n", fastest_reference, worst, binding);
  EXPECT_GT(binding, 500) << "the region must bind during the scenario";
  EXPECT_LE(worst, 1.01);
}

// The demo with a constraint whose region never binds (v_max of kilometres per second): every column
// of the log but the cycle's wall time is the demo's own, bit for bit.
std::vector<std::string> demo_log(bool with_idle_constraint) {
  phri::Config config = phri::Config::from_yaml_file(kRoot + "/configs/demo.yaml");
  if (with_idle_constraint) {
    phri::PowerForceLimitSettings idle;
    idle.regions.region = {"idle", 100.0, 0.6, 1e4, 2.0};  // v_max = 2e4 / sqrt(mu 100) > 2 km/s
    config.controller.qp.power_force_limit = idle;
  }
  phri::SimRobot robot(config.plant);
  phri::Controller cycle(config.controller);
  phri::Fsm fsm(config.fsm, cycle);
  EXPECT_EQ(cycle.qp().power_force_limit() != nullptr, with_idle_constraint);  // in the QP, not merely configured
  config.logging.path = phri::test::temp_path("phri_test_pfl_demo", with_idle_constraint ? "idle.csv" : "demo.csv");
  config.logging.pfl_links = phri::PowerForceLimitMonitor::monitored_links(*cycle.collision());
  phri::Logger logger(config.logging);
  phri::RunOptions options;
  options.duration_s = 7.0;  // the start-up, the elbow pushes at 4 and 6 s
  options.status_line = false;
  options.pushes = &robot;
  options.ground_truth = &robot;
  options.body_regions = &*config.body_regions;
  std::ostringstream out;
  phri::run_session(robot, cycle, fsm, nullptr, &logger, options, out);
  logger.close();
  std::ifstream in(config.logging.path);
  std::vector<std::string> rows;
  std::string line, header;
  std::getline(in, header);
  // The cycle's wall time is the one column a second run cannot repeat.
  std::size_t skip = 0, column = 0;
  for (std::size_t at = 0; at != std::string::npos; at = header.find(',', at + 1), ++column) {
    if (header.compare(at == 0 ? 0 : at + 1, 12, "cycle_time_s") == 0) skip = column;
  }
  EXPECT_GT(skip, 0u) << header;
  while (std::getline(in, line)) {
    std::stringstream cells(line);
    std::string cell, kept;
    for (std::size_t c = 0; std::getline(cells, cell, ','); ++c) kept += c == skip ? "," : cell + ",";
    rows.push_back(kept);
  }
  return rows;
}

TEST(PowerForceLimit, AConstraintThatNeverBindsChangesNothingInTheDemosLog) {
  const std::vector<std::string> demo = demo_log(false);
  const std::vector<std::string> idle = demo_log(true);
  ASSERT_EQ(demo.size(), idle.size());
  EXPECT_GT(demo.size(), 6900u);
  std::size_t differing = 0;
  for (std::size_t i = 0; i < demo.size(); ++i) differing += demo[i] != idle[i] ? 1 : 0;
  EXPECT_EQ(differing, 0u) << "first: " << [&] {
    for (std::size_t i = 0; i < demo.size(); ++i) {
      if (demo[i] != idle[i]) return demo[i] + "\n" + idle[i];
    }
    return std::string();
  }();
}

// On the plant, through the loops: the bound holds as well as each loop realises the QP's acceleration.
TEST(PowerForceLimit, OnThePlantTheConstraintCutsTheSpeedToNearItsBound) {
  const double free = drive_far(false);
  const double custom = drive_far(true);
  const double position = drive_far(true, phri::LowLevelMode::kPosition);
  const double kinova = drive_far(true, phri::LowLevelMode::kKinovaTorque);
  std::printf("power and force limit on the plant, a 0.32 m move of the end effector (governor 0.25 m/s), worst true "
              "v / v_max: %.3f without the constraint; with it %.3f custom loop, %.3f position loop, %.3f Kinova torque\n",
              free, custom, position, kinova);
  EXPECT_GT(free, 1.5) << "the test region must bind";
  for (double limited : {custom, position, kinova}) EXPECT_LT(limited, 0.5 * free);
}

}  // namespace

namespace {

std::string force_table_with(const std::string& power_force_limit) {
  std::ifstream in(kRoot + "/configs/force_table.yaml");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::string key = "controller:\n";
  text.insert(text.find(key) + key.size(), "  qp: {power_force_limit: " + power_force_limit + "}\n");
  return text;
}

TEST(PowerForceLimit, TheRunYamlNamesARegionOfTheShippedFile) {
  const phri::Config config = phri::Config::from_yaml_string(
      force_table_with("{regions_file: iso_ts_15066_regions.yaml, region: hand_fingers}"), "test.yaml", kRoot + "/configs");
  ASSERT_TRUE(config.controller.qp.power_force_limit);
  const phri::BodyRegion& hand = config.controller.qp.power_force_limit->regions.region;
  EXPECT_EQ(hand.name, "hand_fingers");
  EXPECT_EQ(hand.stiffness_N_per_m, 75000.0);
  EXPECT_EQ(hand.mass_kg, 0.6);
  EXPECT_EQ(hand.transient_force_N(), 280.0);
  try {
    phri::Config::from_yaml_string(force_table_with("{regions_file: iso_ts_15066_regions.yaml, region: elbow}"), "test.yaml",
                                   kRoot + "/configs");
    ADD_FAILURE() << "an unknown region is an error";
  } catch (const phri::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("controller.qp.power_force_limit.region: no region 'elbow'"), std::string::npos)
        << e.what();
  }
}

// The monitor's figures per link: the faster capsule end point's speed against central
// differences of the forward kinematics, its reflected mass against reflected_mass() along that
// motion, v_max and the energy against their closed forms; each link's region as the map names it.
TEST(PowerForceLimitMonitor, EachLinkHasItsFasterEndPointsFiguresAndItsOwnRegion) {
  const std::string gen3 = kRoot + "/robots/kinova_gen3/";
  const phri::Model model = phri::Model::from_urdf_file(gen3 + "gen3.urdf");
  const phri::CollisionModel capsules = phri::CollisionModel::from_yaml_file(gen3 + "collision.yaml", model);
  phri::BodyRegionMap regions;
  regions.region = {"lower_arm_wrist", 40000.0, 2.0, 160.0, 2.0};
  regions.links.emplace_back("end_effector_link", phri::BodyRegion{"hand_fingers", 75000.0, 0.6, 140.0, 2.0});
  const Eigen::VectorXd rotor = Eigen::VectorXd::Constant(7, 0.2);
  phri::PowerForceLimitMonitor monitor(model, capsules, rotor, regions);
  const std::vector<std::string> links = phri::PowerForceLimitMonitor::monitored_links(capsules);
  ASSERT_EQ(monitor.num_links(), static_cast<int>(links.size()));
  ASSERT_EQ(links.size(), capsules.capsules().size() - 1) << "every capsule but the base's";
  Eigen::VectorXd q(7), qd(7);
  q << 0.2, 0.6, 3.0, -1.8, 0.3, 0.9, 1.5;
  qd << 0.4, -0.3, 0.5, 0.6, -0.8, 0.7, 1.1;
  phri::Data data(model);
  phri::compute_all_terms(model, data, q, qd);
  monitor.update(model, data);
  Eigen::MatrixXd inertia = data.mass_matrix;
  inertia.diagonal() += rotor;
  phri::SmallCholesky llt(inertia.rows());
  ASSERT_TRUE(llt.compute(inertia));
  auto world = [&](const Eigen::VectorXd& at, int body, const Eigen::Vector3d& local) {
    phri::Data d(model);
    phri::forward_kinematics(model, d, at);
    return Eigen::Vector3d(d.body_placements[static_cast<std::size_t>(body)] * local);
  };
  const double h = 1e-6;
  double worst = 0.0;
  int index = 0;
  for (const phri::Capsule& c : capsules.capsules()) {
    if (c.body < 0) continue;
    SCOPED_TRACE(c.link);
    const phri::ContactPointState& s = monitor.link(index);
    EXPECT_EQ(monitor.link_name(index), c.link);
    EXPECT_EQ(monitor.region(index).name, c.link == "end_effector_link" ? "hand_fingers" : "lower_arm_wrist");
    Eigen::Vector3d v[2];
    int k = 0;
    for (const Eigen::Vector3d& local : {c.p0, c.p1}) {
      v[k++] = (world(q + h * qd, c.body, local) - world(q - h * qd, c.body, local)) / (2 * h);
    }
    const int fast = v[1].norm() > v[0].norm() ? 1 : 0;
    EXPECT_NEAR(s.speed_m_s, v[fast].norm(), 1e-6);
    Eigen::MatrixXd j(3, 7);
    phri::body_point_linear_jacobian(model, data, c.body, world(q, c.body, fast ? c.p1 : c.p0), j);
    Eigen::VectorXd scratch(7), solved(7);
    const double m_u = phri::reflected_mass(j, llt, v[fast].normalized(), scratch, solved);
    EXPECT_NEAR(s.reflected_mass_kg, m_u, 1e-9 * m_u);
    const phri::BodyRegion& r = monitor.region(index);
    const double mu = 1.0 / (1.0 / r.mass_kg + 1.0 / m_u);
    EXPECT_NEAR(s.permissible_speed_m_s, r.transient_force_N() / std::sqrt(mu * r.stiffness_N_per_m), 1e-9);
    EXPECT_NEAR(s.energy_J, 0.5 * mu * s.speed_m_s * s.speed_m_s, 1e-9 * s.energy_J);
    worst = std::max(worst, s.ratio());
    ++index;
  }
  EXPECT_GT(worst, 0.0);
  EXPECT_EQ(monitor.link(monitor.worst_link()).ratio(), worst);
}

TEST(PowerForceLimitMonitor, TheRunYamlMapsLinksToRegionsAndTheConstraintsMapIsTheDefault) {
  const std::string file = "regions_file: iso_ts_15066_regions.yaml";
  phri::Config config = phri::Config::from_yaml_string(
      force_table_with("{" + file + ", region: chest, links: {forearm_link: upper_arm_elbow}}"), "test.yaml", kRoot + "/configs");
  ASSERT_TRUE(config.body_regions) << "the constraint's regions when there is no body_regions block";
  EXPECT_EQ(config.body_regions->region.name, "chest");
  EXPECT_EQ(config.body_regions->for_link("forearm_link").name, "upper_arm_elbow");
  EXPECT_EQ(config.body_regions->for_link("bracelet_link").name, "chest");
  std::string text = force_table_with("{" + file + ", region: chest}");
  text += "body_regions: {" + file + ", region: face, links: {end_effector_link: hand_fingers}}\n";
  config = phri::Config::from_yaml_string(text, "test.yaml", kRoot + "/configs");
  ASSERT_TRUE(config.body_regions);
  EXPECT_EQ(config.body_regions->region.name, "face");
  EXPECT_EQ(config.body_regions->for_link("end_effector_link").name, "hand_fingers");
  EXPECT_EQ(config.controller.qp.power_force_limit->regions.region.name, "chest");
  try {
    phri::Config::from_yaml_string(force_table_with("{" + file + ", region: chest, links: {forearm_link: elbow}}"), "test.yaml",
                                   kRoot + "/configs");
    ADD_FAILURE() << "an unknown region is an error";
  } catch (const phri::ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("links.forearm_link: no region 'elbow'"), std::string::npos) << e.what();
  }
}

}  // namespace
