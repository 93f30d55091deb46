// ctest-labels: physics
// Faults that arrive while the arm moves under a push (issue 37): a control-thread stall, a
// sequence jump, a torque-sensor offset. Whatever the cause, the stop must bring the arm to rest
// within its limits, at most at its velocity limit, and end in a hold the robot accepts. Judged on
// the plant's truth (joint limits, speed), and on the writes the plant refused at the end.
#include <phri/control/controller.hpp>

#include "hand_push.hpp"
#include "safety_rig.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <string>

namespace {

using phri::test::hand_push;
using phri::test::joint_direction;
using Rig = phri::test::SafetyRig;
using phri::ComplianceMode;
using phri::LowLevelMode;

constexpr LowLevelMode kLoops[] = {LowLevelMode::kPosition, LowLevelMode::kKinovaTorque,
                                   LowLevelMode::kKinovaTorqueHighVelocity, LowLevelMode::kCurrent};

std::string name(LowLevelMode loop) { return std::string(phri::to_string(loop)); }

// The verdict every case shares: never over the velocity limit nor past a joint limit, the last
// 0.5 s without a refused write; stopped: at rest in the robot's hold; not stopped: where the same
// run without the fault (`clean`) rests.
void expect_safe_end(const Rig& rig, const Rig& clean, const std::string& what) {
  const bool stopped = rig.cycle_.supervisor().safe_stop();
  const double off_path = phri::test::distance(rig.q(), clean.q());
  std::printf("%s: max |qd| / limit %.3f, limit excess %.4f rad, refused writes %ld (last at %.3f s), end speed %.4f, "
              "off the fault-free path %.4f rad, state %s (%s)\n",
              what.c_str(), rig.speed_ratio_, rig.limit_excess_, rig.refused_, rig.last_refused_s_,
              rig.qd().cwiseAbs().maxCoeff(), off_path, std::string(phri::to_string(rig.cycle_.supervisor().state())).c_str(),
              std::string(phri::to_string(rig.cycle_.supervisor().safe_stop_transition().reason)).c_str());
  EXPECT_LE(rig.speed_ratio_, 1.0);
  EXPECT_LE(rig.limit_excess_, 0.0);
  EXPECT_LT(rig.last_refused_s_, rig.robot_.state().time_s - 0.5) << "writes still refused at the end";
  if (stopped) {
    EXPECT_LT(rig.qd().cwiseAbs().maxCoeff(), 0.01) << "at rest at the end";
    EXPECT_EQ(rig.robot_.state().mode, LowLevelMode::kPosition) << "in the robot's hold";
    EXPECT_TRUE(rig.cycle_.holding());
  } else if (clean.qd().cwiseAbs().maxCoeff() < 0.01) {
    EXPECT_LT(off_path, 0.05) << "back where the fault-free run rests (the safety fuzz's tolerance)";
  } else {
    // The fault-free run is still walking back (a carried arm, ReturnLeash): two moving arms at
    // different phases of the walk are not compared; the limits above still hold.
    std::printf("  (the fault-free run still moves at %.3f rad/s: not compared)\n", clean.qd().cwiseAbs().maxCoeff());
  }
}

// A push on the wrist turning the arm about its base, ramped in at 0.5 s for 1.5 s; the stall
// comes 0.3 s into it, with the arm moving.
phri::ExternalForce wrist_push(double force_N) {
  return hand_push("spherical_wrist_1_link", Eigen::Vector3d::Zero(), force_N * joint_direction("spherical_wrist_1_link", 0),
                   0.5, 1.5);
}

TEST(SafeStopInMotion, AControlThreadStallUnderAPushEndsInAnAcceptedHold) {
  for (const long periods : {19L, 20L, 50L}) {
    for (const LowLevelMode loop : kLoops) {
      const std::string what = "stall " + std::to_string(periods) + " periods, 80 N, full_body, " + name(loop);
      SCOPED_TRACE(what);
      Rig clean(ComplianceMode::kFullBody, loop, {wrist_push(80.0)});
      Rig rig(ComplianceMode::kFullBody, loop, {wrist_push(80.0)});
      // Long enough for a carried arm to walk back home (ReturnLeash) after the push.
      clean.run(10.0);
      rig.run(0.8);
      rig.stall(periods);
      rig.run(10.0 - 0.8 - 0.001 * static_cast<double>(periods));
      expect_safe_end(rig, clean, what);
      // Beyond the degraded budget (20 ms) the robot ran on a stale command too long: a safe stop.
      EXPECT_EQ(rig.cycle_.supervisor().safe_stop(), periods >= 20);
    }
  }
}

TEST(SafeStopInMotion, OneSequenceJumpUnderAPushIsOneMissingSample) {
  for (const LowLevelMode loop : kLoops) {
    const std::string what = "sequence +1e6 once, 40 N, null_space, " + name(loop);
    SCOPED_TRACE(what);
    Rig clean(ComplianceMode::kNullSpace, loop, {wrist_push(40.0)});
    Rig rig(ComplianceMode::kNullSpace, loop, {wrist_push(40.0)});
    clean.run(3.5);
    rig.run(3.5, [](long k, phri::RobotState& s) {
      if (k == 800) {
        s.joints.sequence += 1000000;
        s.torque.sequence += 1000000;
        s.current.sequence += 1000000;
      }
    });
    expect_safe_end(rig, clean, what);
    EXPECT_FALSE(rig.cycle_.supervisor().safe_stop()) << "one missing sample is no reason to stop";
    EXPECT_LT(phri::test::distance(rig.q(), clean.q()), 0.02) << "on the fault-free path";
  }
}

TEST(SafeStopInMotion, ATorqueSensorOffsetStopsWithoutOverspeed) {
  for (const ComplianceMode mode : {ComplianceMode::kNullSpace, ComplianceMode::kFullBody}) {
  for (const int joint : {1, 6}) {
    for (const LowLevelMode loop : {LowLevelMode::kKinovaTorque, LowLevelMode::kKinovaTorqueHighVelocity, LowLevelMode::kCurrent}) {
      const std::string what = "+50 N.m on joint " + std::to_string(joint + 1) + ", " + std::string(phri::to_string(mode)) +
                               ", " + name(loop);
      SCOPED_TRACE(what);
      Rig clean(mode, loop, {wrist_push(40.0)});
      Rig rig(mode, loop, {wrist_push(40.0)});
      clean.run(3.5);
      rig.run(3.5, [joint](long k, phri::RobotState& s) {
        if (k >= 800 && k < 900) s.tau_sensor_Nm[joint] += 50.0;
      });
      expect_safe_end(rig, clean, what);
      EXPECT_EQ(rig.cycle_.supervisor().safe_stop_transition().reason, phri::SafetyFault::kTorqueCurrentMismatch);
    }
  }
  }
}

}  // namespace

