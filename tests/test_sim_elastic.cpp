// ctest-labels: physics
// Joint elasticity in the simulated plant (SimRobotConfig::Elasticity, ElasticTransmission): at rest
// under the vendor position servo, the spring carries the gravity torque MuJoCo computes for the
// link (qfrc_bias), the torque sensor reads it, and the link sags by tau / K behind a motor-side
// servo while a link-side servo holds the link itself at its set-point.
#include <phri/control/controller.hpp>
#include <phri/experiments/elastic_modes.hpp>
#include <phri/sim/sim_robot.hpp>

#include "gen3_settings.hpp"

#include <mujoco/mujoco.h>

#include <Eigen/Eigenvalues>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <cstdio>
#include <string>
#include <tuple>
#include <vector>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;
const std::vector<double> kPose = {0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57};

struct Held {
  Eigen::VectorXd q_link, q_motor, tau_sensor, gravity, command;
};

// The elastic Gen3 plant at kPose without noise, quantisation or sensor offsets (an offset the drive
// would read as deflection).
phri::SimRobotConfig quiet_elastic_plant(phri::SimRobotConfig::Elasticity::Encoder encoder) {
  phri::SimRobotConfig c = phri::SimRobotConfig::from_yaml_file(kRoot + "/configs/plant_gen3.yaml");
  c.initial_q_rad = kPose;
  c.noise.torque_sensor_std_Nm = 0.0;
  c.noise.velocity_std_rad_s = 0.0;
  c.noise.current_std_A = 0.0;
  c.noise.encoder_counts_per_rev = 0.0;
  c.noise.torque_sensor_offset_Nm.assign(7, 0.0);
  c.elasticity.enabled = true;
  c.elasticity.position_loop_encoder = encoder;
  return c;
}

Held hold_at_rest(phri::SimRobotConfig::Elasticity::Encoder encoder) {
  phri::SimRobot robot(quiet_elastic_plant(encoder));
  phri::RobotCommand hold(7);
  hold.mode = phri::LowLevelMode::kPosition;
  hold.q_rad = Eigen::Map<const Eigen::VectorXd>(kPose.data(), 7);
  for (int k = 0; k < 4000; ++k) {
    robot.write(hold);
    robot.read();
  }
  Held h;
  h.q_link = robot.truth().q_rad;
  h.q_motor = robot.truth().q_motor_rad;
  h.tau_sensor = robot.truth().tau_transmitted_Nm;
  h.gravity = Eigen::VectorXd(7);
  const mjModel* m = robot.mujoco_model();
  const mjData* d = robot.mujoco_data();
  for (int i = 0; i < 7; ++i) h.gravity[i] = d->qfrc_bias[i];  // the arm's 7 hinges come first in the scene
  (void)m;
  h.command = hold.q_rad;
  EXPECT_FALSE(robot.state().fault);
  return h;
}

TEST(SimElastic, MotorSideServoLeavesTheLinkSaggingByTorqueOverStiffness) {
  const Held h = hold_at_rest(phri::SimRobotConfig::Elasticity::Encoder::kMotor);
  const phri::SimRobotConfig c = phri::SimRobotConfig::from_yaml_file(kRoot + "/configs/plant_gen3.yaml");
  for (int i = 0; i < 7; ++i) {
    const double k = c.elasticity.stiffness_Nm_per_rad[static_cast<std::size_t>(i)];
    // At rest the spring holds the link against gravity, and the sensor measures the spring.
    EXPECT_NEAR(h.tau_sensor[i], h.gravity[i], 0.02 + 1e-3 * std::abs(h.gravity[i])) << "joint " << i + 1;
    // The servo's integrator brings the rotor to the set-point; the link sits tau / K behind it.
    EXPECT_NEAR(h.q_motor[i], h.command[i], 2e-5) << "joint " << i + 1;
    EXPECT_NEAR(h.q_link[i] - h.q_motor[i], -h.gravity[i] / k, 2e-5 + 1e-3 * std::abs(h.gravity[i] / k)) << "joint " << i + 1;
  }
  std::printf("joint 2: gravity %.2f N.m, link - motor %.3f mrad (-tau/K %.3f mrad)\n", h.gravity[1],
              1e3 * (h.q_link[1] - h.q_motor[1]), -1e3 * h.gravity[1] / 13000.0);
}

