// ctest-labels: unit
// The QP's constraint objects against closed forms: the second-order velocity damper's gain and
// its overdamped approach (the damped oscillator's analytic solution), the joint-limit and
// velocity-limit bounds at their edges, the torque rows against tau = M qdd + h - tau_ext, and the
// self-collision rows' activation at the influence distance.
#include <phri/control/joint_limit_constraint.hpp>
#include <phri/control/self_collision_constraint.hpp>
#include <phri/control/torque_limit_constraint.hpp>
#include <phri/control/velocity_damper.hpp>
#include <phri/control/velocity_limit_constraint.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/qp/qp_solver.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <random>

namespace {

const std::string kGen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";

TEST(VelocityDamper, GainIsTheFormulaOfThePaperForItsDemoValues) {
  // Paper: d_i 0.03 m, d_s 0.015 m, M 1.8, xi 0.08 m/s: lambda = 4 M^2 xi / (d_i - d_s) = 69.12.
  const phri::VelocityDamper damper({0.03, 0.015, 0.08, 1.8});
  EXPECT_NEAR(damper.lambda(), 4.0 * 3.24 * 0.08 / 0.015, 1e-12);
  EXPECT_NEAR(damper.lambda(), 69.12, 1e-9);
  EXPECT_NEAR(damper.stiffness(), 69.12 * 69.12 / (4.0 * 3.24), 1e-9);
  // At the safety distance and at rest the damper allows no approach: ë >= 0.
  EXPECT_DOUBLE_EQ(damper.min_acceleration(0.015, 0.0), 0.0);
  // Moving away from the limit faster than the damper's pull: negative ë allowed.
  EXPECT_LT(damper.min_acceleration(0.02, 0.5), 0.0);
}

TEST(VelocityDamper, RidingTheBoundIsTheOverdampedOscillatorAndNeverCrossesTheSafetyDistance) {
  // ë = -k (e - d_s) - lambda ė, started at d_i approaching at xi. With x = e - d_s the solution is
  // x(t) = A exp(r1 t) + B exp(r2 t), r1,2 = lambda (-1 +- sqrt(1 - 1/M^2)) / 2.
  const double di = 0.1, ds = 0.02, xi = 0.5, m = 1.8;
  const phri::VelocityDamper damper({di, ds, xi, m});
  const double lambda = damper.lambda();
  const double root = std::sqrt(1.0 - 1.0 / (m * m));
  const double r1 = 0.5 * lambda * (-1.0 + root), r2 = 0.5 * lambda * (-1.0 - root);
  const double x0 = di - ds, v0 = -xi;
  const double b = (v0 - r1 * x0) / (r2 - r1), a = x0 - b;
  double e = di, e_dot = -xi, min_e = e;
  const double dt = 1e-6;
  for (int k = 1; k <= 200000; ++k) {  // 0.2 s, semi-implicit Euler at 1 us
    e_dot += dt * damper.min_acceleration(e, e_dot);
    e += dt * e_dot;
    min_e = std::min(min_e, e);
    if (k % 20000 == 0) {
      const double t = k * dt;
      EXPECT_NEAR(e - ds, a * std::exp(r1 * t) + b * std::exp(r2 * t), 2e-5) << "t = " << t;
    }
  }
  EXPECT_GT(min_e, ds);
}

class ConstraintTest : public ::testing::Test {
protected:
  phri::Model model_ = phri::Model::from_urdf_file(kGen3 + "gen3.urdf");
  phri::Data data_{model_};
};

TEST_F(ConstraintTest, JointLimitBoundsStopAJointAtRestAtItsSafetyDistanceAndPushBackBeyond) {
  const Eigen::VectorXd v = Eigen::VectorXd::Constant(7, 1.0);
  const phri::JointLimitConstraint limits(model_, {0.1, 0.01, 1.8}, v);
  const int j = 1;  // joint 2: limited
  ASSERT_TRUE(limits.limited(j));
  ASSERT_FALSE(limits.limited(0));  // joint 1: continuous
  const double range = model_.upper_limits()[j] - model_.lower_limits()[j];
  EXPECT_NEAR(limits.safe_upper()[j], model_.upper_limits()[j] - 0.01 * range, 1e-12);
  EXPECT_NEAR(limits.safe_lower()[j], model_.lower_limits()[j] + 0.01 * range, 1e-12);
  const double inf = std::numeric_limits<double>::infinity();
  Eigen::VectorXd q = Eigen::VectorXd::Zero(7), qd = Eigen::VectorXd::Zero(7);
  Eigen::VectorXd lower = Eigen::VectorXd::Constant(7, -inf), upper = Eigen::VectorXd::Constant(7, inf);
  q[j] = limits.safe_upper()[j];
  limits.tighten(q, qd, lower, upper);
  EXPECT_NEAR(upper[j], 0.0, 1e-9);      // at rest on the safety bound: no acceleration toward the limit
  EXPECT_EQ(upper[0], inf);              // continuous joint untouched
  q[j] = model_.upper_limits()[j];       // beyond the safety bound
  lower.setConstant(-inf);
  upper.setConstant(inf);
  limits.tighten(q, qd, lower, upper);
  EXPECT_LT(upper[j], 0.0);              // must accelerate back
  // Mirror image at the lower limit.
  q[j] = limits.safe_lower()[j];
  lower.setConstant(-inf);
  upper.setConstant(inf);
  limits.tighten(q, qd, lower, upper);
  EXPECT_NEAR(lower[j], 0.0, 1e-9);
}

TEST_F(ConstraintTest, VelocityLimitBoundsVanishAtTheLimitAndConvergeAtTheirGain) {
  const Eigen::VectorXd v = Eigen::VectorXd::Constant(7, 1.2), gain = Eigen::VectorXd::Constant(7, 50.0);
  const phri::VelocityLimitConstraint limit(v, gain);
  Eigen::VectorXd qd = v, lower(7), upper(7);
  limit.bound(qd, lower, upper);
  EXPECT_NEAR(upper.cwiseAbs().maxCoeff(), 0.0, 1e-12);
  EXPECT_NEAR(lower[0], -50.0 * 2.4, 1e-12);
  // Riding the upper bound from 2 v_max: qd - v decays as exp(-gain t).
  double speed = 2.4;
  const double dt = 1e-5;
  for (int k = 0; k < 10000; ++k) {
    qd.setConstant(speed);
    limit.bound(qd, lower, upper);
    speed += dt * upper[0];
  }
  EXPECT_NEAR(speed - 1.2, 1.2 * std::exp(-50.0 * 0.1), 1e-4);
}

// Return gain (VelocityLimitConstraint::deceleration), against its closed form: below the limit the
// paper's bound; beyond it return_gain x the excess, but never more deceleration than the
// direction's reserve gives (reserve / M_ii), nor less than the paper's gain asks.
TEST_F(ConstraintTest, BeyondTheLimitTheBoundReturnsAtItsGainWithinTheReserve) {
  const Eigen::VectorXd v = Eigen::VectorXd::Constant(7, 2.0), gain = Eigen::VectorXd::Constant(7, 50.0);
  const Eigen::VectorXd tau_max = Eigen::VectorXd::Constant(7, 100.0), inertia = Eigen::VectorXd::Constant(7, 0.5);
  phri::VelocityLimitConstraint paper(v, gain, {0.3, 0.5, 0.0});
  phri::VelocityLimitConstraint limit(v, gain, {0.3, 0.5, 200.0});
  Eigen::VectorXd lower(7), upper(7), paper_lower(7), paper_upper(7);
  Eigen::VectorXd qd = Eigen::VectorXd::LinSpaced(7, -1.9, 1.9), hold = Eigen::VectorXd::Zero(7);
  // Within the limits: identical.
  limit.bound(qd, hold, tau_max, inertia, lower, upper);
  paper.bound(qd, hold, tau_max, inertia, paper_lower, paper_upper);
  EXPECT_EQ(lower, paper_lower);
  EXPECT_EQ(upper, paper_upper);
  EXPECT_FALSE(limit.returning());
  // 0.3 rad/s beyond +2 with the whole reserve (100 N.m, 200 rad/s^2 on 0.5 kg.m^2): 200 x 0.3 = 60
  // rad/s^2, four times the paper's 15. Mirror image below -2.
  qd.setConstant(2.3);
  limit.bound(qd, hold, tau_max, inertia, lower, upper);
  paper.bound(qd, hold, tau_max, inertia, paper_lower, paper_upper);
  EXPECT_NEAR(paper_upper[0], -15.0, 1e-9);
  EXPECT_NEAR(upper[0], -60.0, 1e-9);
  EXPECT_TRUE(limit.returning());
  // Without it (WholeBodyQp's second solve when the QP is infeasible with it): the paper's bound.
  limit.bound(qd, hold, tau_max, inertia, lower, upper, false);
  EXPECT_EQ(upper, paper_upper);
  EXPECT_FALSE(limit.returning());
  qd.setConstant(-2.3);
  limit.bound(qd, hold, tau_max, inertia, lower, upper);
  EXPECT_NEAR(lower[0], 60.0, 1e-9);
  // A push holding -75 N.m leaves 25 N.m to brake a + motion (50 rad/s^2) and lowers the + limit
  // to 25 / 30 of 2: 1.667 rad/s, 0.633 below 2.3. The paper's gain asks 31.7 rad/s^2, the return
  // gain 126.7: the reserve's 50 is asked.
  qd.setConstant(2.3);
  hold.setConstant(-75.0);
  limit.bound(qd, hold, tau_max, inertia, lower, upper);
  paper.bound(qd, hold, tau_max, inertia, paper_lower, paper_upper);
  EXPECT_NEAR(paper_upper[0], -50.0 * (2.3 - 2.0 * 25.0 / 30.0), 1e-9);
  EXPECT_NEAR(upper[0], -50.0, 1e-9);
  // No reserve left: the paper's bound alone (which asks nothing the torque cannot give).
  hold.setConstant(-100.0);
  limit.bound(qd, hold, tau_max, inertia, lower, upper);
  paper.bound(qd, hold, tau_max, inertia, paper_lower, paper_upper);
  EXPECT_EQ(upper[0], paper_upper[0]);
  // Riding the bound from 2.6 rad/s with the whole reserve: the excess decays as exp(-200 t).
  hold.setZero();
  double speed = 2.6;
  const double dt = 1e-5;
  for (int k = 0; k < 1000; ++k) {
    qd.setConstant(speed);
    limit.bound(qd, hold, tau_max, inertia, lower, upper);
    speed += dt * upper[0];
  }
  EXPECT_NEAR(speed - 2.0, 0.6 * std::exp(-200.0 * 0.01), 1e-3);
}

// Release bound (velocity_limit_constraint.hpp), against its closed form: on the side the release
// acceleration a_r points to, qdd <= (v - qd) / h - a_r (mirrored below) where that is tighter than the
// damper; the other side, a zero a_r and a joint moving away from that side (the braking a push needs)
// keep the paper's bounds; relax() drops it for the cycle; no a_r (null, wrong size, not finite): none.
TEST_F(ConstraintTest, AReleaseBoundKeepsTheSpeedALetGoWouldReachWithinTheLimit) {
  const Eigen::VectorXd v = Eigen::VectorXd::Constant(7, 3.0), gain = Eigen::VectorXd::Constant(7, 50.0);
  const phri::VelocityLimitConstraint paper(v, gain);
  phri::VelocityLimitConstraint limit(v, gain, {0.0, 0.5, 0.0});  // no reserve, no return gain: the bound alone
  const Eigen::VectorXd tau_ext = Eigen::VectorXd::Zero(7), tau_max = Eigen::VectorXd::Constant(7, 100.0);
  const Eigen::VectorXd inertia = Eigen::VectorXd::Constant(7, 0.5);
  Eigen::VectorXd qd(7), hold = Eigen::VectorXd::Zero(7);
  qd << 2.8, -2.8, 2.9, -1.0, 0.0, 2.95, -2.99;  // rad/s, against 3.0
  const Eigen::VectorXd q = Eigen::VectorXd::Zero(7);
  const phri::ConstraintContext context{model_, data_, q, qd, tau_ext, hold, tau_max, inertia};
  Eigen::VectorXd release(7);
  release << 300.0, -300.0, 0.0, 1000.0, -1000.0, -400.0, 200.0;  // rad/s^2
  const double horizon = 2e-3;
  Eigen::VectorXd lower = Eigen::VectorXd::Constant(7, -1e9), upper = Eigen::VectorXd::Constant(7, 1e9);
  Eigen::VectorXd paper_lower(7), paper_upper(7);
  paper.bound(qd, paper_lower, paper_upper);
  limit.set_release(&release, horizon);
  limit.begin_cycle();
  limit.bound(context, lower, upper);
  for (int i = 0; i < 7; ++i) {
    const double up = release[i] > 0.0 ? std::min(paper_upper[i], (3.0 - qd[i]) / horizon - release[i]) : paper_upper[i];
    const double down = release[i] < 0.0 ? std::max(paper_lower[i], (-3.0 - qd[i]) / horizon - release[i]) : paper_lower[i];
    EXPECT_DOUBLE_EQ(upper[i], up) << i;
    EXPECT_DOUBLE_EQ(lower[i], down) << i;
  }
  // Near the limit on a_r's side it binds: joint 1 at 2.8 rad/s keeps 0.2 / 2 ms - 300 = -200 rad/s^2
  // (the damper allows +10), joint 2 mirrored; joint 4 (moving away, 4 rad/s from its + limit) and
  // joint 5 (at rest, 3 rad/s from each) keep the damper's bounds although their a_r is 1000.
  EXPECT_DOUBLE_EQ(upper[0], -200.0);
  EXPECT_DOUBLE_EQ(lower[1], 200.0);
  EXPECT_EQ(upper[3], paper_upper[3]);
  EXPECT_EQ(lower[4], paper_lower[4]);
  EXPECT_EQ(upper[4], paper_upper[4]);
  // Relaxed (the QP infeasible with it): the paper's bounds.
  ASSERT_TRUE(limit.relax());
  lower.setConstant(-1e9);
  upper.setConstant(1e9);
  limit.bound(context, lower, upper);
  EXPECT_EQ(lower, paper_lower);
  EXPECT_EQ(upper, paper_upper);
  // None given: none, and nothing for relax() to drop.
  Eigen::VectorXd not_finite = release;
  not_finite[2] = std::numeric_limits<double>::quiet_NaN();
  const Eigen::VectorXd short_release = release.head(6);
  const Eigen::VectorXd* no_release[] = {nullptr, &not_finite, &short_release};
  for (const Eigen::VectorXd* none : no_release) {
    limit.set_release(none, horizon);
    limit.begin_cycle();
    lower.setConstant(-1e9);
    upper.setConstant(1e9);
    limit.bound(context, lower, upper);
    EXPECT_EQ(lower, paper_lower);
    EXPECT_EQ(upper, paper_upper);
    EXPECT_FALSE(limit.relax()) << "nothing to drop";
  }
}

// Braking reserve (velocity_limit_constraint.hpp), against its closed form: full limit from
// reserve_fraction x tau_max of reserve, linear below, min_speed_fraction at none; a joint faster
// than its lowered limit is asked exactly the deceleration its reserve gives.
TEST_F(ConstraintTest, BrakingReserveLowersTheLimitTowardAPushThatTakesTheTorque) {
  const Eigen::VectorXd v = Eigen::VectorXd::Constant(7, 2.0), gain = Eigen::VectorXd::Constant(7, 80.0);
  const Eigen::VectorXd tau_max = Eigen::VectorXd::Constant(7, 100.0), inertia = Eigen::VectorXd::Constant(7, 0.5);
  const phri::VelocityLimitConstraint plain(v, gain);
  phri::VelocityLimitConstraint limit(v, gain, {0.3, 0.5, 0.0});
  Eigen::VectorXd qd = Eigen::VectorXd::LinSpaced(7, -1.5, 1.5), hold = Eigen::VectorXd::Zero(7);
  Eigen::VectorXd lower(7), upper(7), plain_lower(7), plain_upper(7);
  // Plenty of reserve both ways (|hold| <= 70 % of tau_max): the paper's bounds, bit for bit.
  hold << -70.0, -40.0, -10.0, 0.0, 10.0, 40.0, 70.0;
  limit.bound(qd, hold, tau_max, inertia, lower, upper);
  plain.bound(qd, plain_lower, plain_upper);
  EXPECT_EQ(lower, plain_lower);
  EXPECT_EQ(upper, plain_upper);
  // Moving toward + brakes with tau >= -tau_max: reserve tau_max + hold. hold -76 leaves 24 N.m,
  // 0.8 of the 30 N.m from which the full limit holds: the + limit is 1.6 rad/s; the - one keeps 2.
  qd.setZero();
  hold.setConstant(-76.0);
  limit.bound(qd, hold, tau_max, inertia, lower, upper);
  EXPECT_NEAR(upper[0], 80.0 * 1.6, 1e-9);
  EXPECT_NEAR(lower[0], -80.0 * 2.0, 1e-9);
  // No reserve (or less than none: a push beyond the drive): min_speed_fraction x v.
  for (double h : {-100.0, -130.0, -95.5}) {
    hold.setConstant(h);
    limit.bound(qd, hold, tau_max, inertia, lower, upper);
    EXPECT_NEAR(upper[0], 80.0 * 1.0, 1e-9) << h;
  }
  // Already at 1.8 rad/s with 6 N.m of reserve (hold -94): lowered limit 0.5 x 2 = 1 rad/s, but the
  // bound asks only what 6 N.m decelerates the joint's 0.5 kg.m^2 at: qdd <= -12 rad/s^2.
  qd.setConstant(1.8);
  hold.setConstant(-94.0);
  limit.bound(qd, hold, tau_max, inertia, lower, upper);
  EXPECT_NEAR(upper[0], -6.0 / 0.5, 1e-9);
  // ... and with no reserve at all it asks for no acceleration along the motion, not a deceleration
  // the torque limits forbid (the QP would go infeasible); with 5 N.m less than none it lets
  // through the 10 rad/s^2 the torque limit cannot stop.
  hold.setConstant(-100.0);
  limit.bound(qd, hold, tau_max, inertia, lower, upper);
  EXPECT_NEAR(upper[0], 0.0, 1e-9);
  hold.setConstant(-105.0);
  limit.bound(qd, hold, tau_max, inertia, lower, upper);
  EXPECT_NEAR(upper[0], 5.0 / 0.5, 1e-9);
  // Mirror image toward -: reserve tau_max - hold.
  qd.setConstant(-1.8);
  hold.setConstant(94.0);
  limit.bound(qd, hold, tau_max, inertia, lower, upper);
  EXPECT_NEAR(lower[0], 6.0 / 0.5, 1e-9);
  EXPECT_NEAR(upper[0], -80.0 * (-1.8 - 2.0), 1e-9);  // + keeps its full limit (reserve 194 N.m)
}

TEST_F(ConstraintTest, TorqueRowsHoldExactlyTheTorquesWithinTheLimits) {
  Eigen::VectorXd q(7), qd(7);
  q << 0.3, 0.58, 3.14, -1.84, 0.2, 0.85, 1.57;
  qd << 0.1, -0.2, 0.3, 0.1, -0.2, 0.1, 0.3;
  phri::compute_all_terms(model_, data_, q, qd);
  const Eigen::VectorXd limit = Eigen::VectorXd::Constant(7, 30.0);
  const phri::TorqueLimitConstraint torque(limit);
  Eigen::MatrixXd a(7, 7);
  Eigen::VectorXd l(7), u(7);
  Eigen::VectorXd tau_ext = Eigen::VectorXd::LinSpaced(7, -3.0, 3.0);
  torque.rows(data_, tau_ext, a, l, u);
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> uniform(-60.0, 60.0);
  for (int trial = 0; trial < 200; ++trial) {
    Eigen::VectorXd qdd(7);
    for (int i = 0; i < 7; ++i) qdd[i] = uniform(rng);
    // Independent: inverse dynamics by RNEA.
    const Eigen::VectorXd tau = phri::rnea(model_, data_, q, qd, qdd) - tau_ext;
    const Eigen::VectorXd row = a * qdd;
    for (int i = 0; i < 7; ++i) {
      const bool inside_rows = row[i] >= l[i] && row[i] <= u[i];
      const bool inside_limit = std::abs(tau[i]) <= 30.0;
      if (std::abs(std::abs(tau[i]) - 30.0) > 1e-9) {
        EXPECT_EQ(inside_rows, inside_limit) << "joint " << i;
      }
    }
  }
}

TEST_F(ConstraintTest, SelfCollisionRowsActOnlyInsideTheInfluenceDistance) {
  const phri::CollisionModel collision = phri::CollisionModel::from_yaml_file(kGen3 + "collision.yaml", model_);
  Eigen::VectorXd q(7), qd = Eigen::VectorXd::Constant(7, 0.2);
  q << 0, 0.58, 3.14, -1.84, 0, 0.85, 1.57;
  phri::compute_all_terms(model_, data_, q, qd);
  // An influence distance beyond every pair's distance, then one below every pair's distance.
  for (const double influence : {10.0, 1e-4}) {
    phri::SelfCollisionConstraint constraint(model_, collision, {influence, 0.5e-4, 0.08, 1.8});
    const int n = constraint.num_rows();
    ASSERT_GT(n, 0);
    Eigen::MatrixXd a(n, 7);
    Eigen::VectorXd l(n), u(n);
    constraint.rows(model_, data_, a, l, u);
    const phri::VelocityDamper damper({influence, 0.5e-4, 0.08, 1.8});
    for (int p = 0; p < n; ++p) {
      EXPECT_EQ(u[p], std::numeric_limits<double>::infinity());
      const double d = constraint.data().distance[p];
      if (d < influence) {
        EXPECT_DOUBLE_EQ(l[p], damper.min_acceleration(d, constraint.data().velocity[p]) - constraint.data().jdot_qdot[p]);
      } else {
        EXPECT_EQ(l[p], -std::numeric_limits<double>::infinity());
      }
      EXPECT_TRUE(a.row(p).isApprox(constraint.data().jacobian.row(p)));
    }
  }
}

// The broad phase (self_collision_constraint.hpp): a pair that bounds nothing gets no Jacobian.
// Against the full computation of every pair (compute_collision_distances with derivatives), on
// 2000 random states where pairs are near and far, fast and slow: each pair the constraint keeps has
// bit-identical row and bound, each pair it skips would have had l = -inf, and a QP over the rows
// gives the same solution, to the bit.
TEST_F(ConstraintTest, SelfCollisionBroadPhaseSkipsOnlyPairsThatBoundNothingAndLeavesTheQpUnchanged) {
  const phri::CollisionModel collision = phri::CollisionModel::from_yaml_file(kGen3 + "collision.yaml", model_);
  const phri::VelocityDamperSettings damper_settings{0.03, 0.015, 0.08, 1.8};
  const phri::CollisionBrakingSettings braking{3.0, 50.0};
  const phri::VelocityDamper damper(damper_settings);
  std::mt19937 rng(20261128);
  std::uniform_real_distribution<double> joint(-2.5, 2.5), speed(-2.0, 2.0);
  const int n = collision.num_pairs();
  int skipped = 0, kept = 0, far = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    Eigen::VectorXd q(7), qd(7);
    for (int i = 0; i < 7; ++i) {
      q[i] = joint(rng);
      qd[i] = speed(rng);
    }
    phri::compute_all_terms(model_, data_, q, qd);
    phri::SelfCollisionConstraint constraint(model_, collision, damper_settings, braking);
    Eigen::MatrixXd a(n, 7);
    Eigen::VectorXd l(n), u(n);
    constraint.rows(model_, data_, a, l, u);
    phri::CollisionData full(model_, collision);
    phri::compute_collision_distances(model_, data_, collision, full, true);
    Eigen::MatrixXd a_full(n, 7);
    Eigen::VectorXd l_full(n);
    for (int p = 0; p < n; ++p) {
      const double d = full.distance[p], d_dot = full.velocity[p];
      // The bounding spheres' bounds hold; a pair they show to be far keeps its lower bound.
      const phri::CollisionData& got = constraint.data();
      ASSERT_LE(got.distance_lower_bound[p], d + 1e-12);
      ASSERT_LE(-d_dot, got.approach_speed_bound[p] + 1e-12);
      if (got.distance[p] == got.distance_lower_bound[p] && got.distance[p] != d) {
        ++far;
        ASSERT_GE(got.distance[p], 0.03);
        ASSERT_EQ(got.velocity[p], 0.0);
      } else {
        ASSERT_EQ(got.distance[p], d);
        ASSERT_EQ(got.velocity[p], d_dot);
      }
      const double lower = d < 0.03 ? damper.min_acceleration(d, d_dot) : -std::numeric_limits<double>::infinity();
      l_full[p] = std::max(lower, phri::collision_braking_bound(d, d_dot, 0.015, braking)) - full.jdot_qdot[p];
      a_full.row(p) = full.jacobian.row(p);
      if (a.row(p).isZero(0.0) && !full.jacobian.row(p).isZero(0.0)) {
        ++skipped;
        EXPECT_EQ(l[p], -std::numeric_limits<double>::infinity());
        EXPECT_EQ(l_full[p], -std::numeric_limits<double>::infinity());
      } else {
        ++kept;
        EXPECT_EQ(l[p], l_full[p]);
        EXPECT_TRUE(a.row(p) == a_full.row(p));
      }
    }
    // The same QP either way: min |qdd - qdd_ref|^2 over the rows.
    phri::QpProblem problem;
    problem.resize(7, 0, n);
    problem.H.setIdentity();
    problem.g = -Eigen::VectorXd::LinSpaced(7, -30.0, 30.0);
    problem.l = l;
    problem.u = u;
    problem.A = a;
    phri::QpSolver solver;
    solver.resize(7, 0, n);
    const phri::QpStatus broad = solver.solve(problem);
    const Eigen::VectorXd x_broad = solver.x();
    problem.A = a_full;
    problem.l = l_full;
    const phri::QpStatus reference = solver.solve(problem);
    ASSERT_EQ(broad, reference);
    if (reference == phri::QpStatus::kOptimal) {
      EXPECT_TRUE(x_broad == solver.x()) << "trial " << trial;
    }
  }
  std::printf("broad phase over 2000 random states: %d pair rows kept, %d skipped (%d without closest points)\n", kept,
              skipped, far);
  EXPECT_GT(skipped, 0);
  EXPECT_GT(kept, 0);
  EXPECT_GT(far, 0);
}

