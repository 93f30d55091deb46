// ctest-labels: physics
// The safety promise on the realistic plant (phri::SimRobot, 5 % mismatch, friction, noise):
// regression tests for the defects a hostile tester found, each written against behaviour (the
// plant's true motion), not against the fix. A sensor fault is injected between the robot and the
// controller, as a corrupted frame would arrive; pushes are scripted hand pushes on the plant.
// Each test compares with the same run without the fault where that is the reference.
#include <phri/control/controller.hpp>
#include <phri/core/error.hpp>
#include <phri/experiments/run_validity.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/sim/sim_robot.hpp>

#include "allocation_counter.hpp"
#include "hand_push.hpp"
#include "safety_rig.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <limits>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;
using phri::test::distance;
using phri::test::hand_push;
using phri::test::joint_direction;
using phri::test::kLimit2;
using phri::test::kLimit4;
using phri::test::kLimit6;
using Rig = phri::test::SafetyRig;
using Corrupt = phri::test::Corrupt;

// Defect 1: one finite but implausible sample (±1e6 on one joint's τ_s, q̇ or q) made the observer
// report ~5e4 N.m of phantom push; the arm was slammed (39x the velocity limit). Now it is a
// missing sample: the arm stays on its fault-free path.
TEST(Safety, OneImplausibleSampleDoesNotMoveTheArm) {
  Rig reference(phri::ComplianceMode::kNullSpace, phri::LowLevelMode::kCurrent);
  reference.run(3.5);
  struct Spike {
    const char* name;
    Corrupt corrupt;
  };
  const std::vector<Spike> spikes = {
      {"tau_s[1] + 1e6", [](long k, phri::RobotState& s) { if (k == 500) s.tau_sensor_Nm[1] += 1e6; }},
      {"qd[1] + 1e6", [](long k, phri::RobotState& s) { if (k == 500) s.qd_rad_s[1] += 1e6; }},
      {"q[1] + 1e6", [](long k, phri::RobotState& s) { if (k == 500) s.q_rad[1] += 1e6; }},
      {"qd[3] - 3 rad/s", [](long k, phri::RobotState& s) { if (k == 500) s.qd_rad_s[3] -= 3.0; }},
  };
  for (const Spike& spike : spikes) {
    SCOPED_TRACE(spike.name);
    Rig rig(phri::ComplianceMode::kNullSpace, phri::LowLevelMode::kCurrent);
    rig.run(3.5, spike.corrupt);
    std::printf("spike %-16s: max |qd| / limit %.3f, final distance to the fault-free run %.4f rad\n", spike.name,
                rig.speed_ratio_, distance(rig.q(), reference.q()));
    EXPECT_LT(rig.speed_ratio_, 0.2);
    EXPECT_LT(distance(rig.q(), reference.q()), 0.01);
    EXPECT_NE(rig.cycle_.status(), phri::CycleStatus::kSafeStop) << "one sample is not a reason to stop";
  }
}

// Defect 2: in the position loop, q_ref was integrated open loop: when the servo could not follow
// (a ~190 N upward push on the bracelet in stiff mode), q_ref ran away, every later write was
// refused and the robot kept executing an old set-point. Now q_ref stays near the arm, no write is
// refused, and after the push the arm is back where it was.
TEST(Safety, PositionLoopReferenceNeverRunsAwayFromTheArm) {
  Rig rig(phri::ComplianceMode::kStiff, phri::LowLevelMode::kPosition,
          {hand_push("bracelet_link", Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 250.0), 1.0, 0.8)});
  rig.run(0.5);
  const Eigen::VectorXd start = rig.q();
  double max_lead = 0.0, speed_after = 0.0;
  rig.run(4.0, {}, [&]() {
    max_lead = std::max(max_lead, distance(rig.cycle_.low_level().position_reference(), rig.robot_.state().q_rad));
    if (rig.robot_.truth().time_s > 1.9) {
      for (int i = 0; i < 7; ++i) speed_after = std::max(speed_after, std::abs(rig.qd()[i]) / rig.velocity_limit_[i]);
    }
  });
  std::printf("position loop, 250 N push: reference ahead of the arm by at most %.4f rad; refused writes %ld; "
              "final distance to the start %.4f rad; max |qd| / limit %.3f (after the push %.3f)\n",
              max_lead, rig.refused_, distance(rig.q(), start), rig.speed_ratio_, speed_after);
  EXPECT_LT(max_lead, 0.0873) << "within Kinova's 5 degree following-error fault";
  EXPECT_EQ(rig.refused_, 0);
  EXPECT_LT(distance(rig.q(), start), 0.05);
  EXPECT_LT(speed_after, 1.0) << "the push (beyond what the servo resists) ended: no swing";
}

