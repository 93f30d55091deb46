// ctest-labels: unit
// phri::FakeRobot, the MuJoCo-free arm for tests of the run loop, against its closed forms: the
// position servo reaching the set-point in one period, the unit-inertia double integrator under
// constant torque or current (semi-implicit Euler: qd_k = k T u, q_k = q_0 + T^2 u k (k + 1) / 2),
// the RobotInterface contract (time and cycle of read k, refused commands change nothing but the
// status, no allocation), and each fault hook on exactly the reads or writes it names.
#include <phri/core/error.hpp>
#include <phri/robot/fake_robot.hpp>

#include "allocation_counter.hpp"
#include "config_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <vector>

namespace {

constexpr double kT = 1e-3;

phri::FakeRobotSettings three_joints() {
  phri::FakeRobotSettings s;
  s.dof = 3;
  s.period_s = kT;
  s.initial_q_rad = Eigen::Vector3d(0.1, -0.2, 0.3);
  s.torque_per_amp_Nm_per_A = Eigen::Vector3d(11.0, 7.6, 2.0);
  return s;
}

TEST(FakeRobot, BeforeAnyWriteItHoldsItsInitialPostureAndReadKHasTimeKT) {
  phri::FakeRobot robot(three_joints());
  EXPECT_EQ(robot.dof(), 3);
  EXPECT_EQ(robot.period_s(), kT);
  for (std::uint64_t k = 1; k <= 5; ++k) {
    const phri::RobotState& s = robot.read();
    EXPECT_EQ(s.cycle, k);
    EXPECT_NEAR(s.time_s, 1e-3 * static_cast<double>(k), 1e-15);
    EXPECT_EQ(s.joints.sequence, k);
    EXPECT_TRUE(s.joints.valid && s.torque.valid && s.current.valid);
    EXPECT_FALSE(s.wrench.valid) << "no F/T sensor";
    EXPECT_EQ(s.q_rad, Eigen::VectorXd(Eigen::Vector3d(0.1, -0.2, 0.3)));
    EXPECT_EQ(s.qd_rad_s, Eigen::VectorXd::Zero(3));
    EXPECT_EQ(s.mode, phri::LowLevelMode::kPosition);
  }
  EXPECT_EQ(robot.reads(), 5u);
  EXPECT_EQ(robot.writes(), 0u);
}

TEST(FakeRobot, PositionModeReachesTheSetPointInOnePeriod) {
  phri::FakeRobot robot(three_joints());
  phri::RobotCommand command(3);
  command.q_rad = Eigen::Vector3d(0.2, -0.2, 0.25);
  ASSERT_EQ(robot.write(command), phri::WriteStatus::kOk);
  EXPECT_EQ(robot.true_q(), Eigen::VectorXd(Eigen::Vector3d(0.1, -0.2, 0.3))) << "takes effect at the next read";
  const phri::RobotState& s = robot.read();
  EXPECT_EQ(s.q_rad, command.q_rad);
  // qd = (q_cmd - q) / T: 100, 0, -50 rad/s; from rest, the link's acceleration is qd / T.
  EXPECT_NEAR(s.qd_rad_s[0], 100.0, 1e-9);
  EXPECT_NEAR(s.qd_rad_s[1], 0.0, 1e-12);
  EXPECT_NEAR(s.qd_rad_s[2], -50.0, 1e-9);
  EXPECT_NEAR(s.tau_sensor_Nm[0], 1e5, 1e-5);
  EXPECT_NEAR(s.current_A[0], 1e5 / 11.0, 1e-6);
  // Held: velocity back to zero, position unchanged.
  const phri::RobotState& again = robot.read();
  EXPECT_EQ(again.q_rad, command.q_rad);
  EXPECT_NEAR(again.qd_rad_s.norm(), 0.0, 1e-12);
}

TEST(FakeRobot, TorqueModeIntegratesAUnitInertiaExactlyAsSemiImplicitEuler) {
  const Eigen::Vector3d u(2.0, -1.0, 0.5);
  for (const phri::LowLevelMode mode :
       {phri::LowLevelMode::kKinovaTorque, phri::LowLevelMode::kKinovaTorqueHighVelocity}) {
    phri::FakeRobot arm(three_joints());
    phri::RobotCommand command(3);
    command.mode = mode;
    command.tau_Nm = u;
    ASSERT_EQ(arm.write(command), phri::WriteStatus::kOk);
    for (int k = 1; k <= 1000; ++k) {
      const phri::RobotState& s = arm.read();
      const double kk = static_cast<double>(k);
      for (int i = 0; i < 3; ++i) {
        ASSERT_NEAR(s.qd_rad_s[i], kk * kT * u[i], 1e-12) << k;
        ASSERT_NEAR(s.q_rad[i], three_joints().initial_q_rad[i] + kT * kT * u[i] * kk * (kk + 1.0) / 2.0, 1e-12) << k;
        ASSERT_NEAR(s.tau_sensor_Nm[i], u[i], 1e-9);
      }
      ASSERT_EQ(s.mode, mode);
    }
    // After 1 s: q_0 + u t^2 / 2 plus the scheme's u T t / 2 (continuous reference, O(T) apart).
    EXPECT_NEAR(arm.true_q()[0], 0.1 + 2.0 * 0.5 + 2.0 * kT * 1.0 / 2.0, 1e-12);
  }
}

TEST(FakeRobot, CurrentModeDrivesTorquePerAmpTimesTheCurrent) {
  phri::FakeRobot robot(three_joints());
  phri::RobotCommand command(3);
  command.mode = phri::LowLevelMode::kCurrent;
  command.current_A = Eigen::Vector3d(0.1, -0.5, 1.0);  // torques 1.1, -3.8, 2.0 N.m
  ASSERT_EQ(robot.write(command), phri::WriteStatus::kOk);
  for (int k = 1; k <= 100; ++k) robot.read();
  const phri::RobotState& s = robot.state();
  EXPECT_NEAR(s.qd_rad_s[0], 0.1 * 1.1, 1e-12);
  EXPECT_NEAR(s.qd_rad_s[1], 0.1 * -3.8, 1e-12);
  EXPECT_NEAR(s.qd_rad_s[2], 0.1 * 2.0, 1e-12);
  EXPECT_NEAR(s.current_A[1], -0.5, 1e-12);
  EXPECT_NEAR(s.tau_sensor_Nm[1], -3.8, 1e-12);
  EXPECT_EQ(s.mode, phri::LowLevelMode::kCurrent);
}

TEST(FakeRobot, InvalidCommandsAreRefusedWithTheirStatusAndChangeNothing) {
  phri::FakeRobot robot(three_joints());
  phri::RobotCommand command(3);
  command.q_rad = Eigen::Vector3d(0.0, 0.0, 0.0);
  ASSERT_EQ(robot.write(command), phri::WriteStatus::kOk);
  const phri::RobotCommand accepted = robot.last_accepted();

  phri::RobotCommand wrong_size(2);
  EXPECT_EQ(robot.write(wrong_size), phri::WriteStatus::kSizeMismatch);
  phri::RobotCommand not_finite(3);
  not_finite.mode = phri::LowLevelMode::kKinovaTorque;
  not_finite.tau_Nm[1] = NAN;
  EXPECT_EQ(robot.write(not_finite), phri::WriteStatus::kNotFinite);
  phri::RobotCommand bad_mode(3);
  bad_mode.mode = static_cast<phri::LowLevelMode>(9);
  EXPECT_EQ(robot.write(bad_mode), phri::WriteStatus::kInvalidMode);
  // Only the selected mode's vector is read: a NaN elsewhere is no reason to refuse.
  phri::RobotCommand other_nan(3);
  other_nan.q_rad = Eigen::Vector3d(0.0, 0.0, 0.0);
  other_nan.current_A[0] = NAN;
  EXPECT_EQ(robot.write(other_nan), phri::WriteStatus::kOk);

  EXPECT_EQ(robot.writes(), 5u);
  EXPECT_EQ(robot.refused_writes(), 3u);
  EXPECT_EQ(robot.accepted_writes(), 2u);
  EXPECT_EQ(robot.last_accepted().mode, accepted.mode);
  EXPECT_EQ(robot.last_accepted().q_rad, accepted.q_rad);
  const phri::RobotState& s = robot.read();
  EXPECT_EQ(s.rejected_writes, 3u);
  EXPECT_EQ(s.last_write_status, phri::WriteStatus::kOk);
  EXPECT_EQ(s.q_rad, Eigen::VectorXd::Zero(3));
}

TEST(FakeRobot, EachFaultHookActsOnExactlyTheReadsItNames) {
  phri::FakeRobot robot(three_joints());
  robot.inject_nan({.first = 3, .count = 2}, 1);
  robot.invalidate_joints({.first = 6, .count = 1});
  robot.freeze_joints({.first = 8, .count = 3});
  phri::RobotCommand command(3);
  command.mode = phri::LowLevelMode::kKinovaTorque;
  command.tau_Nm = Eigen::Vector3d(1.0, 1.0, 1.0);  // moving: a frozen frame is visible
  robot.write(command);
  std::uint32_t last_sequence = 0;
  double last_q = 0.0;
  for (std::uint64_t k = 1; k <= 12; ++k) {
    SCOPED_TRACE("read " + std::to_string(k));
    const phri::RobotState& s = robot.read();
    EXPECT_EQ(s.cycle, k);
    const bool nan = k == 3 || k == 4, invalid = k == 6, frozen = k >= 8 && k <= 10;
    EXPECT_EQ(std::isnan(s.q_rad[1]), nan);
    EXPECT_TRUE(std::isfinite(s.q_rad[0]) && std::isfinite(s.q_rad[2]));
    EXPECT_TRUE(s.joints.valid || invalid);
    EXPECT_EQ(s.joints.valid, !invalid);
    if (frozen) {
      EXPECT_EQ(s.joints.sequence, last_sequence) << "no new joint frame";
      EXPECT_EQ(s.q_rad[0], last_q);
      EXPECT_NE(robot.true_q()[0], last_q) << "the arm moves underneath";
    } else {
      EXPECT_EQ(s.joints.sequence, last_sequence + 1);
      EXPECT_EQ(s.q_rad[0], robot.true_q()[0]);
    }
    last_sequence = s.joints.sequence;
    last_q = s.q_rad[0];
  }
}

TEST(FakeRobot, RefusedWritesKeepThePreviousCommandAndAreCountedInTheState) {
  phri::FakeRobot robot(three_joints());
  robot.refuse_writes({.first = 2, .count = 2}, phri::WriteStatus::kOutOfRange);
  std::vector<phri::WriteStatus> seen;
  robot.set_write_observer([&](const phri::RobotCommand&, phri::WriteStatus status) { seen.push_back(status); });
  phri::RobotCommand command(3);
  for (int k = 1; k <= 4; ++k) {
    command.q_rad = Eigen::Vector3d::Constant(0.01 * k);
    robot.write(command);
    robot.read();
  }
  using W = phri::WriteStatus;
  EXPECT_EQ(seen, (std::vector<W>{W::kOk, W::kOutOfRange, W::kOutOfRange, W::kOk}));
  EXPECT_EQ(robot.refused_writes(), 2u);
  EXPECT_EQ(robot.state().rejected_writes, 2u);
  EXPECT_EQ(robot.state().q_rad, Eigen::VectorXd::Constant(3, 0.04));
  // Writes 2 and 3 were refused: reads 2 and 3 still showed command 1's 0.01 rad.
  phri::FakeRobot replay(three_joints());
  replay.refuse_writes({.first = 2, .count = 2}, W::kOutOfRange);
  for (int k = 1; k <= 3; ++k) {
    command.q_rad = Eigen::Vector3d::Constant(0.01 * k);
    replay.write(command);
    EXPECT_EQ(replay.read().q_rad, Eigen::VectorXd::Constant(3, 0.01)) << k;
    EXPECT_EQ(replay.state().last_write_status, k == 1 ? W::kOk : W::kOutOfRange);
  }
}

TEST(FakeRobot, InFaultItRefusesEveryWriteAndStandsStill) {
  phri::FakeRobot robot(three_joints());
  phri::RobotCommand command(3);
  command.mode = phri::LowLevelMode::kKinovaTorque;
  command.tau_Nm = Eigen::Vector3d(1.0, 1.0, 1.0);
  robot.write(command);
  for (int k = 0; k < 10; ++k) robot.read();
  robot.set_fault(true);
  const Eigen::VectorXd q = robot.true_q();
  EXPECT_EQ(robot.write(command), phri::WriteStatus::kFault);
  const phri::RobotState& s = robot.read();
  EXPECT_TRUE(s.fault);
  EXPECT_EQ(s.q_rad, q);
  EXPECT_EQ(s.qd_rad_s, Eigen::VectorXd::Zero(3));
  robot.set_fault(false);
  EXPECT_EQ(robot.write(command), phri::WriteStatus::kOk);
  EXPECT_FALSE(robot.read().fault);
}

TEST(FakeRobot, ReadAndWriteDoNotAllocate) {
  phri::FakeRobot robot(phri::FakeRobotSettings{});
  phri::RobotCommand command(7);
  command.mode = phri::LowLevelMode::kCurrent;
  command.current_A.setConstant(0.1);
  robot.inject_nan({.first = 3, .count = 1});
  robot.freeze_joints({.first = 5, .count = 2});
  phri::test::AllocationCounter count;
  {
    phri::test::NoMallocScope no_malloc;
    for (int k = 0; k < 20; ++k) {
      robot.read();
      robot.write(command);
    }
  }
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_EQ(robot.reads(), 20u);
}

TEST(FakeRobot, BadSettingsAreRefused) {
  using phri::test::expect_config_error;
  phri::FakeRobotSettings s;
  s.dof = 0;
  expect_config_error([&] { phri::FakeRobot robot(s); }, {.element = "dof", .file = "FakeRobotSettings"});
  s = {};
  s.period_s = 0.0;
  expect_config_error([&] { phri::FakeRobot robot(s); }, {.element = "period_s"});
  s = {};
  s.initial_q_rad = Eigen::VectorXd::Zero(3);
  EXPECT_THROW(phri::FakeRobot robot(s), phri::ArgumentError);
}

}  // namespace