// The braking row ahead of the collision damper (self_collision_constraint.hpp) on a distance
// riding its bound: from 1.5 m/s at 0.5 m it stops before d_s, decelerating no harder than about
// the set deceleration (a pure v^2 = 2 a (d - d_s) profile asks exactly a), and a slow approach
// never meets it; what the paper's damper alone asks at d_i from that speed is far beyond.
TEST_F(ConstraintTest, CollisionBrakingStopsAFastApproachBeforeTheSafetyDistance) {
  const phri::CollisionBrakingSettings braking{3.0, 50.0};
  const double d_s = 0.015, dt = 1e-4;
  double d = 0.5, d_dot = -1.5, hardest = 0.0, closest = d;
  for (int k = 0; k < 200000; ++k) {
    const double bound = phri::collision_braking_bound(d, d_dot, d_s, braking);
    const double d_ddot = std::isfinite(bound) ? std::max(bound, 0.0) : 0.0;  // coasting unless bounded
    hardest = std::max(hardest, d_ddot);
    d_dot += dt * d_ddot;
    d += dt * d_dot;
    closest = std::min(closest, d);
  }
  EXPECT_GT(closest, 0.99 * d_s);
  EXPECT_LT(closest, d_s + 0.005);               // it does come near: the row only brakes
  EXPECT_LT(hardest, 2.0 * braking.deceleration);  // the profile's a, plus the gain's lag
  EXPECT_GT(hardest, 0.8 * braking.deceleration);
  // Slow approaches (below half the braking profile's speed) and separating pairs: no row.
  EXPECT_EQ(phri::collision_braking_bound(0.1, -0.3, d_s, braking), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(phri::collision_braking_bound(0.02, 0.5, d_s, braking), -std::numeric_limits<double>::infinity());
  EXPECT_EQ(phri::collision_braking_bound(0.1, -1.0, d_s, {0.0, 50.0}), -std::numeric_limits<double>::infinity());
  // Inside d_s it asks to stop approaching at the gain: -gain x d_dot; near it, the linear end.
  EXPECT_DOUBLE_EQ(phri::collision_braking_bound(0.01, -0.2, d_s, braking), 50.0 * 0.2);
  EXPECT_DOUBLE_EQ(phri::collision_braking_bound(d_s + 0.01, -0.2, d_s, braking), -50.0 * (-0.2 + 10.0 * 0.01));
  // The paper's damper at d_i from 1.5 m/s asks some 100 m/s^2.
  const phri::VelocityDamper damper({0.03, d_s, 0.08, 1.8});
  EXPECT_GT(damper.min_acceleration(0.03, -1.5), 90.0);
}

// The broad phase's decision without the square root (collision_braking_left_out) is the braking
// bound's own, on random states and on approaches within a few ulp of the square-root end, the
// linear end, zero, and non-finite inputs and settings.
TEST(CollisionBraking, TheLeftOutTestAgreesWithTheBoundEverywhere) {
  constexpr double kInf = std::numeric_limits<double>::infinity();
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double d_s = 0.015;
  std::mt19937_64 rng(44);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  long checked = 0, boundary = 0;
  const auto agree = [&](double d, double d_dot, const phri::CollisionBrakingSettings& b) {
    const bool left_out = phri::collision_braking_bound(d, d_dot, d_s, b) == -kInf;
    EXPECT_EQ(phri::collision_braking_left_out(d, d_dot, d_s, b), left_out)
        << "d " << d << ", d_dot " << d_dot << ", a " << b.deceleration << ", gain " << b.gain;
    ++checked;
  };
  for (int k = 0; k < 20000; ++k) {
    const phri::CollisionBrakingSettings b{unit(rng) < 0.05 ? 0.0 : 0.1 + 10.0 * unit(rng), 1.0 + 100.0 * unit(rng)};
    const double d = -0.05 + 1.5 * unit(rng);
    agree(d, -3.0 + 4.0 * unit(rng), b);
    // Approaches at the two ends of the profile, stepped by ulps across each.
    const double x = std::max(d - d_s, 0.0);
    for (const double end : {0.5 * std::sqrt(2.0 * b.deceleration * x), 0.5 * (0.2 * b.gain * x)}) {
      double approach = end;
      for (int step = 0; step < 3; ++step) approach = std::nextafter(approach, -kInf);
      for (int step = 0; step < 6; ++step, approach = std::nextafter(approach, kInf)) {
        agree(d, -approach, b);
        ++boundary;
      }
    }
  }
  const phri::CollisionBrakingSettings b{3.0, 50.0};
  for (const double d : {-kInf, -1.0, 0.0, d_s, 0.1, 1e300, kInf, nan}) {
    for (const double d_dot : {-kInf, -1e300, -1.0, -1e-300, 0.0, 1.0, kInf, nan}) {
      agree(d, d_dot, b);
      agree(d, d_dot, {kInf, 50.0});
      agree(d, d_dot, {3.0, kInf});
      agree(d, d_dot, {nan, 50.0});
    }
  }
  EXPECT_GT(boundary, 200000);
  EXPECT_GT(checked, 220000);
}

}  // namespace