// A safe stop in the position loop while the arm moves (its end effector streamed along x at
// 0.2 m/s): the held reference brakes from where it is, so the servo's torque makes no step (it
// jumped to the measured pose: a spike of kd x (following error / T) in the velocity
// feed-forward: 33 N.m here).
TEST(Safety, ASafeStopInThePositionLoopBrakesTheReferenceWithoutATorqueStep) {
  Rig rig(phri::ComplianceMode::kNullSpace, phri::LowLevelMode::kPosition);
  rig.run(0.3);
  Eigen::Isometry3d pose = rig.cycle_.qp().end_effector().target_pose();
  double before = 0.0, after = 0.0;
  Eigen::VectorXd last_tau = rig.robot_.truth().tau_motor_Nm;
  auto largest_step = [&](double& largest) {
    largest = std::max(largest, (rig.robot_.truth().tau_motor_Nm - last_tau).cwiseAbs().maxCoeff());
    last_tau = rig.robot_.truth().tau_motor_Nm;
  };
  rig.run(0.5, {}, [&]() {
    pose.translation().x() += 0.2 * rig.robot_.period_s();
    rig.targets_.has_pose = true;
    rig.targets_.pose.pose = pose;
    rig.targets_.pose.velocity.setZero();
    rig.targets_.pose.velocity[0] = 0.2;
    if (rig.robot_.truth().time_s > 0.5) largest_step(before);
  });
  const double speed_at_fault = rig.qd().cwiseAbs().maxCoeff();
  rig.cycle_.report_fault(phri::SafetyFault::kWriteRefused, 0.8);
  const Eigen::VectorXd start = rig.q();
  rig.run(0.5, {}, [&]() { largest_step(after); });
  std::printf("safe stop in the position loop at %.3f rad/s: largest motor-torque step per ms %.2f N.m before, %.2f after; "
              "%.4f rad travelled while braking; refused writes %ld\n",
              speed_at_fault, before, after, distance(rig.q(), start), rig.refused_);
  EXPECT_GT(speed_at_fault, 0.1) << "the arm moves when the stop comes";
  EXPECT_EQ(rig.cycle_.status(), phri::CycleStatus::kSafeStop);
  EXPECT_TRUE(rig.cycle_.holding());
  EXPECT_LT(rig.qd().cwiseAbs().maxCoeff(), 0.01) << "at rest 0.5 s later";
  EXPECT_LT(after, before + 5.0);
  EXPECT_LT(distance(rig.q(), start), speed_at_fault / 20.0 + 0.01) << "the brake's distance: speed / brake_rate";
  EXPECT_EQ(rig.refused_, 0);
}

// Defect 2, second half: a refused write is a fault the loop acts on (here: the controller is told
// by the caller, as run_session does) — a safe stop, at rest, holding.
TEST(Safety, ARefusedWriteReportedToTheControllerEndsInASafeStopAtRest) {
  Rig rig(phri::ComplianceMode::kNullSpace, phri::LowLevelMode::kCurrent);
  rig.run(0.5);
  rig.cycle_.report_fault(phri::SafetyFault::kWriteRefused, 0.5);
  const Eigen::VectorXd start = rig.q();
  rig.run(1.0);
  EXPECT_EQ(rig.cycle_.status(), phri::CycleStatus::kSafeStop);
  EXPECT_TRUE(rig.cycle_.holding());
  EXPECT_EQ(rig.command_.mode, phri::LowLevelMode::kPosition);
  EXPECT_LT(rig.qd().cwiseAbs().maxCoeff(), 0.01);
  EXPECT_LT(distance(rig.q(), start), 0.02);
  EXPECT_EQ(rig.refused_, 0);
}

