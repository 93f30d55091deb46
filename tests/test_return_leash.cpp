// ctest-labels: unit
// The way back after a carry (return_leash.hpp) and the end-effector stiction term
// (end_effector_task.hpp), against closed forms: the walk is a straight line in joint space at the
// set speed and ends exactly on the target; a dragging joint takes the leash along without a step;
// a lagging one does not hold it back; the pose offset carries the end-effector target onto the
// leash's own kinematics; continuous joints go the short way round; nothing is allocated.
#include <phri/control/end_effector_task.hpp>
#include <phri/control/return_leash.hpp>
#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>

#include "allocation_counter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace {

const std::string kGen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";

class ReturnLeashTest : public ::testing::Test {
protected:
  void SetUp() override {
    target_ << 0, 0.58, 3.14, -1.84, 0, 0.85, 1.57;
    zero_ = Eigen::VectorXd::Zero(7);
  }
  // Pull the leash out: joint velocities v for `seconds` while dragging, from the target.
  Eigen::VectorXd carry(phri::ReturnLeash& leash, const Eigen::VectorXd& v, double seconds) {
    Eigen::VectorXd q = target_;
    for (int k = 0; k < std::lround(seconds / dt_); ++k) {
      q += v * dt_;
      leash.update(model_, q, v, target_, zero_, true, dt_);
    }
    return q;
  }
  Eigen::Isometry3d pose_at(const Eigen::VectorXd& q) {
    phri::Data data(model_);
    phri::forward_kinematics(model_, data, q);
    phri::update_frame_placements(model_, data);
    return data.frame_placements[static_cast<std::size_t>(frame_)];
  }

  phri::Model model_ = phri::Model::from_urdf_file(kGen3 + "gen3.urdf");
  int frame_ = model_.frame_id("end_effector_link");
  Eigen::VectorXd target_{7}, zero_;
  double dt_ = 1e-3;
  // J̇ qd of the frame along x (zero at rest): the task subtracts it from its reference.
  double frame_bias_x(const phri::Data& data) const {
    return phri::frame_jdot_qdot(model_, data, frame_, phri::ReferenceFrame::kLocalWorldAligned)[0];
  }
};

TEST_F(ReturnLeashTest, ACarriedJointDragsTheLeashAtItsLengthWithoutAStep) {
  phri::ReturnLeash leash(model_, frame_, {.length_rad = 0.2, .return_speed_rad_s = 0.5});
  Eigen::VectorXd v = Eigen::VectorXd::Zero(7);
  v[1] = 1.0;  // joint 2 carried at 1 rad/s for 1 s
  Eigen::VectorXd q = target_;
  double largest_step = 0.0;
  Eigen::VectorXd previous = leash.offset();
  for (int k = 0; k < 1000; ++k) {
    q += v * dt_;
    leash.update(model_, q, v, target_, zero_, true, dt_);
    largest_step = std::max(largest_step, (leash.offset() - previous).cwiseAbs().maxCoeff());
    previous = leash.offset();
  }
  // It trails the joint by the length (the walk back pulls it in by 0.5 rad/s * dt each cycle
  // before the drag moves it with the joint).
  EXPECT_NEAR(q[1] - target_[1] - leash.offset()[1], 0.2, 1.0 * dt_ + 1e-9);
  EXPECT_LE(largest_step, 1.0 * dt_ + 1e-12);  // never faster than the joint
  for (int i : {0, 2, 3, 4, 5, 6}) EXPECT_EQ(leash.offset()[i], 0.0);
  EXPECT_TRUE(leash.out());
}