TEST(SimElastic, LinkSideServoHoldsTheLinkItself) {
  const Held h = hold_at_rest(phri::SimRobotConfig::Elasticity::Encoder::kLink);
  for (int i = 0; i < 7; ++i) {
    EXPECT_NEAR(h.q_link[i], h.command[i], 2e-5) << "joint " << i + 1;
    EXPECT_NEAR(h.tau_sensor[i], h.gravity[i], 0.02 + 1e-3 * std::abs(h.gravity[i])) << "joint " << i + 1;
  }
}

TEST(SimElastic, MotorServoLessTheMeasuredDeflectionHoldsTheLinkAtTheCommand) {
  const Held h = hold_at_rest(phri::SimRobotConfig::Elasticity::Encoder::kMotorCompensated);
  const phri::SimRobotConfig c = phri::SimRobotConfig::from_yaml_file(kRoot + "/configs/plant_gen3.yaml");
  for (int i = 0; i < 7; ++i) {
    const double k = c.elasticity.stiffness_Nm_per_rad[static_cast<std::size_t>(i)];
    EXPECT_NEAR(h.q_link[i], h.command[i], 2e-5) << "joint " << i + 1;
    // The rotor leads the link by the spring's deflection tau / K.
    EXPECT_NEAR(h.q_motor[i] - h.q_link[i], h.gravity[i] / k, 2e-5 + 1e-3 * std::abs(h.gravity[i] / k)) << "joint " << i + 1;
    EXPECT_NEAR(h.tau_sensor[i], h.gravity[i], 0.02 + 1e-3 * std::abs(h.gravity[i])) << "joint " << i + 1;
  }
}

// Kinova's low-level examples start by commanding each actuator's measured position, which holds the
// arm still (reference kortex_lowlevel.md section 5, step 3). The largest change of the motor torque
// K_T i over the first 50 ms of that command, from the plant's own hold.
double motor_torque_jump_on_measured_position(phri::SimRobotConfig::Elasticity::Encoder encoder, double stiffness) {
  phri::SimRobotConfig c = quiet_elastic_plant(encoder);
  c.elasticity.stiffness_Nm_per_rad.assign(7, stiffness);
  phri::SimRobot robot(c);
  const phri::RobotState start = robot.read();
  phri::RobotCommand hold(7);
  hold.mode = phri::LowLevelMode::kPosition;
  hold.q_rad = start.q_rad;
  const phri::ActuatorTable drives = robot.config().plant_actuators();
  double jump = 0.0;
  for (int k = 0; k < 50; ++k) {
    robot.write(hold);
    const phri::RobotState& s = robot.read();
    for (int i = 0; i < 7; ++i) {
      jump = std::max(jump, std::abs(drives[static_cast<std::size_t>(i)].torque_per_amp() * (s.current_A[i] - start.current_A[i])));
    }
  }
  return jump;
}

TEST(SimElastic, CommandingTheMeasuredPositionHoldsStillOnlyWhenTheServoCompensatesTheDeflection) {
  using Encoder = phri::SimRobotConfig::Elasticity::Encoder;
  for (const double k : {4000.0, 13000.0}) {
    const double motor = motor_torque_jump_on_measured_position(Encoder::kMotor, k);
    const double compensated = motor_torque_jump_on_measured_position(Encoder::kMotorCompensated, k);
    std::printf("K %.0f N.m/rad: motor torque jump %.2f N.m on the rotor encoder, %.3f N.m less the deflection\n", k,
                motor, compensated);
    // Joint 2 holds about 17 N.m at this pose: the rotor encoder's servo steps by kp tau / K.
    EXPECT_GT(motor, 5.0) << "K " << k;
    EXPECT_LT(compensated, 0.5) << "K " << k;
  }
}