// Defect 3: a joint in its hard stop. The stop's reaction reaches the torque sensors like a push
// (the momentum observer cannot tell them apart); fed back through tau_d = M qdd + h - tau_ext it
// made the controller press into the stop, whose answer grew the "push", and so on. Here the
// controller sees joint 4 at rest 0.01 rad inside its lower limit with a 20 N.m outward reaction
// on its sensor: tau_d must not press further into the stop, and must push out against the
// joint's static friction (the damper's acceleration alone is below it, so a joint could rest in
// the stop). Kinova's torque loop (no friction compensation of ours), full-body compliance.
TEST(Safety, AHardStopIsNotReadAsAPushAndTheJointIsPushedOut) {
  phri::Controller cycle(phri::test::gen3_controller_settings(phri::ComplianceMode::kFullBody,
                                                              phri::LowLevelMode::kKinovaTorque));
  phri::Model model = phri::Model::from_urdf_file(kRoot + "/robots/kinova_gen3/gen3.urdf",
                                                  phri::Controller::model_options(cycle.settings()));
  phri::Data data(model);
  Eigen::VectorXd q(7), zero = Eigen::VectorXd::Zero(7);
  q << 0, 0.58, 3.14, -2.56, 0, 0.85, 1.57;
  phri::compute_all_terms(model, data, q, zero);
  const Eigen::VectorXd gravity = data.nonlinear_effects;
  phri::RobotState state(7);
  state.q_rad = q;
  state.joints.valid = state.torque.valid = true;
  phri::RobotCommand command(7);
  double pressing = 0.0;
  for (int k = 1; k <= 500; ++k) {
    state.time_s = state.joints.stamp_s = 1e-3 * k;
    state.joints.sequence = state.torque.sequence = static_cast<std::uint32_t>(k);
    state.qd_rad_s.setConstant(k % 2 ? 1e-4 : -1e-4);  // sensor noise
    // The link side carries what holds the arm plus the stop's push outward (+ for a lower stop).
    state.tau_sensor_Nm = gravity;
    state.tau_sensor_Nm[3] -= 20.0;  // sensor: torque transmitted to the link; the stop adds +20 as external
    cycle.step(state, command);
    pressing = command.tau_Nm[3] - gravity[3];
  }
  std::printf("hard stop: observer tau_ext[4] %.2f N.m; tau_d[4] - g[4] = %.2f N.m (static friction 2.15)\n",
              cycle.observer().external_torque()[3], pressing);
  EXPECT_GT(cycle.observer().external_torque()[3], 15.0) << "the observer does see the reaction";
  EXPECT_EQ(command.mode, phri::LowLevelMode::kKinovaTorque);
  EXPECT_GT(pressing, 2.15) << "out of the stop, against static friction";
}

// Defect 4: the velocity limit in the custom loop against pushes the arm can easily resist: a
// 41 N push turning the arm about its base in full-body compliance, and a 160 N tangential push
// on the elbow (~7 N.m... tens of N.m on joint 1, well within its torque) in null-space mode.
TEST(Safety, VelocityLimitHoldsAgainstPushesTheArmCanResist) {
  struct Case {
    phri::ComplianceMode mode;
    const char* link;
    double force_N;
  };
  for (const Case& c : {Case{phri::ComplianceMode::kFullBody, "spherical_wrist_1_link", 41.0},
                        Case{phri::ComplianceMode::kNullSpace, "half_arm_2_link", 160.0}}) {
    for (const phri::LowLevelMode loop : {phri::LowLevelMode::kCurrent, phri::LowLevelMode::kKinovaTorque}) {
      SCOPED_TRACE(std::string(phri::to_string(loop)) + ", " + c.link);
      const Eigen::Vector3d force = c.force_N * joint_direction(c.link, 0);
      Rig rig(c.mode, loop, {hand_push(c.link, Eigen::Vector3d::Zero(), force, 0.5, 2.0)});
      double moved = 0.0;
      rig.run(3.0, {}, [&]() { moved = std::max(moved, std::abs(rig.q()[0])); });
      std::printf("%.0f N on %s, %s, %s loop: joint 1 moved %.3f rad, max |qd| / limit %.3f\n", c.force_N, c.link,
                  std::string(phri::to_string(c.mode)).c_str(), std::string(phri::to_string(loop)).c_str(), moved,
                  rig.speed_ratio_);
      EXPECT_LT(rig.speed_ratio_, 1.0);
    }
  }
}

// Defect 5: an observer gain with K_O T >= 2 makes the discrete observer unstable (inf/NaN
// tau_ext); it was accepted. And a QP that keeps failing never led to a safe stop.
TEST(Safety, AnUnstableObserverGainIsRefusedAndAQpThatKeepsFailingStopsSafely) {
  phri::ControllerSettings s = phri::test::gen3_controller_settings();
  s.observer_gain = 2500.0;
  EXPECT_THROW(phri::Controller{s}, phri::ConfigError);
  // Torque limits no posture can be held with: the QP is infeasible every cycle.
  Rig rig(phri::ComplianceMode::kNullSpace, phri::LowLevelMode::kCurrent, {}, [](phri::ControllerSettings& c) {
    c.qp.torque_limit = Eigen::VectorXd::Constant(7, 0.5);
  });
  rig.run(1.5);
  EXPECT_EQ(rig.cycle_.status(), phri::CycleStatus::kSafeStop);
  EXPECT_EQ(rig.cycle_.supervisor().safe_stop_transition().reason, phri::SafetyFault::kQpFailure);
  EXPECT_TRUE(rig.cycle_.holding());
  EXPECT_LT(rig.qd().cwiseAbs().maxCoeff(), 0.01);
}