namespace {

// A robot that refuses every command: the first refusal starts the stop in the same cycle, the
// next ones re-target the hold at the pose the robot reports, and a hold refused more than
// max_hold_refusals cycles in a row is the stop's own fault.
TEST(SafeStopInMotion, ARefusedHoldIsRetargetedEachCycleAndThenAFaultOfItsOwn) {
  Rig rig(ComplianceMode::kNullSpace, LowLevelMode::kCurrent);
  rig.run(0.5);
  const int allowed = rig.cycle_.settings().safety.max_hold_refusals;
  for (int k = 0; k <= allowed + 1; ++k) {
    const phri::RobotState& state = rig.robot_.read();
    rig.cycle_.step(state, rig.targets_, rig.command_);
    ASSERT_TRUE(rig.cycle_.answer_refused_write(state, rig.command_));
    EXPECT_TRUE(rig.cycle_.supervisor().safe_stop());
    if (k >= 1) {
      EXPECT_EQ(rig.command_.mode, LowLevelMode::kPosition);
      EXPECT_EQ(rig.command_.q_rad, state.q_rad) << "the hold where the robot says it is";
    }
    const phri::SafetyFault escalation = rig.cycle_.supervisor().escalation().reason;
    EXPECT_EQ(escalation, k >= allowed ? phri::SafetyFault::kHoldRefused : phri::SafetyFault::kNone) << k;
  }
  EXPECT_EQ(rig.cycle_.supervisor().safe_stop_transition().reason, phri::SafetyFault::kWriteRefused);
}

}  // namespace
