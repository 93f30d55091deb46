// ctest-labels: unit
// The scenarios' reference generators (config/fsm_settings.hpp) against their definitions: the quintic's
// boundary conditions, the rounded triangle's bounds, speed and start, the dynamic trajectory's
// parameters (paper_parameters.md section 5) and the consistency of every feed-forward velocity
// and acceleration with the finite differences of the positions, the moves and brakes.
#include <phri/config/fsm_settings.hpp>
#include <phri/trajectory/joint_move.hpp>
#include <phri/trajectory/pose_move.hpp>
#include <phri/trajectory/quintic.hpp>
#include <phri/control/end_effector_task.hpp>
#include <phri/model/model.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;

TEST(Quintic, BoundaryConditionsAndPeakRate) {
  const auto a = phri::Quintic::at(0.0), b = phri::Quintic::at(1.0), m = phri::Quintic::at(0.5);
  EXPECT_DOUBLE_EQ(a.s, 0.0);
  EXPECT_DOUBLE_EQ(a.ds, 0.0);
  EXPECT_DOUBLE_EQ(a.dds, 0.0);
  EXPECT_DOUBLE_EQ(b.s, 1.0);
  EXPECT_DOUBLE_EQ(b.ds, 0.0);
  EXPECT_NEAR(b.dds, 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(m.s, 0.5);
  EXPECT_DOUBLE_EQ(m.ds, phri::Quintic::kPeakRate);
  EXPECT_DOUBLE_EQ(phri::Quintic::at(2.0).s, 1.0);  // clamped
}

TEST(SmoothTriangle, StaysWithinBoundsAtTheCruiseSpeedWithContinuousVelocity) {
  const double lo = -0.4, hi = 0.05, v = 0.1, a = 0.5;
  const phri::SmoothTriangle tri(lo, hi, v, a);
  EXPECT_NEAR(tri.period(), 2.0 * ((hi - lo) / v + v / a), 1e-12);  // 9.4 s
  double x0, v0, a0;
  tri.evaluate(0.0, x0, v0, a0);
  EXPECT_NEAR(x0, 0.0, 1e-12);
  EXPECT_NEAR(v0, -v, 1e-12);  // starts toward lo at cruise speed
  double min_x = 1.0, max_x = -1.0, max_speed = 0.0, max_dv = 0.0, worst_fd = 0.0;
  const double dt = 1e-3;
  double px = x0, pv = v0;
  for (int k = 1; k < 30000; ++k) {
    double x, vel, acc;
    tri.evaluate(k * dt, x, vel, acc);
    min_x = std::min(min_x, x);
    max_x = std::max(max_x, x);
    max_speed = std::max(max_speed, std::abs(vel));
    max_dv = std::max(max_dv, std::abs(vel - pv));
    worst_fd = std::max(worst_fd, std::abs((x - px) / dt - 0.5 * (vel + pv)));
    px = x;
    pv = vel;
  }
  EXPECT_NEAR(min_x, lo, 1e-6);
  EXPECT_NEAR(max_x, hi, 1e-6);
  EXPECT_NEAR(max_speed, v, 1e-9);
  EXPECT_LE(max_dv, a * dt + 1e-9);  // velocity changes at most by the turn acceleration
  EXPECT_LT(worst_fd, 1e-6);
}

TEST(SmoothTriangle, ShortSpanSlowsDown) {
  const phri::SmoothTriangle tri(-0.01, 0.01, 1.0, 1.0);  // span 0.02 < v^2 / a
  double max_speed = 0.0, max_x = 0.0;
  for (int k = 0; k < 5000; ++k) {
    double x, v, a;
    tri.evaluate(k * 1e-3, x, v, a);
    max_speed = std::max(max_speed, std::abs(v));
    max_x = std::max(max_x, std::abs(x));
  }
  EXPECT_LE(max_x, 0.01 + 1e-9);
  EXPECT_LE(max_speed, std::sqrt(0.02) + 1e-9);
}

// Finite differences of a pose reference against its own velocity and acceleration.
template <class Evaluate>
void check_derivatives(Evaluate&& evaluate, double t_end, double tolerance_v, double tolerance_a) {
  const double h = 1e-5;
  for (double t = h; t < t_end; t += 0.0371) {
    phri::PoseReference m, c, p;
    evaluate(t - h, m);
    evaluate(t, c);
    evaluate(t + h, p);
    const Eigen::Vector3d v_fd = (p.pose.translation() - m.pose.translation()) / (2 * h);
    const Eigen::Vector3d w_fd = phri::rotation_log(p.pose.linear() * m.pose.linear().transpose()) / (2 * h);
    const phri::Vector6d a_fd = (p.velocity - m.velocity) / (2 * h);
    ASSERT_LT((v_fd - c.velocity.head<3>()).norm(), tolerance_v) << "t " << t;
    ASSERT_LT((w_fd - c.velocity.tail<3>()).norm(), tolerance_v) << "t " << t;
    ASSERT_LT((a_fd - c.acceleration).norm(), tolerance_a) << "t " << t;
  }
}

TEST(DynamicTrajectory, PaperParametersRampInAndExactFeedForward) {
  phri::DynamicTrajectory trajectory;  // defaults: paper_parameters.md section 5
  Eigen::Isometry3d centre = Eigen::Isometry3d::Identity();
  centre.translation() << 0.75, 0.0, 0.4;
  centre.linear() = Eigen::AngleAxisd(0.3, Eigen::Vector3d(1, 2, 3).normalized()).toRotationMatrix();
  trajectory.start(centre);
  phri::PoseReference r;
  trajectory.evaluate(0.0, r);
  EXPECT_LT((r.pose.translation() - centre.translation()).norm(), 1e-12);
  EXPECT_LT(r.velocity.norm(), 1e-12);
  EXPECT_LT(r.acceleration.norm(), 1e-12);
  double z_min = 1.0, z_max = -1.0, y_min = 1.0, y_max = -1.0, max_x_dev = 0.0, max_rot = 0.0;
  for (double t = 2.0; t < 12.0; t += 1e-3) {  // after the 2 s ramp
    trajectory.evaluate(t, r);
    z_min = std::min(z_min, r.pose.translation().z());
    z_max = std::max(z_max, r.pose.translation().z());
    y_min = std::min(y_min, r.pose.translation().y());
    y_max = std::max(y_max, r.pose.translation().y());
    max_x_dev = std::max(max_x_dev, std::abs(r.pose.translation().x() - 0.75));
    max_rot = std::max(max_rot, (r.pose.linear() - centre.linear()).cwiseAbs().maxCoeff());
  }
  EXPECT_NEAR(z_max, 0.5, 1e-4);
  EXPECT_NEAR(z_min, 0.3, 1e-4);
  EXPECT_NEAR(y_min, -0.4, 1e-3);
  EXPECT_NEAR(y_max, 0.05, 1e-3);
  EXPECT_EQ(max_x_dev, 0.0);
  EXPECT_EQ(max_rot, 0.0);
  check_derivatives([&](double t, phri::PoseReference& out) { trajectory.evaluate(t, out); }, 12.0, 1e-6, 2e-4);
}

TEST(PoseMove, ReachesTheGoalWithinSpeedBounds) {
  Eigen::Isometry3d a = Eigen::Isometry3d::Identity(), b = Eigen::Isometry3d::Identity();
  a.translation() << 0.5, -0.2, 0.3;
  b.translation() << 0.7, 0.1, 0.5;
  b.linear() = Eigen::AngleAxisd(0.8, Eigen::Vector3d::UnitY()).toRotationMatrix();
  phri::PoseMove move;
  move.start(a, b, 0.1, 0.5, 1.0);
  const double distance = (b.translation() - a.translation()).norm();
  EXPECT_NEAR(move.duration(), std::max(1.875 * distance / 0.1, 1.875 * 0.8 / 0.5), 1e-9);
  phri::PoseReference r;
  double peak = 0.0, peak_w = 0.0;
  for (double t = 0; t <= move.duration(); t += 1e-3) {
    move.evaluate(t, r);
    peak = std::max(peak, r.velocity.head<3>().norm());
    peak_w = std::max(peak_w, r.velocity.tail<3>().norm());
  }
  EXPECT_LE(peak, 0.1 + 1e-9);
  EXPECT_LE(peak_w, 0.5 + 1e-9);
  move.evaluate(move.duration(), r);
  EXPECT_LT((r.pose.translation() - b.translation()).norm(), 1e-12);
  EXPECT_LT((r.pose.linear() - b.linear()).norm(), 1e-12);
  EXPECT_LT(r.velocity.norm(), 1e-12);
  check_derivatives([&](double t, phri::PoseReference& out) { move.evaluate(t, out); }, move.duration(), 1e-6, 1e-4);
}

TEST(PoseBrake, ToRestWithContinuousVelocityAndAcceleration) {
  phri::PoseReference from;
  from.pose.translation() << 0.6, 0.0, 0.4;
  from.velocity << 0.3, -0.4, 0.0, 0.0, 0.0, 1.0;      // 0.5 m/s, 1 rad/s about z
  from.acceleration << 0.0, 0.0, -0.9, 0.0, 0.0, 0.5;  // e.g. the top of the sine
  phri::BrakeSettings settings;  // 1 m/s^2, 2 rad/s^2, at least 0.2 s
  phri::PoseBrake brake;
  brake.start(from, settings);
  EXPECT_NEAR(brake.duration(), 1.5 * 0.5 / 1.0, 1e-12);
  phri::PoseReference r;
  brake.evaluate(0.0, r);
  EXPECT_LT((r.pose.translation() - from.pose.translation()).norm(), 1e-15);
  EXPECT_LT((r.velocity - from.velocity).norm(), 1e-12);          // no velocity step
  EXPECT_LT((r.acceleration - from.acceleration).norm(), 1e-12);  // no acceleration step either
  double peak = 0.0;
  for (double t = 0.0; t < brake.duration(); t += 1e-3) {
    brake.evaluate(t, r);
    peak = std::max(peak, r.acceleration.head<3>().norm());
  }
  EXPECT_LE(peak, 1.0 + 0.25 * 0.9 + 0.9);  // the velocity term's bound plus the fading a0
  brake.evaluate(brake.duration() - 1e-9, r);
  EXPECT_LT(r.velocity.norm(), 1e-6);
  EXPECT_LT(r.acceleration.norm(), 1e-6);
  brake.evaluate(5.0, r);
  EXPECT_EQ(r.velocity.norm(), 0.0);
  const double T = brake.duration();  // displacement T (v0 / 2 + T a0 / 12)
  const Eigen::Vector3d expected = T * (0.5 * from.velocity.head<3>() + T / 12.0 * from.acceleration.head<3>());
  EXPECT_LT((r.pose.translation() - from.pose.translation() - expected).norm(), 1e-12);
  check_derivatives([&](double t, phri::PoseReference& out) { brake.evaluate(t, out); }, T - 1e-3, 1e-6, 1e-4);
  // At rest already: the minimum duration, and it stays put.
  phri::PoseReference still;
  brake.start(still, settings);
  EXPECT_DOUBLE_EQ(brake.duration(), 0.2);
  brake.evaluate(0.1, r);
  EXPECT_LT(r.pose.translation().norm(), 1e-15);
}

TEST(JointMoveAndBrake, ShortWayRoundAndRest) {
  const phri::Model model = phri::Model::from_urdf_file(kRoot + "/robots/kinova_gen3/gen3.urdf");
  phri::JointMove move(model);
  Eigen::VectorXd from(7), to(7), q(7), qd(7), qdd(7);
  from << 0.0, 0.262, 3.14, -2.269, 0.0, 0.96, 1.57;
  to << 0.0, 0.58, 3.14 - 2 * std::numbers::pi, -1.84, 0.0, 0.85, 1.57;  // joint 3 continuous: same angle
  move.start(from, to, 0.3, 1.0);
  EXPECT_NEAR(move.duration(), 1.875 * 0.429 / 0.3, 1e-9);
  move.evaluate(move.duration(), q, qd, qdd);
  EXPECT_NEAR(q[2], 3.14, 1e-12);  // did not unwind a full turn
  EXPECT_NEAR(q[3], -1.84, 1e-12);
  EXPECT_LT(qd.norm(), 1e-12);
  move.evaluate(0.5 * move.duration(), q, qd, qdd);
  EXPECT_NEAR(qd.cwiseAbs().maxCoeff(), 0.3, 1e-9);

  phri::JointBrake brake(7);
  qd.setZero();
  qd[1] = 0.4;
  qd[3] = -0.2;
  qdd.setZero();
  qdd[3] = 0.3;
  brake.start(from, qd, qdd, phri::BrakeSettings{});
  const double T = 1.5 * 0.4 / 1.0;
  EXPECT_NEAR(brake.duration(), T, 1e-12);
  Eigen::VectorXd q2(7), qd2(7), qdd2(7);
  brake.evaluate(0.0, q2, qd2, qdd2);
  EXPECT_LT((qd2 - qd).norm(), 1e-12);
  EXPECT_LT((qdd2 - qdd).norm(), 1e-12);
  brake.evaluate(1.0, q2, qd2, qdd2);
  EXPECT_LT(qd2.norm(), 1e-12);
  EXPECT_NEAR(q2[1] - from[1], 0.5 * T * 0.4, 1e-12);  // same time for every joint
  EXPECT_NEAR(q2[3] - from[3], T * (-0.5 * 0.2 + T / 12.0 * 0.3), 1e-12);
}

}  // namespace