// A push the QP cannot answer (its torque limits lowered to a third here; the drives keep theirs):
// the QP falls back, then the safe stop. Its brake was gravity compensation and damping only; the
// push it dropped then flung the arm (safety-fuzz seed 24680, full_body/custom/3: 2.66x the
// velocity limit, a joint past its limit, -34 mm collision). The brake goes on resisting the push
// it saw, as the QP's fallback did, up to the drive's torque. Before: 1.07x and 1.02 rad after the
// stop (stiff, 70 N), 0.75 rad (full body, 50 N); now 0.12 and 0.11 rad, below the limit. (Since
// the custom loop's entry stopped carrying the position loop's friction hold into sliding, 70 N
// no longer makes the QP fail in stiff mode: 80 N, 0.95x and 0.12 rad; since the bounds hold the push
// the command does not cancel yet, nor does 80 N: 90 N, 0.83x and 0.08 rad. With scaled braking the
// QP answers 90 N in stiff mode too, braking with the share of its dampers' demands the cut limits
// allow: it is off here, for the fallback and the stop this test is about.)
TEST(Safety, ASafeStopAfterTheQpFailedUnderAPushKeepsResistingIt) {
  struct Case {
    phri::ComplianceMode mode;
    double force_N;
  };
  for (const Case& c : {Case{phri::ComplianceMode::kStiff, 90.0}, Case{phri::ComplianceMode::kFullBody, 50.0}}) {
    SCOPED_TRACE(std::string(phri::to_string(c.mode)));
    const Eigen::Vector3d force = c.force_N * joint_direction("bracelet_link", 1);
    Rig rig(c.mode, phri::LowLevelMode::kCurrent, {hand_push("bracelet_link", Eigen::Vector3d::Zero(), force, 0.5, 2.0)},
            [](phri::ControllerSettings& s) {
              s.qp.torque_limit.resize(7);
              s.qp.torque_limit << 30, 30, 30, 30, 8, 15, 8;
              s.qp.scale_braking = false;
            });
    bool stopped = false;
    double ratio_after = 0.0, moved_after = 0.0;
    Eigen::VectorXd q_stop;
    rig.run(3.0, {}, [&]() {
      if (!stopped && rig.cycle_.status() == phri::CycleStatus::kSafeStop) {
        stopped = true;
        q_stop = rig.q();
      }
      if (!stopped) return;
      ratio_after = std::max(ratio_after, rig.qd().cwiseQuotient(rig.velocity_limit_).cwiseAbs().maxCoeff());
      moved_after = std::max(moved_after, distance(rig.q(), q_stop));
    });
    std::printf("%.0f N on the bracelet, %s: after the safe stop max |qd| / limit %.3f, moved %.3f rad\n", c.force_N,
                std::string(phri::to_string(c.mode)).c_str(), ratio_after, moved_after);
    ASSERT_TRUE(stopped);
    EXPECT_EQ(rig.cycle_.supervisor().safe_stop_transition().reason, phri::SafetyFault::kQpFailure);
    EXPECT_LT(ratio_after, 1.0);
    EXPECT_LT(moved_after, 0.25);
    EXPECT_TRUE(rig.cycle_.holding());
    EXPECT_LT(rig.qd().cwiseAbs().maxCoeff(), 0.01);
    EXPECT_LE(rig.limit_excess_, 0.0);
  }
}

// A run's validity names why its QP fell back: under a 90 N push on the bracelet with the torque
// limits cut (as above) the hold h - tau_ext asks one joint for more than its limit, and the reason
// says which joint and how much, the largest |h_i - tau_ext_i| / limit_i over the fallback cycles
// recomputed here from the controller's model terms and estimate.
TEST(Safety, AQpFallbackUnderALoadBeyondAnActuatorIsNamedInTheRunsValidity) {
  const Eigen::Vector3d force = 90.0 * joint_direction("bracelet_link", 1);
  Rig rig(phri::ComplianceMode::kStiff, phri::LowLevelMode::kCurrent,
          {hand_push("bracelet_link", Eigen::Vector3d::Zero(), force, 0.5, 2.0)}, [](phri::ControllerSettings& s) {
            s.qp.torque_limit.resize(7);
            s.qp.torque_limit << 30, 30, 30, 30, 8, 15, 8;
          });
  phri::RunValidity validity;
  double worst = 0.0;
  int worst_joint = -1;
  long fallbacks = 0;
  rig.run(1.5, {}, [&]() {
    validity.check_cycle(rig.cycle_.status(), rig.cycle_, rig.command_, false, phri::LowLevelMode::kCurrent);
    if (rig.cycle_.status() != phri::CycleStatus::kQpFallback) return;
    ++fallbacks;
    const Eigen::VectorXd hold = rig.cycle_.data().nonlinear_effects - rig.cycle_.external_torque();
    for (int i = 0; i < 7; ++i) {
      const double ratio = std::abs(hold[i]) / rig.cycle_.qp().torque_limit()[i];
      if (ratio > worst) worst = ratio, worst_joint = i;
    }
  });
  ASSERT_GT(fallbacks, 0) << "the push must make the QP fail for this test to mean anything";
  EXPECT_EQ(validity.qp_fallbacks, fallbacks);
  EXPECT_GT(worst, 1.0);
  EXPECT_EQ(validity.fallback_hold_joint, worst_joint);
  EXPECT_NEAR(validity.fallback_hold_ratio, worst, 1e-12);
  const std::string why = validity.invalid_reason();
  EXPECT_NE(why.find("joint " + std::to_string(worst_joint + 1) + " for "), std::string::npos) << why;
  EXPECT_NE(why.find("beyond its actuator"), std::string::npos) << why;
  EXPECT_FALSE(validity.valid());
}