// The paper's position mode (ControllerSettings::position_mode_open_loop) on the elastic plant: the
// QP runs on the state the low level integrates, so nothing feeds the links' deflection back; the
// reference stays where the arm was when the loop started and the links settle tau / K below the
// rotors, with tau the gravity torque MuJoCo computes at the settled pose.
TEST(SimElastic, OpenLoopPositionModeLeavesTheSpringDeflectionUncorrected) {
  phri::SimRobotConfig c = phri::SimRobotConfig::from_yaml_file(kRoot + "/configs/plant_gen3.yaml");
  c.initial_q_rad = kPose;
  c.elasticity.enabled = true;
  phri::SimRobot robot(c);
  phri::ControllerSettings s = phri::test::gen3_controller_settings(phri::ComplianceMode::kStiff);
  s.position_mode_open_loop = true;
  phri::Controller cycle(s);
  phri::RobotCommand command(7);
  phri::ControllerTargets targets(7);
  const Eigen::VectorXd q_start = robot.state().q_rad;
  for (int k = 0; k < 3000; ++k) {
    const phri::RobotState& state = robot.read();
    cycle.step(state, targets, command);
    robot.write(command);
  }
  const Eigen::VectorXd& q_ref = cycle.low_level().position_reference();
  const mjData* d = robot.mujoco_data();
  for (int i = 0; i < 7; ++i) {
    const double k = c.elasticity.stiffness_Nm_per_rad[static_cast<std::size_t>(i)];
    EXPECT_NEAR(q_ref[i], q_start[i], 1e-4) << "joint " << i + 1;  // the QP saw no error to correct
    EXPECT_NEAR(robot.truth().q_rad[i] - q_ref[i], -d->qfrc_bias[i] / k, 5e-5 + 0.02 * std::abs(d->qfrc_bias[i] / k))
        << "joint " << i + 1;
  }
  EXPECT_FALSE(robot.state().fault);
}

// The ringing figure of issue 39 (elastic_modes.hpp): rotor B and link J on a spring K have one
// non-zero mode, the generalized eigenvalue of K [[1, -1], [-1, 1]] x = w^2 diag(J, B) x; the closed
// form sqrt(K (1/J + 1/B)) / 2 pi must equal it, and the plant's figure must use the plant's own K, B
// and link-side M_ii (MuJoCo's full inertia matrix's diagonal: the rotor is off the link).
TEST(SimElastic, TwoMassModeIsTheSpringsEigenvalueOnThePlantsInertia) {
  for (const auto& [k, j, b] : {std::tuple{13000.0, 2.5, 0.03}, std::tuple{5500.0, 0.012, 0.03}, std::tuple{4000.0, 0.3, 0.3}}) {
    Eigen::Matrix2d stiffness, inertia;
    stiffness << k, -k, -k, k;
    inertia << j, 0.0, 0.0, b;
    const Eigen::GeneralizedSelfAdjointEigenSolver<Eigen::Matrix2d> modes(stiffness, inertia);
    const double eigen_hz = std::sqrt(modes.eigenvalues().maxCoeff()) / (2.0 * std::numbers::pi);
    EXPECT_NEAR(phri::two_mass_mode_hz(k, j, b), eigen_hz, 1e-9 * eigen_hz);
    EXPECT_LT(std::abs(modes.eigenvalues().minCoeff()), 1e-9 * modes.eigenvalues().maxCoeff());  // the rigid motion
  }
  EXPECT_EQ(phri::two_mass_mode_hz(1000.0, 0.0, 0.03), 0.0);

  phri::SimRobotConfig c = phri::SimRobotConfig::from_yaml_file(kRoot + "/configs/plant_gen3.yaml");
  c.initial_q_rad = kPose;
  c.elasticity.enabled = true;
  phri::SimRobot robot(c);
  robot.read();
  const std::vector<phri::ElasticJointMode> plant = phri::elastic_joint_modes(robot);
  ASSERT_EQ(plant.size(), 7u);
  const mjModel* m = robot.mujoco_model();
  std::vector<mjtNum> full(static_cast<std::size_t>(m->nv * m->nv));
  mj_fullM(m, full.data(), robot.mujoco_data()->qM);
  for (int i = 0; i < 7; ++i) {  // the arm's 7 hinges come first in the scene
    const phri::ElasticJointMode& mode = plant[static_cast<std::size_t>(i)];
    EXPECT_DOUBLE_EQ(mode.stiffness_Nm_per_rad, c.elasticity.stiffness_Nm_per_rad[static_cast<std::size_t>(i)]);
    EXPECT_DOUBLE_EQ(mode.rotor_inertia_kgm2, robot.plant_actuators()[i].reflected_inertia_kgm2);
    EXPECT_NEAR(mode.link_inertia_kgm2, full[static_cast<std::size_t>(i * m->nv + i)], 1e-12);
    EXPECT_NEAR(mode.mode_hz, phri::two_mass_mode_hz(mode.stiffness_Nm_per_rad, mode.link_inertia_kgm2, mode.rotor_inertia_kgm2), 1e-12);
    EXPECT_GT(mode.mode_hz, mode.locked_link_hz);  // the link's inertia only adds to 1/B
  }
  c.elasticity.enabled = false;
  EXPECT_TRUE(phri::elastic_joint_modes(phri::SimRobot(c)).empty());
}

}  // namespace
