// ctest-labels: unit physics integration
// robot.yaml `drive: generic` (issue 16): an arm whose drives are not Kinova's. The plant's
// GenericDrive offers a position hold (PD), a plain torque mode and the current mode (phri's custom
// torque loop), with the friction and limits of actuators.yaml; Kinova's torque loops are not
// offered, and asking for one is refused (a ConfigError in a run YAML, a rejected target at run
// time) while the arm keeps running. The arm is robots/example_6dof, copied with `drive: generic`.
#include <phri/app/config.hpp>
#include <phri/app/fsm.hpp>
#include <phri/app/robot_bundle.hpp>
#include <phri/control/controller.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/sim/sim_robot.hpp>

#include "config_error.hpp"
#include "hand_push.hpp"
#include "temp_dir.hpp"

#include <mujoco/mujoco.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>

namespace {

using phri::test::expect_config_error;
using L = phri::LowLevelMode;
using M = phri::ComplianceMode;

const std::string kRoot = PHRI_SOURCE_DIR;
const std::string kExample = kRoot + "/robots/example_6dof";

// robots/example_6dof copied with its `drive: kinova` replaced by `drive: <drive>`.
std::string example_with_drive(const std::string& drive) {
  const std::string folder = phri::test::temp_path("phri_test_generic_drive", "example_" + drive);
  std::filesystem::create_directories(folder);
  for (const char* file : {"example_6dof.urdf", "actuators.yaml"}) {
    std::filesystem::copy_file(kExample + "/" + file, folder + "/" + file, std::filesystem::copy_options::overwrite_existing);
  }
  std::ifstream in(kExample + "/robot.yaml");
  std::stringstream text;
  text << in.rdbuf();
  std::string robot = text.str();
  const std::string key = "drive: kinova";
  const std::size_t at = robot.find(key);
  EXPECT_NE(at, std::string::npos);
  robot.replace(at, key.size(), "drive: " + drive);
  std::ofstream(folder + "/robot.yaml") << robot;
  return folder;
}

const std::string& generic_folder() {
  static const std::string folder = example_with_drive("generic");
  return folder;
}

phri::Config run_config(const std::string& folder, const std::string& more = "") {
  const std::string run = "robot: " + folder + "\nrun: {duration_s: 3}\nfsm: {startup: {enabled: false}}\n"
                          "logging: {enabled: false}\ngamepad: {enabled: false}\n" + more;
  return phri::Config::from_yaml_string(run, "generic_drive_run.yaml", folder);
}

// As `phri run` steps it: read, step, write; records what must never happen on the plant's true state.
class Session {
public:
  Session(M mode, L loop, std::vector<phri::ExternalForce> pushes = {})
      : config_(make_config(mode, loop, std::move(pushes))), robot_(config_.plant), cycle_(config_.controller),
        command_(robot_.dof()), targets_(robot_.dof()) {}

  static phri::Config make_config(M mode, L loop, std::vector<phri::ExternalForce> pushes) {
    phri::Config c = run_config(generic_folder());
    c.controller.initial_compliance = mode;
    c.controller.initial_loop = loop;
    c.plant.disturbances = std::move(pushes);
    return c;
  }

  void run(double seconds, const std::function<void()>& each = {}) {
    const long n = std::lround(seconds / robot_.period_s());
    for (long k = 0; k < n; ++k) {
      const phri::RobotState& state = robot_.read();
      cycle_.step(state, targets_, command_);
      targets_.clear();
      if (robot_.write(command_) != phri::WriteStatus::kOk) ++refused_;
      record();
      if (each) each();
    }
  }
  void record() {
    const auto& t = robot_.truth();
    finite_ &= t.q_rad.allFinite() && t.qd_rad_s.allFinite();
    for (int i = 0; i < robot_.dof(); ++i) {
      speed_ratio_ = std::max(speed_ratio_, std::abs(t.qd_rad_s[i]) / robot_.plant_actuators()[i].velocity_limit_rad_s);
      beyond_limit_ = std::max({beyond_limit_, robot_.position_lower_rad()[i] - t.q_rad[i], t.q_rad[i] - robot_.position_upper_rad()[i]});
    }
  }
  Eigen::Vector3d site(const std::string& name) const {
    const int id = mj_name2id(robot_.mujoco_model(), mjOBJ_SITE, name.c_str());
    const mjtNum* p = robot_.mujoco_data()->site_xpos + 3 * id;
    return Eigen::Vector3d(p[0], p[1], p[2]);
  }
  Eigen::Vector3d flange() const { return site("flange"); }