// A robot that still obeys but asks for a safe stop (RobotState::stop_requested: the Kortex
// backend's degraded link) while a push moves the arm: the stop is logged as robot_stop_request,
// the samples stay good, and the brake blends in from the last command over
// requested_stop_blend_s instead of stepping to it (13.6 N.m on the demo through the emulator).
TEST(Safety, ARequestedStopBrakesWithoutATorqueStep) {
  struct Outcome {
    double largest_step = 0.0, speed_at_request = 0.0;
  };
  auto run = [](double blend_s) {
    Rig rig(phri::ComplianceMode::kNullSpace, phri::LowLevelMode::kCurrent,
            {hand_push("forearm_link", Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 30, 0), 0.6, 1.0)},
            [blend_s](phri::ControllerSettings& s) { s.safety.requested_stop_blend_s = blend_s; });
    Outcome o;
    Eigen::VectorXd previous = rig.robot_.truth().tau_motor_Nm;
    rig.run(2.5, [](long k, phri::RobotState& s) { s.stop_requested = k >= 1000; }, [&]() {
      const Eigen::VectorXd& tau = rig.robot_.truth().tau_motor_Nm;
      if (rig.cycle_count_ == 1000) o.speed_at_request = rig.qd().cwiseAbs().maxCoeff();
      if (rig.cycle_count_ >= 1000) o.largest_step = std::max(o.largest_step, (tau - previous).cwiseAbs().maxCoeff());
      previous = tau;
    });
    EXPECT_EQ(rig.cycle_.status(), phri::CycleStatus::kSafeStop);
    EXPECT_EQ(rig.cycle_.supervisor().safe_stop_transition().reason, phri::SafetyFault::kRobotStopRequest);
    EXPECT_TRUE(rig.cycle_.holding());
    EXPECT_LT(rig.qd().cwiseAbs().maxCoeff(), 0.01);
    EXPECT_LT(rig.speed_ratio_, 1.0);
    return o;
  };
  const Outcome blended = run(0.05), stepped = run(0.0);
  std::printf("stop requested at %.2f rad/s: largest motor torque step %.2f N.m blended, %.2f N.m without the blend\n",
              blended.speed_at_request, blended.largest_step, stepped.largest_step);
  EXPECT_GT(blended.speed_at_request, 0.1);  // the arm was moving
  EXPECT_LT(blended.largest_step, 0.5 * stepped.largest_step);
}

// Defect 6: with NaN on q2 for 2.5 s, the torque loops repeated the last torque or current command
// for the whole time and the arm moved 5-6 rad. Now: a brake, then the robot's position hold,
// which also resists a push meanwhile.
TEST(Safety, InvalidDataForSecondsBrakeAndHoldInEveryTorqueLoop) {
  for (const phri::LowLevelMode loop : {phri::LowLevelMode::kCurrent, phri::LowLevelMode::kKinovaTorque,
                                        phri::LowLevelMode::kKinovaTorqueHighVelocity, phri::LowLevelMode::kPosition}) {
    SCOPED_TRACE(std::string(phri::to_string(loop)));
    // A 40 N push on the wrist while the data are invalid: nothing but the robot's own hold
    // resists it (a repeated torque command would not).
    const Eigen::Vector3d force = 40.0 * joint_direction("spherical_wrist_1_link", 0);
    Rig rig(phri::ComplianceMode::kNullSpace, loop, {hand_push("spherical_wrist_1_link", Eigen::Vector3d::Zero(), force, 1.0, 1.0)});
    rig.run(0.5);
    const Eigen::VectorXd start = rig.q();
    rig.run(3.0, [](long k, phri::RobotState& s) {
      if (k >= 500 && k < 3000) s.q_rad[1] = std::numeric_limits<double>::quiet_NaN();
    });
    std::printf("NaN on q2 for 2.5 s, %s loop: moved %.4f rad, max |qd| / limit %.3f\n",
                std::string(phri::to_string(loop)).c_str(), distance(rig.q(), start), rig.speed_ratio_);
    EXPECT_LT(distance(rig.q(), start), 0.05);
    EXPECT_LT(rig.speed_ratio_, 0.2);
    EXPECT_LT(rig.qd().cwiseAbs().maxCoeff(), 0.01);
    EXPECT_EQ(rig.robot_.state().mode, phri::LowLevelMode::kPosition) << "the robot's hold at the end";
  }
}