TEST_F(ReturnLeashTest, TheWalkBackIsAStraightLineAtTheSetSpeedEndingExactlyOnTheTarget) {
  phri::ReturnLeash leash(model_, frame_, {.length_rad = 0.1, .return_speed_rad_s = 0.5});
  Eigen::VectorXd v(7);
  v << 0.8, -0.4, 0.2, 0.0, 0.6, -0.3, 0.1;
  const Eigen::VectorXd q = carry(leash, v, 1.5);
  const Eigen::VectorXd start = leash.offset();
  const double largest = start.cwiseAbs().maxCoeff();
  ASSERT_GT(largest, 1.0);
  // Released: the arm stays where it is (a stuck arm must not hold the leash back).
  int k = 0;
  for (; leash.out() && k < 100000; ++k) {
    leash.update(model_, q, zero_, target_, zero_, true, dt_);
    if (k == 999) {  // after 1 s: 0.5 rad less on the largest joint, every joint by the same fraction
      const double fraction = 1.0 - 0.5 / largest;
      for (int i = 0; i < 7; ++i) EXPECT_NEAR(leash.offset()[i], fraction * start[i], 1e-9) << i;
    }
  }
  EXPECT_NEAR(k, largest / (0.5 * dt_), 1.0);
  EXPECT_TRUE(leash.offset().isZero(0.0));
  EXPECT_TRUE(leash.pose_offset().matrix().isIdentity(0.0));
}

