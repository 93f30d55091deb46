// ctest-labels: unit
// phri::StateSupervisor alone, on synthetic samples of one joint moving at constant speed: the
// re-synchronisation after a gap or a jumped counter, the kinematics kept for the brake when only
// the torque is wrong, and the stop on a gap beyond the degraded budget.
#include <phri/safety/state_supervisor.hpp>

#include <gtest/gtest.h>

#include <cstdint>
#include <string>
#include <limits>

namespace {

using phri::SafetyFault;
using phri::SupervisorState;

phri::SensorRanges one_joint() {
  phri::SensorRanges r;
  auto one = [](double v) { return Eigen::VectorXd::Constant(1, v); };
  r.q_lower = one(-10.0);
  r.q_upper = one(10.0);
  r.velocity_limit = one(1.4);
  r.torque_range = one(50.0);
  r.current_range = one(10.0);
  return r;
}

constexpr double kSpeed = 0.8;  // [rad/s]

// The k-th sample of the joint at kSpeed (k periods of 1 ms), with a torque of 5 N.m plus a small
// ripple (real sensors never repeat a value bit for bit).
phri::RobotState sample(long k) {
  phri::RobotState s(1);
  s.joints.valid = s.torque.valid = true;
  s.time_s = s.joints.stamp_s = s.torque.stamp_s = 1e-3 * static_cast<double>(k);
  s.joints.sequence = s.torque.sequence = static_cast<std::uint32_t>(k);
  s.q_rad[0] = kSpeed * s.time_s;
  s.qd_rad_s[0] = kSpeed;
  s.tau_sensor_Nm[0] = 5.0 + 1e-3 * static_cast<double>(k % 7);
  return s;
}

TEST(StateSupervisor, OneSampleWithAJumpedSequenceIsOneMissingSample) {
  phri::StateSupervisor supervisor(one_joint(), phri::SupervisorSettings{});
  for (long k = 1; k <= 100; ++k) ASSERT_TRUE(supervisor.check(sample(k)));
  phri::RobotState jumped = sample(101);
  jumped.joints.sequence += 1000000;
  EXPECT_FALSE(supervisor.check(jumped));
  EXPECT_EQ(supervisor.sample_fault(), SafetyFault::kStampJump);
  for (long k = 102; k <= 110; ++k) EXPECT_TRUE(supervisor.check(sample(k))) << k;
  EXPECT_EQ(supervisor.state(), SupervisorState::kNormal);
  EXPECT_EQ(supervisor.last_good().joints.sequence, 110u);
}

TEST(StateSupervisor, ACounterThatStaysJumpedIsFollowedAfterOneSample) {
  struct Jump {
    std::uint32_t sequence;
    double stamp_s;
    bool stops;  // both jumped: a gap as far as the robot's counters can tell, a safe stop
  };
  for (const Jump jump : {Jump{1000000u, 0.0, false}, Jump{0u, 0.5, false}, Jump{1000000u, 0.5, true}}) {
    SCOPED_TRACE(std::to_string(jump.sequence) + " / " + std::to_string(jump.stamp_s));
    phri::StateSupervisor supervisor(one_joint(), phri::SupervisorSettings{});
    for (long k = 1; k <= 100; ++k) ASSERT_TRUE(supervisor.check(sample(k)));
    // From 101 on the counters are off (a restarted link, garbage counters): the first such sample
    // is missing, the next one follows on from it.
    long accepted = 0;
    for (long k = 101; k <= 200; ++k) {
      phri::RobotState s = sample(k);
      s.joints.sequence += jump.sequence;
      s.joints.stamp_s += jump.stamp_s;
      accepted += supervisor.check(s) ? 1 : 0;
    }
    EXPECT_EQ(accepted, 99);
    EXPECT_EQ(supervisor.resyncs(), 1);
    EXPECT_EQ(supervisor.safe_stop(), jump.stops) << "one counter says one period passed: no gap";
    // And back to the original counters: again one sample.
    accepted = 0;
    for (long k = 201; k <= 210; ++k) accepted += supervisor.check(sample(k)) ? 1 : 0;
    EXPECT_EQ(accepted, 9);
    EXPECT_EQ(supervisor.resyncs(), 2);
    if (!jump.stops) {
      EXPECT_EQ(supervisor.state(), SupervisorState::kNormal);
    }
  }
}

TEST(StateSupervisor, AGapBeyondTheBudgetStopsAndTheStopSeesTheSamplesAfterIt) {
  for (const long missing : {19L, 50L, 2000L}) {
    SCOPED_TRACE(missing);
    phri::StateSupervisor supervisor(one_joint(), phri::SupervisorSettings{});
    for (long k = 1; k <= 100; ++k) ASSERT_TRUE(supervisor.check(sample(k)));
    const long first = 101 + missing;  // sequence and stamps both skip `missing` periods
    supervisor.check(sample(first));
    for (long k = first + 1; k <= first + 10; ++k) EXPECT_TRUE(supervisor.check(sample(k))) << k;
    // 20 ms is the budget (SupervisorSettings::max_degraded_s): 19 missing periods are a 20 ms gap.
    EXPECT_EQ(supervisor.safe_stop(), missing > 19);
    if (missing > 19) {
      EXPECT_EQ(supervisor.safe_stop_transition().reason, SafetyFault::kDegradedTooLong);
    }
    EXPECT_DOUBLE_EQ(supervisor.last_good().q_rad[0], sample(first + 10).q_rad[0]) << "measured, not held";
    EXPECT_TRUE(supervisor.kinematics_fresh());
  }
}

TEST(StateSupervisor, AfterAGapTheMotionIsJudgedAgainstTheSampleBefore) {
  phri::StateSupervisor supervisor(one_joint(), phri::SupervisorSettings{});
  for (long k = 1; k <= 100; ++k) ASSERT_TRUE(supervisor.check(sample(k)));
  supervisor.check(sample(200));  // a 100-period gap: missing, the candidate to follow
  phri::RobotState teleported = sample(201);
  teleported.q_rad[0] += 0.5;  // half a radian in one period
  EXPECT_FALSE(supervisor.check(teleported));
  EXPECT_EQ(supervisor.sample_fault(), SafetyFault::kPositionJump);
}

TEST(StateSupervisor, ARepeatedFrameIsStaleEvenAfterAJump) {
  phri::StateSupervisor supervisor(one_joint(), phri::SupervisorSettings{});
  for (long k = 1; k <= 100; ++k) ASSERT_TRUE(supervisor.check(sample(k)));
  EXPECT_FALSE(supervisor.check(sample(100)));
  EXPECT_EQ(supervisor.sample_fault(), SafetyFault::kStale);
  EXPECT_TRUE(supervisor.check(sample(101)));
}

TEST(StateSupervisor, ATorqueOutOfRangeKeepsTheJointsKinematicsForTheBrake) {
  phri::StateSupervisor supervisor(one_joint(), phri::SupervisorSettings{});
  for (long k = 1; k <= 100; ++k) ASSERT_TRUE(supervisor.check(sample(k)));
  phri::RobotState s = sample(101);
  s.tau_sensor_Nm[0] = 1e6;
  EXPECT_FALSE(supervisor.check(s));
  EXPECT_EQ(supervisor.sample_fault(), SafetyFault::kTorqueRange);
  EXPECT_TRUE(supervisor.kinematics_fresh());
  EXPECT_DOUBLE_EQ(supervisor.kinematic_q()[0], s.q_rad[0]);
  EXPECT_DOUBLE_EQ(supervisor.last_good().q_rad[0], sample(100).q_rad[0]);
  // A NaN position is no kinematics at all.
  s = sample(102);
  s.q_rad[0] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(supervisor.check(s));
  EXPECT_FALSE(supervisor.kinematics_fresh());
  EXPECT_DOUBLE_EQ(supervisor.kinematic_q()[0], sample(101).q_rad[0]);
}

TEST(StateSupervisor, AFaultOfTheStopItselfIsKeptBesideTheStopsReason) {
  phri::StateSupervisor supervisor(one_joint(), phri::SupervisorSettings{});
  ASSERT_TRUE(supervisor.check(sample(1)));
  supervisor.report(SafetyFault::kWriteRefused, 0.001);
  supervisor.report(SafetyFault::kHoldRefused, 0.007);
  EXPECT_EQ(supervisor.safe_stop_transition().reason, SafetyFault::kWriteRefused);
  EXPECT_EQ(supervisor.escalation().reason, SafetyFault::kHoldRefused);
  EXPECT_DOUBLE_EQ(supervisor.escalation().time_s, 0.007);
  supervisor.reset();
  EXPECT_EQ(supervisor.escalation().reason, SafetyFault::kNone);
}

}  // namespace
