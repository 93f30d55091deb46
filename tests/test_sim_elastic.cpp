// ctest-labels: physics
// Joint elasticity in the simulated plant (SimRobotConfig::Elasticity, ElasticTransmission): at rest
// under the vendor position servo, the spring carries the gravity torque MuJoCo computes for the
// link (qfrc_bias), the torque sensor reads it, and the link sags by tau / K behind a motor-side
// servo while a link-side servo holds the link itself at its set-point.
#include <phri/control/controller.hpp>
#include <phri/sim/sim_robot.hpp>

#include "gen3_settings.hpp"

#include <mujoco/mujoco.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;
const std::vector<double> kPose = {0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57};

struct Held {
  Eigen::VectorXd q_link, q_motor, tau_sensor, gravity, command;
};

Held hold_at_rest(phri::SimRobotConfig::Elasticity::Encoder encoder) {
  phri::SimRobotConfig c = phri::SimRobotConfig::from_yaml_file(kRoot + "/configs/plant_gen3.yaml");
  c.initial_q_rad = kPose;
  c.noise.torque_sensor_std_Nm = 0.0;
  c.noise.velocity_std_rad_s = 0.0;
  c.noise.current_std_A = 0.0;
  c.noise.encoder_counts_per_rev = 0.0;
  c.noise.torque_sensor_offset_Nm.assign(7, 0.0);
  c.elasticity.enabled = true;
  c.elasticity.position_loop_encoder = encoder;
  phri::SimRobot robot(c);
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

}  // namespace