  phri::Config config_;
  phri::SimRobot robot_;
  phri::Controller cycle_;
  phri::RobotCommand command_;
  phri::ControllerTargets targets_;
  int refused_ = 0;
  bool finite_ = true;
  double speed_ratio_ = 0.0;
  double beyond_limit_ = -1.0;  // [rad] > 0: a joint beyond its limit
};

// ----------------------------------------------------------------------------- configuration
TEST(GenericDrive, TheBundleSelectsTheDriveAndTheLoopsItOffers) {
  const phri::Config generic = run_config(generic_folder());
  EXPECT_EQ(generic.plant.drive, phri::DriveKind::kGeneric);
  for (L loop : {L::kPosition, L::kTorque, L::kCurrent}) EXPECT_TRUE(generic.controller.offered_loops.contains(loop));
  for (L loop : {L::kKinovaTorque, L::kKinovaTorqueHighVelocity}) EXPECT_FALSE(generic.controller.offered_loops.contains(loop));

  const phri::Config kinova = run_config(kRoot + "/robots/kinova_gen3");
  EXPECT_EQ(kinova.plant.drive, phri::DriveKind::kKinova);
  for (L loop : {L::kPosition, L::kKinovaTorque, L::kKinovaTorqueHighVelocity, L::kCurrent}) {
    EXPECT_TRUE(kinova.controller.offered_loops.contains(loop));
  }
  EXPECT_FALSE(kinova.controller.offered_loops.contains(L::kTorque));  // Kortex has no plain torque mode
}

TEST(GenericDrive, ALoopTheDriveDoesNotOfferIsAOneLineConfigError) {
  expect_config_error([&] { (void)run_config(generic_folder(), "low_level: {torque_loop: kinova_torque}\n"); },
                      {.element = "low_level.torque_loop", .mentions = {"kinova_torque", "position, custom, torque"},
                       .file = "generic_drive_run.yaml"});
  expect_config_error(
      [&] { (void)run_config(generic_folder(), "events: [{at: 1.0, event: kinova_torque_high_velocity_loop}]\n"); },
      {.element = "events[0].event", .mentions = {"kinova_torque_high_velocity"}, .file = "generic_drive_run.yaml"});
  expect_config_error([&] { (void)run_config(kRoot + "/robots/kinova_gen3", "low_level: {torque_loop: torque}\n"); },
                      {.element = "low_level.torque_loop", .mentions = {"'torque'"}});
  const std::string unknown = example_with_drive("franka");
  expect_config_error([&] { (void)phri::RobotBundle::from_folder(unknown); }, {.element = "drive", .mentions = {"generic"}});
  // Settings built in code are checked where the controller is made.
  phri::ControllerSettings settings = run_config(generic_folder()).controller;
  settings.initial_loop = L::kKinovaTorque;
  expect_config_error([&] { phri::Controller cycle(settings); }, {.element = "initial_loop", .mentions = {"kinova_torque"}});
}

// ----------------------------------------------------------------------------------- at rest
TEST(GenericDrive, HoldsItsPoseWithinOneMillimetreInEveryOfferedLoop) {
  for (L loop : {L::kPosition, L::kTorque, L::kCurrent}) {
    SCOPED_TRACE(std::string(phri::to_string(loop)));
    Session s(M::kNullSpace, loop);
    const Eigen::Vector3d start = s.flange();
    double drift = 0.0;
    s.run(1.5, [&]() { drift = std::max(drift, (s.flange() - start).norm()); });
    std::printf("generic drive, %-8s at rest: flange drift max %.3f mm\n", std::string(phri::to_string(loop)).c_str(),
                1e3 * drift);
    EXPECT_LT(drift, 1e-3);
    EXPECT_EQ(s.cycle_.status(), phri::CycleStatus::kOk);
    EXPECT_EQ(s.robot_.state().mode, loop);
    EXPECT_EQ(s.refused_, 0);
  }
}

// ------------------------------------------------------------------------------ under pushes
// A hand on the tool (8 N, 0.3 s to 0.8 s), in every compliance mode and every offered loop: the
// plant stays finite, within its joint limits and below 1.05 x its velocity limits.
TEST(GenericDrive, StaysWithinItsLimitsUnderAPushInEveryModeAndLoop) {
  for (M mode : {M::kStiff, M::kNullSpace, M::kFullBody, M::kDual}) {
    for (L loop : {L::kPosition, L::kTorque, L::kCurrent}) {
      const std::string name = std::string(phri::to_string(mode)) + ", " + std::string(phri::to_string(loop));
      SCOPED_TRACE(name);
      Session s(mode, loop, {phri::test::hand_push("tool", Eigen::Vector3d::Zero(), Eigen::Vector3d(8.0, 0.0, 0.0), 0.3, 0.5)});
      s.run(0.25);
      const Eigen::Vector3d start = s.flange();
      double moved = 0.0;
      s.run(1.25, [&]() { moved = std::max(moved, (s.flange() - start).norm()); });
      std::printf("generic drive, %-22s push: flange moved %.1f mm, speed %.2f x limit\n", name.c_str(), 1e3 * moved,
                  s.speed_ratio_);
      EXPECT_TRUE(s.finite_);
      EXPECT_LE(s.beyond_limit_, 0.0);
      EXPECT_LE(s.speed_ratio_, 1.05);
      EXPECT_EQ(s.refused_, 0);
      EXPECT_NE(s.cycle_.status(), phri::CycleStatus::kSafeStop);
      EXPECT_EQ(s.robot_.state().mode, loop);
      // A compliant task yields to the hand where the torque reaches the joints.
      if (loop != L::kPosition && (mode == M::kFullBody || mode == M::kDual)) {
        EXPECT_GT(moved, 0.01);
      }
    }
  }
}

// ------------------------------------------------------------------------------- refusals
TEST(GenericDrive, AKinovaLoopIsRefusedAndTheArmKeepsRunningInItsLoop) {
  Session s(M::kNullSpace, L::kCurrent);
  s.run(0.3);
  // A target from code (a dashboard, a script): rejected, the loop stays.
  s.targets_.low_level_mode = L::kKinovaTorque;
  s.run(0.001);
  EXPECT_EQ(s.cycle_.status(), phri::CycleStatus::kTargetsRejected);
  EXPECT_EQ(s.cycle_.low_level().requested(), L::kCurrent);
  // An FSM event (gamepad, dashboard button): the same, and the FSM keeps its torque loop.
  phri::Fsm fsm(s.config_.fsm, s.cycle_);
  bool rejected = false;
  const long cycles = 300;
  for (long k = 0; k < cycles; ++k) {
    if (k == 100) fsm.post(phri::Event::kKinovaTorqueHighVelocityLoop);
    const phri::RobotState& state = s.robot_.read();
    s.cycle_.step(state, fsm.update(state.time_s, state, s.cycle_), s.command_);
    rejected |= s.cycle_.status() == phri::CycleStatus::kTargetsRejected;
    if (s.robot_.write(s.command_) != phri::WriteStatus::kOk) ++s.refused_;
    s.record();
  }
  EXPECT_TRUE(rejected);
  EXPECT_EQ(fsm.torque_loop(), L::kCurrent);
  EXPECT_EQ(s.cycle_.low_level().loop(), L::kCurrent);
  EXPECT_EQ(s.cycle_.status(), phri::CycleStatus::kOk);
  EXPECT_EQ(s.robot_.state().mode, L::kCurrent);
  EXPECT_EQ(s.refused_, 0);
  EXPECT_LT(s.robot_.truth().qd_rad_s.cwiseAbs().maxCoeff(), 0.01);
  // The plant itself refuses a Kinova loop's command, and keeps the one in force.
  phri::RobotCommand kinova(s.robot_.dof());
  kinova.mode = L::kKinovaTorqueHighVelocity;
  EXPECT_EQ(s.robot_.write(kinova), phri::WriteStatus::kInvalidMode);
  s.robot_.read();
  EXPECT_EQ(s.robot_.state().mode, L::kCurrent);
}

// ---------------------------------------------------------------------------------- safe stop
// As tests/test_safety.cpp's ARefusedWriteReportedToTheControllerEndsInASafeStopAtRest, on the
// generic drive: the stop hands over to the drive's position hold, at rest.
TEST(GenericDrive, TheSafeStopEndsAtRestInTheDrivesPositionHold) {
  for (L loop : {L::kTorque, L::kCurrent}) {
    SCOPED_TRACE(std::string(phri::to_string(loop)));
    Session s(M::kNullSpace, loop);
    s.run(0.5);
    s.cycle_.report_fault(phri::SafetyFault::kWriteRefused, 0.5);
    const Eigen::VectorXd start = s.robot_.truth().q_rad;
    s.run(1.0);
    EXPECT_EQ(s.cycle_.status(), phri::CycleStatus::kSafeStop);
    EXPECT_TRUE(s.cycle_.holding());
    EXPECT_EQ(s.command_.mode, L::kPosition);
    EXPECT_EQ(s.robot_.state().mode, L::kPosition);  // the drive's own hold runs
    EXPECT_LT(s.robot_.truth().qd_rad_s.cwiseAbs().maxCoeff(), 0.01);
    EXPECT_LT((s.robot_.truth().q_rad - start).norm(), 0.02);
    EXPECT_EQ(s.refused_, 0);
  }
}

// ------------------------------------------------------------------------------------ physics
// Plain torque at rest: the plant's joint acceleration is M^-1 (tau - h + friction), M and h from
// phri's own rigid-body model of the same URDF and end of arm (armature: the reflected rotor
// inertia), friction as the plant applied it. First frictionless (the model alone), then with the
// drives' friction, tau past the static level so that the joints break away.
TEST(GenericDrive, PlainTorqueGivesTheRigidBodyAcceleration) {
  for (const double friction_scale : {0.0, 1.0}) {
    SCOPED_TRACE(friction_scale);
    phri::Config config = run_config(generic_folder());
    config.plant.friction_scale = friction_scale;
    config.plant.noise.torque_sensor_std_Nm = config.plant.noise.velocity_std_rad_s = config.plant.noise.current_std_A = 0.0;
    phri::SimRobot robot(config.plant);
    phri::ModelOptions options = phri::Controller::model_options(config.controller);
    for (int i = 0; i < robot.dof(); ++i) options.armature.push_back(robot.plant_actuators()[i].reflected_inertia_kgm2);
    const phri::Model model = phri::Model::from_urdf_file(config.controller.urdf_path, options);
    phri::Data data(model);

    const Eigen::VectorXd q = robot.truth().q_rad, zero = Eigen::VectorXd::Zero(robot.dof());
    Eigen::VectorXd qdd_wanted(robot.dof());
    qdd_wanted << 4.0, -3.0, 5.0, -6.0, 20.0, -25.0;  // past static friction on every joint
    const Eigen::MatrixXd mass = phri::crba(model, data, q);
    const Eigen::VectorXd bias = phri::nonlinear_effects(model, data, q, zero);
    phri::RobotCommand command(robot.dof());
    command.mode = L::kTorque;
    command.tau_Nm = bias + mass * qdd_wanted;
    for (int i = 0; i < robot.dof(); ++i) ASSERT_LT(std::abs(command.tau_Nm[i]), robot.plant_actuators()[i].torque_limit_Nm);
    ASSERT_EQ(robot.write(command), phri::WriteStatus::kOk);
    robot.read();  // one control period (4 physics steps) from rest
    const auto& truth = robot.truth();
    EXPECT_LT((truth.tau_motor_Nm - command.tau_Nm).cwiseAbs().maxCoeff(), 1e-9);  // applied as asked
    // The reference at the last step's state (the arm has moved by ~1e-6 rad).
    const Eigen::MatrixXd mass_now = phri::crba(model, data, truth.q_rad);
    const Eigen::VectorXd bias_now = phri::nonlinear_effects(model, data, truth.q_rad, truth.qd_rad_s);
    const Eigen::VectorXd expected = mass_now.ldlt().solve(truth.tau_motor_Nm - bias_now + truth.tau_friction_Nm);
    const double error = (truth.qdd_rad_s2 - expected).cwiseAbs().maxCoeff();
    std::printf("plain torque, friction x %.0f: |qdd - M^-1 (tau - h + f)| max %.2e rad/s^2 (|qdd| max %.1f, friction max %.2f N.m)\n",
                friction_scale, error, truth.qdd_rad_s2.cwiseAbs().maxCoeff(), truth.tau_friction_Nm.cwiseAbs().maxCoeff());
    EXPECT_LT(error, 1e-2 * qdd_wanted.cwiseAbs().maxCoeff());
    if (friction_scale == 0.0) {
      EXPECT_LT((truth.qdd_rad_s2 - qdd_wanted).cwiseAbs().maxCoeff(), 1e-2 * qdd_wanted.cwiseAbs().maxCoeff());
    } else {
      // Friction acts, and changes the acceleration from the frictionless one.
      EXPECT_GT(truth.tau_friction_Nm.cwiseAbs().maxCoeff(), 1.0);
      EXPECT_GT((truth.qdd_rad_s2 - qdd_wanted).cwiseAbs().maxCoeff(), 0.1);
    }
  }
}

}  // namespace