// Defect 7: a current vector shorter than the joints (or empty) passed validation and the custom
// loop read past its end. Without current readings (current.valid false), the loop must work.
TEST(Safety, ShortOrMissingCurrentReadingsNeverCrashTheCustomLoop) {
  for (const int size : {0, 6}) {
    for (const bool valid : {true, false}) {
      SCOPED_TRACE("current_A of size " + std::to_string(size) + (valid ? ", valid" : ", invalid"));
      Rig rig(phri::ComplianceMode::kNullSpace, phri::LowLevelMode::kPosition);
      rig.run(0.3);
      const Eigen::VectorXd start = rig.q();
      phri::ControllerTargets to_custom(7);
      to_custom.low_level_mode = phri::LowLevelMode::kCurrent;
      rig.targets_ = to_custom;
      rig.run(1.0, [&](long, phri::RobotState& s) {
        s.current_A.conservativeResize(size);
        s.current.valid = valid;
      });
      EXPECT_LT(distance(rig.q(), start), 0.02);
      EXPECT_LT(rig.speed_ratio_, 0.2);
    }
  }
}

// Frozen values with an advancing sequence, frozen or jumping stamps: detected (a degraded spell
// that becomes a safe stop at rest), never estimated from.
TEST(Safety, FrozenValuesAndStaleStampsAreDetected) {
  struct Case {
    const char* name;
    Corrupt corrupt;
  };
  auto frozen = std::make_shared<phri::RobotState>();
  const std::vector<Case> cases = {
      {"frozen values", [frozen](long k, phri::RobotState& s) {
         if (k == 500) *frozen = s;
         if (k > 500) {
           const auto sequence = s.joints.sequence;
           const double stamp = s.joints.stamp_s;
           s = *frozen;
           s.joints.sequence = sequence;
           s.joints.stamp_s = stamp;
         }
       }},
      {"frozen stamp", [](long k, phri::RobotState& s) { if (k > 500) s.joints.stamp_s = 0.5; }},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.name);
    Rig rig(phri::ComplianceMode::kNullSpace, phri::LowLevelMode::kCurrent);
    rig.run(2.0, c.corrupt);
    EXPECT_EQ(rig.cycle_.status(), phri::CycleStatus::kSafeStop);
    EXPECT_GT(rig.cycle_.supervisor().implausible_samples(), 0);
    EXPECT_LT(rig.qd().cwiseAbs().maxCoeff(), 0.01);
    EXPECT_LT(rig.speed_ratio_, 0.2);
  }
}

// A clock that jumps back and runs on from there (a restarted link) with the sequence advancing
// is one missing sample, not an invalid state for ever: the next sample follows on from it.
TEST(Safety, AStampThatJumpsBackIsOneMissingSampleThenFollowed) {
  Rig clean(phri::ComplianceMode::kNullSpace, phri::LowLevelMode::kCurrent);
  Rig rig(phri::ComplianceMode::kNullSpace, phri::LowLevelMode::kCurrent);
  clean.run(2.0);
  rig.run(2.0, [](long k, phri::RobotState& s) { if (k > 500) s.joints.stamp_s -= 10.0; });
  EXPECT_EQ(rig.cycle_.supervisor().state(), phri::SupervisorState::kNormal);
  EXPECT_EQ(rig.cycle_.supervisor().implausible_samples(), 1);
  EXPECT_EQ(rig.cycle_.supervisor().resyncs(), 1);
  EXPECT_LT(distance(rig.q(), clean.q()), 1e-3);
}

// A q̇ offset that stays within range (3 rad/s on joint 4 for 100 ms, below the 2.5x bound) made
// the controller brake against a phantom motion: the true joint reached 1.34x its velocity limit.
// q̇ must agree with the rate of q: the offset is caught at its first sample, the arm never moves
// faster than 0.2x its limit and ends in a safe stop near the fault-free run's pose, in every loop.
TEST(Safety, AVelocityOffsetWithinRangeIsCaughtByTheRateOfQ) {
  for (phri::LowLevelMode loop : {phri::LowLevelMode::kPosition, phri::LowLevelMode::kKinovaTorque,
                                  phri::LowLevelMode::kKinovaTorqueHighVelocity, phri::LowLevelMode::kCurrent}) {
    SCOPED_TRACE(std::string(phri::to_string(loop)));
    Rig clean(phri::ComplianceMode::kNullSpace, loop), faulty(phri::ComplianceMode::kNullSpace, loop);
    clean.run(1.5);
    faulty.run(1.5, [](long k, phri::RobotState& s) { if (k >= 500 && k < 600) s.qd_rad_s[3] += 3.0; });
    EXPECT_EQ(faulty.cycle_.supervisor().safe_stop_transition().reason, phri::SafetyFault::kVelocityMismatch);
    EXPECT_EQ(faulty.cycle_.status(), phri::CycleStatus::kSafeStop);
    EXPECT_LT(faulty.speed_ratio_, 0.2);
    EXPECT_LT(distance(faulty.q(), clean.q()), 0.01);
  }
}