TEST_F(ReturnLeashTest, ThePoseOffsetCarriesTheTargetOntoTheLeashKinematics) {
  phri::ReturnLeash leash(model_, frame_, {.length_rad = 0.1, .return_speed_rad_s = 0.5});
  Eigen::VectorXd v(7);
  v << 0.5, 0.3, -0.6, 0.4, 0.2, -0.5, 0.7;
  carry(leash, v, 1.0);
  const Eigen::Isometry3d at_leash = pose_at(target_ + leash.offset());
  // T_offset T(q*) = T(q_l): a target that was the posture's own pose follows the leash exactly.
  ASSERT_GT((at_leash.translation() - pose_at(target_).translation()).norm(), 0.05);  // really out
  EXPECT_LT(((leash.pose_offset() * pose_at(target_)).matrix() - at_leash.matrix()).cwiseAbs().maxCoeff(), 1e-12);
  // Any other target keeps its pose relative to the posture's: T_offset T* = T(q_l) T(q*)^-1 T*.
  Eigen::Isometry3d other = pose_at(target_);
  other.translation() += Eigen::Vector3d(0.05, -0.02, 0.1);
  const Eigen::Isometry3d relative = pose_at(target_).inverse() * other;
  EXPECT_LT(((leash.pose_offset() * other).matrix() - (at_leash * relative).matrix()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST_F(ReturnLeashTest, AContinuousJointCarriedPastHalfATurnGoesBackTheShortWay) {
  ASSERT_EQ(model_.joints()[0].type, phri::JointType::kContinuous);
  phri::ReturnLeash leash(model_, frame_, {.length_rad = 0.2, .return_speed_rad_s = 0.5});
  Eigen::VectorXd v = Eigen::VectorXd::Zero(7);
  v[0] = 1.0;
  const Eigen::VectorXd q = carry(leash, v, 4.0);  // joint 1 carried 4 rad: 2.28 rad the other way
  const double short_way = std::remainder(q[0] - target_[0], 2.0 * std::numbers::pi);
  ASSERT_LT(short_way, 0.0);
  EXPECT_NEAR(leash.offset()[0], short_way - 0.2, 2e-3);  // trailing the joint, on the short side
  // The walk back goes the short way: the offset's size only shrinks.
  double size = std::abs(leash.offset()[0]);
  for (int k = 0; k < 6000 && leash.out(); ++k) {
    leash.update(model_, q, zero_, target_, zero_, true, dt_);
    EXPECT_LE(std::abs(leash.offset()[0]), size + 1e-12);
    size = std::abs(leash.offset()[0]);
  }
  EXPECT_FALSE(leash.out());
}

TEST_F(ReturnLeashTest, OffWhenNotDraggingAndNothingAllocated) {
  phri::ReturnLeash leash(model_, frame_, {});
  Eigen::VectorXd q = target_;
  q[3] += 1.0;  // far, but dragging is off (not in full-body compliance)
  leash.update(model_, q, Eigen::VectorXd::Constant(7, 1.0), target_, zero_, false, dt_);
  EXPECT_FALSE(leash.out());
  const Eigen::VectorXd v = Eigen::VectorXd::Constant(7, 0.5);
  q = target_;
  const phri::test::AllocationCounter counter;
  for (int k = 0; k < 1500; ++k) {
    q += v * dt_;
    leash.update(model_, q, v, target_, zero_, true, dt_);
  }
  for (int k = 0; k < 200; ++k) leash.update(model_, q, zero_, target_, zero_, true, dt_);
  EXPECT_TRUE(leash.out());
  EXPECT_EQ(counter.allocations(), 0u);
}

TEST_F(ReturnLeashTest, RejectsNonsenseSettings) {
  EXPECT_THROW(phri::ReturnLeash(model_, frame_, {.length_rad = 0.0}), phri::ConfigError);
  EXPECT_THROW(phri::ReturnLeash(model_, frame_, {.return_speed_rad_s = -1.0}), phri::ConfigError);
  EXPECT_THROW(phri::ReturnLeash(model_, frame_, {.return_speed_rad_s = std::nan("")}), phri::ConfigError);
}

// The end effector's stiction term: integrates K_I e while the end effector is still and near a
// held target, clamped; bleeds with 0.1 s when it moves; restarts at a crossing or a new target.
TEST_F(ReturnLeashTest, EndEffectorStictionTermIntegratesClampsBleedsAndRestarts) {
  phri::Data data(model_);
  phri::compute_all_terms(model_, data, target_, zero_);
  phri::EndEffectorTask task(model_, frame_);
  task.reset_gains(phri::Vector6d::Constant(30.0), phri::Vector6d::Constant(11.0), 1e4, phri::Vector6d::Zero());
  task.set_integral({.gain = 200.0, .linear_limit = 10.0, .angular_limit = 40.0, .linear_zone = 0.05,
                     .angular_zone = 0.3});
  task.hold_current_pose(data);
  Eigen::Isometry3d held = data.frame_placements[static_cast<std::size_t>(frame_)];
  held.translation().x() += 0.02;  // 2 cm ahead in x, inside the zone
  task.set_target(held);
  const Eigen::VectorXd none = Eigen::VectorXd::Zero(7);
  int k = 0;
  for (; !task.target_reached() && k < 5000; ++k) {  // the governor moves the target there first
    task.update(model_, data, none, dt_);
    if (!task.target_reached()) {
      ASSERT_TRUE(task.integral_term().isZero(0.0)) << k;
    }
  }
  for (k = 1; k < 1000; ++k) task.update(model_, data, none, dt_);
  // The arm does not move: e_x = 0.02 m for 1 s, K_I e t = 200 * 0.02 * 1 = 4 m/s^2.
  EXPECT_NEAR(task.integral_term()[0], 200.0 * 0.02 * 1.0, 200.0 * 0.02 * dt_ + 1e-9);
  EXPECT_NEAR(task.reference()[0] - task.integral_term()[0] + frame_bias_x(data), 30.0 * 0.02, 1e-9);
  for (k = 0; k < 3000; ++k) task.update(model_, data, none, dt_);
  EXPECT_DOUBLE_EQ(task.integral_term()[0], 10.0);  // clamped
  // Moving faster than 0.02 m/s: bleeds off with 0.1 s.
  Eigen::VectorXd qd = Eigen::VectorXd::Zero(7);
  qd[1] = 0.2;
  phri::compute_all_terms(model_, data, target_, qd);
  for (int k = 0; k < 100; ++k) task.update(model_, data, none, dt_);
  EXPECT_NEAR(task.integral_term()[0], 10.0 * std::exp(-0.1 / 0.1), 1e-6);
  // A new target restarts it.
  phri::compute_all_terms(model_, data, target_, zero_);
  held.translation().x() -= 0.04;
  task.set_target(held);
  EXPECT_TRUE(task.integral_term().isZero(0.0));
  // Off while an offset moves the target (the leash walks back).
  Eigen::Isometry3d offset = Eigen::Isometry3d::Identity();
  offset.translation().z() = 0.01;
  task.set_target_offset(offset);
  for (int k = 0; k < 500; ++k) task.update(model_, data, none, dt_);
  EXPECT_TRUE(task.integral_term().isZero(0.0));
  EXPECT_NEAR(task.error()[2], 0.01, 1e-12);  // the offset is what the task tracks
}

}  // namespace
