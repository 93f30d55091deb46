// ctest-labels: unit
// ControllerTargets, the controller's one way in while running: each kind of target takes effect
// in the cycle it is given; a target of the wrong size, non-finite or out of range is ignored
// (the previous one kept), counted and reported in the cycle's status, and never reaches the QP.
// Driven on FakeRobot (position servo, no MuJoCo).
#include <phri/app/fsm.hpp>
#include <phri/control/controller.hpp>
#include <phri/robot/fake_robot.hpp>

#include "allocation_counter.hpp"

#include "gen3_settings.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace {

class ControllerTargetsTest : public ::testing::Test {
protected:
  ControllerTargetsTest() : controller_(phri::test::gen3_controller_settings()), targets_(7), command_(7) {
    Eigen::VectorXd q(7);
    q << 0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57;
    phri::FakeRobotSettings s;
    s.initial_q_rad = q;
    robot_.emplace(s);
    step();  // the first cycle takes the arm's pose as the targets
  }
  phri::CycleStatus step() {
    const phri::CycleStatus status = controller_.step(robot_->read(), targets_, command_);
    robot_->write(command_);
    targets_.clear();
    return status;
  }

  phri::Controller controller_;
  phri::ControllerTargets targets_;
  phri::RobotCommand command_;
  std::optional<phri::FakeRobot> robot_;
};

TEST_F(ControllerTargetsTest, EachRequestTakesEffectInTheCycleItIsGiven) {
  targets_.compliance_mode = phri::ComplianceMode::kFullBody;
  targets_.low_level_mode = phri::LowLevelMode::kKinovaTorque;
  targets_.stiffness_scale = 10.0;  // clamped to the compliance controller's 4
  EXPECT_EQ(step(), phri::CycleStatus::kOk);
  EXPECT_EQ(controller_.compliance().mode(), phri::ComplianceMode::kFullBody);
  EXPECT_EQ(controller_.low_level().loop(), phri::LowLevelMode::kKinovaTorque);
  EXPECT_EQ(command_.mode, phri::LowLevelMode::kKinovaTorque);
  EXPECT_DOUBLE_EQ(controller_.compliance().stiffness_scale(), 4.0);
  // Nothing given: nothing changes.
  EXPECT_EQ(step(), phri::CycleStatus::kOk);
  EXPECT_EQ(controller_.compliance().mode(), phri::ComplianceMode::kFullBody);
  EXPECT_EQ(controller_.rejected_targets(), 0);
}

TEST_F(ControllerTargetsTest, ReferencesPersistUntilTheNextOne) {
  Eigen::VectorXd posture = controller_.qp().posture().target();
  posture[3] += 0.1;
  targets_.has_posture = true;
  targets_.posture.q = posture;
  targets_.posture.qd.setZero();
  targets_.posture.qdd.setZero();
  Eigen::Isometry3d pose = controller_.qp().end_effector().target_pose();
  pose.translation().z() += 1e-5;  // within one period's governed step: tracked as given
  targets_.has_pose = true;
  targets_.pose = {pose, phri::Vector6d::Zero(), phri::Vector6d::Zero()};
  EXPECT_EQ(step(), phri::CycleStatus::kOk);
  for (int k = 0; k < 5; ++k) step();
  EXPECT_TRUE(controller_.qp().posture().target().isApprox(posture, 0.0));
  EXPECT_NEAR((controller_.qp().end_effector().target_pose().translation() - pose.translation()).norm(), 0.0, 1e-12);
}

TEST_F(ControllerTargetsTest, BadTargetsAreIgnoredCountedAndReportedWithoutAllocating) {
  const Eigen::VectorXd posture_before = controller_.qp().posture().target();
  const Eigen::Isometry3d pose_before = controller_.qp().end_effector().target_pose();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  phri::ControllerTargets short_posture(6);
  short_posture.has_posture = true;
  phri::ControllerTargets nan_pose(7);
  nan_pose.has_pose = true;
  nan_pose.pose.pose.translation().x() = nan;
  phri::ControllerTargets bad_scale(7);
  bad_scale.stiffness_scale = -1.0;
  phri::ControllerTargets bad_mode(7);
  bad_mode.low_level_mode = static_cast<phri::LowLevelMode>(9);

  phri::test::AllocationCounter count;
  for (const phri::ControllerTargets* bad : {&short_posture, &nan_pose, &bad_scale, &bad_mode}) {
    const phri::CycleStatus status = controller_.step(robot_->read(), *bad, command_);
    robot_->write(command_);
    EXPECT_EQ(status, phri::CycleStatus::kTargetsRejected);
  }
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_EQ(controller_.rejected_targets(), 4);
  EXPECT_TRUE(controller_.qp().posture().target().isApprox(posture_before, 0.0));
  EXPECT_TRUE(controller_.qp().end_effector().target_pose().isApprox(pose_before, 1e-12));
  EXPECT_DOUBLE_EQ(controller_.compliance().stiffness_scale(), 1.0);
  EXPECT_EQ(controller_.low_level().loop(), phri::LowLevelMode::kPosition);
  EXPECT_TRUE(command_.q_rad.allFinite());
  EXPECT_EQ(step(), phri::CycleStatus::kOk);  // and the next good cycle is ok again
}

TEST_F(ControllerTargetsTest, StiffnessEventsInOneCycleActAsIfHandledOneByOne) {
  // Seven presses up saturate the scale at 4 (1.25^7 = 4.77); one press down then gives 4 / 1.25,
  // as it would over eight cycles, though all reach the FSM in the same period (unclamped, the
  // presses would give 1.25^6 = 3.81).
  phri::FsmSettings settings;
  settings.startup.enabled = false;
  phri::Fsm fsm(settings, controller_);
  for (int k = 0; k < 7; ++k) fsm.post(phri::Event::kStiffnessUp);
  fsm.post(phri::Event::kStiffnessDown);
  const phri::RobotState& state = robot_->read();
  controller_.step(state, fsm.update(state.time_s, state, controller_), command_);
  EXPECT_DOUBLE_EQ(controller_.compliance().stiffness_scale(), 4.0 / 1.25);
}

}  // namespace