// A torque-sensor offset within range (+50 N.m on joint 6 for 100 ms: the small actuators read up
// to 2 x 26 N.m) made the observer report a 50 N.m push nobody made, and the controller drove the
// joint to cancel it: 1.45x its velocity limit in Kinova's high-velocity loop (safety-fuzz seed
// 55555). The motor current cannot explain such a τ_s: offsets from about the small joints'
// torque limit up are caught within milliseconds, the arm ends in a safe stop near the fault-free
// run's pose, in every torque loop.
TEST(Safety, ATorqueOffsetWithinRangeIsCaughtByTheMotorCurrent) {
  struct Offset {
    int joint;
    double Nm;
  };
  for (const Offset offset : {Offset{5, 50.0}, Offset{5, 20.0}, Offset{5, -12.0}, Offset{1, 60.0}, Offset{3, -30.0}}) {
    for (phri::LowLevelMode loop : {phri::LowLevelMode::kKinovaTorque, phri::LowLevelMode::kKinovaTorqueHighVelocity,
                                    phri::LowLevelMode::kCurrent}) {
      const std::string name = std::string(phri::to_string(loop)) + ", " + std::to_string(offset.Nm) + " N.m on joint " +
                               std::to_string(offset.joint + 1);
      SCOPED_TRACE(name);
      Rig clean(phri::ComplianceMode::kNullSpace, loop), faulty(phri::ComplianceMode::kNullSpace, loop);
      clean.run(1.5);
      faulty.run(1.5, [&](long k, phri::RobotState& s) { if (k >= 500 && k < 600) s.tau_sensor_Nm[offset.joint] += offset.Nm; });
      const phri::SafetyTransition& stop = faulty.cycle_.supervisor().safe_stop_transition();
      std::printf("%s: %s, max |qd| / limit %.3f, distance to the fault-free run %.4f rad\n", name.c_str(),
                  std::string(phri::to_string(stop.reason)).c_str(), faulty.speed_ratio_, distance(faulty.q(), clean.q()));
      EXPECT_EQ(stop.reason, phri::SafetyFault::kTorqueCurrentMismatch);
      EXPECT_EQ(stop.joint, offset.joint);
      EXPECT_LT(faulty.speed_ratio_, 0.4);  // -12 N.m on joint 6 is caught at about 0.3x in Kinova's loops
      // The stop holds where the arm came to rest: a joint caught at up to ~0.5 rad/s travels
      // v / brake_rate (~0.025 rad) on the hold's braking reference, after the drift before detection.
      EXPECT_LT(distance(faulty.q(), clean.q()), 0.06);
    }
  }
}

// The torque-current residual needs the rotor's acceleration, rigid (q̈) or through the
// harmonic drive's compliance (q̈ + τ̈_s / K): which one holds depends on the plant. A loop ringing
// at a third of the sample rate (Kinova's high-velocity loop, safety-fuzz seed 8642) moves τ_s
// and the current together, 25 N.m from sample to sample, at a steady speed: the rigid balance
// holds exactly while τ̈_s / K reads ~2000 rad/s^2, and a median of three of that pattern is
// biased (it read -36 N.m against a 35 N.m tolerance: a false safe stop under a 137 N push). The
// check now flags only what neither hypothesis explains; an offset still is.
TEST(Safety, ATorqueLoopRingingIsNotAMismatchButAnOffsetIs) {
  phri::SensorRanges ranges;
  auto one = [](double v) { return Eigen::VectorXd::Constant(1, v); };
  ranges.q_lower = one(-1e9);
  ranges.q_upper = one(1e9);
  ranges.velocity_limit = one(2.0944);
  ranges.torque_range = one(105.0);
  ranges.current_range = one(10.0);
  ranges.torque_per_amp = one(11.0);  // Gen3 large actuator: K_T 0.11 N.m/A x G_r 100
  ranges.reflected_inertia = one(0.03);
  ranges.friction_static = one(2.0);
  ranges.friction_coulomb = one(5.0);
  ranges.friction_viscous = one(0.2);
  ranges.transmission_compliance = one(1.0 / 13000.0);
  for (const double offset : {0.0, 50.0}) {
    SCOPED_TRACE(offset);
    phri::StateSupervisor supervisor(ranges, phri::SupervisorSettings{});
    phri::RobotState s(1);
    s.joints.valid = s.torque.valid = s.current.valid = true;
    const double speed = 1.6, kinetic = 5.0 + 0.2 * speed, ring[3] = {25.0, -12.5, -12.5};
    int flagged = 0;
    for (int k = 1; k <= 300; ++k) {
      s.time_s = s.joints.stamp_s = 1e-3 * k;
      s.joints.sequence = s.torque.sequence = s.current.sequence = static_cast<std::uint32_t>(k);
      s.q_rad[0] = speed * s.time_s;
      s.qd_rad_s[0] = speed;
      const double link = 10.0 + ring[k % 3];  // what the transmission carries
      s.current_A[0] = (link + kinetic) / 11.0;
      s.tau_sensor_Nm[0] = link + (k >= 150 ? offset : 0.0);
      if (!supervisor.check(s) && supervisor.sample_fault() == phri::SafetyFault::kTorqueCurrentMismatch) ++flagged;
    }
    std::printf("offset %.0f N.m under a period-3 ring of 25 N.m: %d of 300 samples flagged\n", offset, flagged);
    if (offset == 0.0) {
      EXPECT_EQ(flagged, 0);
    } else {
      EXPECT_GT(flagged, 100);
    }
  }
}

// A real push loads the motor and the torque sensor alike: hard pushes the arm resists or yields
// to, in every mode and torque loop, are never taken for a torque-current mismatch.
TEST(Safety, HardPushesAreNotATorqueCurrentMismatch) {
  for (phri::ComplianceMode mode : {phri::ComplianceMode::kStiff, phri::ComplianceMode::kFullBody}) {
    for (phri::LowLevelMode loop : {phri::LowLevelMode::kKinovaTorque, phri::LowLevelMode::kCurrent}) {
      SCOPED_TRACE(std::string(phri::to_string(mode)) + " / " + std::string(phri::to_string(loop)));
      Rig rig(mode, loop, {hand_push("bracelet_link", Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 0, 150.0), 0.5, 0.3),
                           hand_push("forearm_link", Eigen::Vector3d::Zero(), Eigen::Vector3d(120.0, 0, 0), 1.2, 0.4)});
      rig.run(2.0);
      EXPECT_EQ(rig.cycle_.supervisor().implausible_samples(), 0);
    }
  }
}

// A single-sample F/T spike (300 N) is not a dual-compliance touch.
TEST(Safety, ASingleSampleForceSpikeIsNotATouch) {
  Rig rig(phri::ComplianceMode::kDual, phri::LowLevelMode::kCurrent);
  rig.run(1.0);
  const int touches = rig.cycle_.compliance().touch_count();
  rig.run(1.0, [](long k, phri::RobotState& s) {
    if (k == 1500) {
      s.wrench_sensor[2] += 300.0;  // one F/T sample (the sensor runs at 1 kHz)
    }
  });
  EXPECT_EQ(rig.cycle_.compliance().touch_count(), touches);
}

// The supervisor and the safe stop allocate nothing: the controller's steps through spikes, a
// degraded spell, the brake and the hand-over to the hold, counted (the corrupted copy of the
// state is made before the count, outside the controller).
TEST(Safety, SupervisorDegradedSpellsAndTheSafeStopAllocateNothing) {
  for (const phri::LowLevelMode loop : {phri::LowLevelMode::kCurrent, phri::LowLevelMode::kKinovaTorque}) {
    Rig rig(phri::ComplianceMode::kNullSpace, loop);
    rig.run(0.3);
    phri::RobotState corrupted(7);
    std::size_t allocations = 0;
    for (int k = 0; k < 1500; ++k) {
      const phri::RobotState& state = rig.robot_.read();
      corrupted = state;
      if (k == 100) corrupted.tau_sensor_Nm[2] += 1e6;                                  // one spike
      if (k >= 200 && k < 210) corrupted.qd_rad_s[1] = std::numeric_limits<double>::quiet_NaN();  // degraded
      if (k >= 400) corrupted.q_rad[3] = std::numeric_limits<double>::infinity();        // -> safe stop
      phri::test::AllocationCounter count;
      rig.cycle_.step(corrupted, rig.command_);
      allocations += count.allocations();
      rig.robot_.write(rig.command_);
    }
    EXPECT_EQ(allocations, 0u);
    EXPECT_EQ(rig.cycle_.status(), phri::CycleStatus::kSafeStop);
    EXPECT_TRUE(rig.cycle_.holding());
    EXPECT_EQ(rig.cycle_.supervisor().transition_count(), 6u);  // (degraded, normal) x 2, degraded, safe stop
  }
}

// The plant refuses a position set-point further from the joint than Kinova's following-error
// fault (5 degrees), as the robot would fault on it; one within it is accepted.
TEST(Safety, ThePlantRefusesAPositionStepBeyondTheFollowingErrorBound) {
  Rig rig(phri::ComplianceMode::kNullSpace, phri::LowLevelMode::kPosition);
  rig.run(0.1);
  phri::RobotCommand command(7);
  command.mode = phri::LowLevelMode::kPosition;
  command.q_rad = rig.q();
  command.q_rad[1] += 0.2;
  EXPECT_EQ(rig.robot_.write(command), phri::WriteStatus::kOutOfRange);
  command.q_rad[1] = rig.q()[1] + 0.05;
  EXPECT_EQ(rig.robot_.write(command), phri::WriteStatus::kOk);
}

}  // namespace
