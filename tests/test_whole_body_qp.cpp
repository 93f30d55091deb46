// ctest-labels: unit
// The compliant QP against closed forms: the unconstrained optimum of the weighted least squares,
// the effect of gamma on tau_d (compliant tasks let the push through exactly, stiff ones negate it
// exactly), the dampers' bounds, torque limits, the fallback, and zero allocation per cycle.
#include <phri/control/compliance_controller.hpp>
#include <phri/control/momentum_observer.hpp>
#include <phri/control/uncancelled_push.hpp>
#include <phri/control/whole_body_qp.hpp>
#include <phri/core/error.hpp>
#include <phri/model/algorithms.hpp>

#include "allocation_counter.hpp"
#include "config_error.hpp"

#include <Eigen/QR>
#include <gtest/gtest.h>
#include <unsupported/Eigen/MatrixFunctions>

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <random>

namespace {

const std::string kGen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";

// The library names no end-effector frame (the Controller sets the robot's): the Gen3's here.
phri::WholeBodyQpSettings gen3_settings() {
  phri::WholeBodyQpSettings s;
  s.end_effector_frame = "end_effector_link";
  return s;
}

class WholeBodyQpTest : public ::testing::Test {
protected:
  void SetUp() override {
    q_ << 0, 0.58, 3.14, -1.84, 0, 0.85, 1.57;
    qd_ << 0.1, -0.2, 0.3, 0.1, -0.2, 0.1, 0.3;
    phri::compute_all_terms(model_, data_, q_, qd_);
  }
  // Far from every limit: large torque limits, gains that keep the bounds slack.
  phri::WholeBodyQpSettings loose_settings() const {
    phri::WholeBodyQpSettings s = gen3_settings();
    s.torque_limit = Eigen::VectorXd::Constant(7, 1e4);
    s.velocity_limit = Eigen::VectorXd::Constant(7, 100.0);
    return s;
  }
  void set_tasks(phri::WholeBodyQp& qp, double gamma_ee, double gamma_posture) {
    qp.end_effector().reset_gains(phri::Vector6d::Constant(100.0), phri::Vector6d::Constant(20.0), 1e3,
                                  phri::Vector6d::Constant(gamma_ee));
    Eigen::Isometry3d target = data_.frame_placements[static_cast<std::size_t>(model_.frame_id("end_effector_link"))];
    target.translation() += Eigen::Vector3d(0.01, -0.02, 0.015);
    qp.end_effector().set_target(target);
    qp.posture().reset_gains(5.0, 3.0, 1.0, gamma_posture);
    Eigen::VectorXd posture = q_;
    posture[0] += 0.2;
    qp.posture().set_target(posture);
  }

  phri::Model model_ = phri::Model::from_urdf_file(kGen3 + "gen3.urdf");
  phri::Data data_{model_};
  Eigen::VectorXd q_ = Eigen::VectorXd(7), qd_ = Eigen::VectorXd(7);
};

TEST_F(WholeBodyQpTest, UnconstrainedOptimumIsTheWeightedLeastSquaresSolution) {
  phri::WholeBodyQp qp(model_, nullptr, loose_settings());
  set_tasks(qp, 0.0, 0.0);
  const Eigen::VectorXd tau_ext = Eigen::VectorXd::Zero(7);
  ASSERT_EQ(qp.update(model_, data_, q_, qd_, tau_ext, 1e-3), phri::WholeBodyQpStatus::kOk);
  const auto& ee = qp.end_effector();
  const double w = ee.weight(), w0 = qp.posture().weight();
  const Eigen::MatrixXd h = w * ee.jacobian().transpose() * ee.jacobian() +
                            (w0 + qp.settings().regularization) * Eigen::MatrixXd::Identity(7, 7);
  const Eigen::VectorXd rhs = w * ee.jacobian().transpose() * ee.reference() + w0 * qp.posture().reference();
  const Eigen::VectorXd expected = h.ldlt().solve(rhs);
  EXPECT_LT((qp.desired_acceleration() - expected).norm(), 1e-9 * (1.0 + expected.norm()));
  // tau_d = M qdd_d + h - tau_ext.
  EXPECT_LT((qp.desired_torque() - (data_.mass_matrix * expected + data_.nonlinear_effects)).norm(), 1e-8);
  // The task reference is ë* - J̇ qd: K e + D (v_target - v) - bias, where the target jumped by a
  // few cm, so the governor moves the tracked target toward it (first step: speed a dt).
  const phri::Vector6d bias = phri::frame_jdot_qdot(model_, data_, ee.frame_id(), phri::ReferenceFrame::kLocalWorldAligned);
  EXPECT_LT((ee.reference() - (100.0 * ee.error() + 20.0 * (ee.target_velocity() - ee.velocity()) - bias)).norm(), 1e-12);
  EXPECT_NEAR(ee.target_velocity().head<3>().norm(), 0.5 * 1e-3, 1e-12);
  EXPECT_FALSE(ee.target_reached());
}

TEST_F(WholeBodyQpTest, GammaOneLetsThePushThroughAndGammaZeroNegatesIt) {
  Eigen::VectorXd tau_ext(7);
  tau_ext << 3.0, -5.0, 1.0, 4.0, -0.5, 0.3, 0.2;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(7);
  for (double gamma : {0.0, 1.0}) {
    phri::WholeBodyQp a(model_, nullptr, loose_settings()), b(model_, nullptr, loose_settings());
    set_tasks(a, gamma, gamma);
    set_tasks(b, gamma, gamma);
    a.update(model_, data_, q_, qd_, zero, 1e-3);
    b.update(model_, data_, q_, qd_, tau_ext, 1e-3);
    // gamma = 1: every reference shifts by the push's acceleration, so qdd_d does too and
    // tau_d = M (qdd_0 + M^-1 tau_ext) + h - tau_ext is unchanged: the controller does not resist.
    // gamma = 0: qdd_d is unchanged, tau_d = tau_0 - tau_ext cancels the push.
    const Eigen::VectorXd expected = gamma == 1.0 ? a.desired_torque() : Eigen::VectorXd(a.desired_torque() - tau_ext);
    // Exact but for the 1e-9 Hessian regularisation.
    EXPECT_LT((b.desired_torque() - expected).norm(), 1e-8 * (1.0 + expected.norm())) << "gamma " << gamma;
  }
}

TEST_F(WholeBodyQpTest, NullSpaceComplianceKeepsTheTaskAccelerationWhileThePostureYields) {
  Eigen::VectorXd tau_ext(7);
  tau_ext << 0.0, 4.0, 2.0, -3.0, 0.0, 0.0, 0.0;
  phri::WholeBodyQp a(model_, nullptr, loose_settings()), b(model_, nullptr, loose_settings());
  set_tasks(a, 0.0, 1.0);
  set_tasks(b, 0.0, 1.0);
  a.update(model_, data_, q_, qd_, Eigen::VectorXd::Zero(7), 1e-3);
  b.update(model_, data_, q_, qd_, tau_ext, 1e-3);
  const Eigen::VectorXd delta = b.desired_acceleration() - a.desired_acceleration();
  const Eigen::MatrixXd& j = b.end_effector().jacobian();
  // The push changes the joint accelerations, but (up to the weight ratio 1e-3) not the task's.
  EXPECT_GT(delta.norm(), 0.1);
  EXPECT_LT((j * delta).norm(), 2e-3 * delta.norm() * j.norm());
}

TEST_F(WholeBodyQpTest, JointDamperAndTorqueLimitsBound) {
  phri::WholeBodyQpSettings settings = gen3_settings();
  phri::WholeBodyQp qp(model_, nullptr, settings);
  set_tasks(qp, 0.0, 0.0);
  // Joint 2 close to its upper limit and moving toward it: the bound brakes it.
  Eigen::VectorXd q = q_, qd = Eigen::VectorXd::Zero(7);
  q[1] = 2.24 - 0.05;
  qd[1] = 0.8;
  phri::compute_all_terms(model_, data_, q, qd);
  Eigen::VectorXd posture = q;
  posture[1] = 3.0;  // the posture pulls beyond the limit
  qp.posture().reset_gains(200.0, 10.0, 1.0, 0.0);
  qp.posture().set_target(posture);
  ASSERT_EQ(qp.update(model_, data_, q, qd, Eigen::VectorXd::Zero(7), 1e-3), phri::WholeBodyQpStatus::kOk);
  const double range = 4.48, d_s = 0.01 * range, d_i = 0.1 * range;
  const double xi = 0.9 * 1.3963, m = 1.8, lambda = 4 * m * m * xi / (d_i - d_s);
  const double bound = lambda * lambda / (4 * m * m) * (0.05 - d_s) - lambda * qd[1];
  EXPECT_LE(qp.desired_acceleration()[1], bound + 1e-9);
  EXPECT_NEAR(qp.desired_acceleration()[1], bound, 1e-6);  // the posture pushes into it: active
  EXPECT_LT(bound, 0.0);  // moving at 0.8 rad/s 5 cm from the limit: must decelerate
  // Torques within limits even for an absurd target.
  Eigen::Isometry3d far = qp.end_effector().target_pose();
  far.translation() += Eigen::Vector3d(5.0, 5.0, 5.0);
  qp.end_effector().set_target(far);
  qp.end_effector().reset_gains(phri::Vector6d::Constant(1e4), phri::Vector6d::Constant(200.0), 1e4, phri::Vector6d::Zero());
  phri::compute_all_terms(model_, data_, q_, qd_);
  qp.update(model_, data_, q_, qd_, Eigen::VectorXd::Zero(7), 1e-3);
  EXPECT_TRUE((qp.desired_torque().cwiseAbs().array() <= qp.torque_limit().array() + 1e-6).all())
      << qp.desired_torque().transpose();
}

// A push the command does not cancel yet, a_u (UncancelledPush): every bound on qdd moves inward by
// it, ub - max(a_u, 0) and lb - min(a_u, 0), so that qdd_d + a_u stays within the paper's bounds;
// the rows and the other direction are untouched. With the posture pressing joint 2 into its
// damper (the case above), the command gives up exactly the push's share.
TEST_F(WholeBodyQpTest, AnUncancelledPushMovesTheBoundsInwardByItsAcceleration) {
  phri::WholeBodyQp plain(model_, nullptr, gen3_settings()), pushed(model_, nullptr, gen3_settings());
  Eigen::VectorXd q = q_, qd = Eigen::VectorXd::Zero(7);
  q[1] = 2.24 - 0.05;
  qd[1] = 0.8;
  phri::compute_all_terms(model_, data_, q, qd);
  Eigen::VectorXd posture = q;
  posture[1] = 3.0;
  for (phri::WholeBodyQp* qp : {&plain, &pushed}) {
    set_tasks(*qp, 0.0, 0.0);
    qp->posture().reset_gains(200.0, 10.0, 1.0, 0.0);
    qp->posture().set_target(posture);
  }
  const Eigen::VectorXd tau_ext = Eigen::VectorXd::Zero(7);
  Eigen::VectorXd uncancelled(7);
  uncancelled << 0.0, 3.0, -0.4, 0.0, 0.7, -0.2, 0.0;
  ASSERT_EQ(plain.update(model_, data_, q, qd, tau_ext, 1e-3), phri::WholeBodyQpStatus::kOk);
  ASSERT_EQ(pushed.update(model_, data_, q, qd, tau_ext, 1e-3, nullptr, &uncancelled), phri::WholeBodyQpStatus::kOk);
  ASSERT_EQ(pushed.solve_count(), 1u) << "feasible with the shift: nothing relaxed";
  const phri::QpProblem &a = plain.qp_problem(), &b = pushed.qp_problem();
  for (int i = 0; i < 7; ++i) {
    EXPECT_EQ(b.ub[i], a.ub[i] - std::max(uncancelled[i], 0.0)) << i;
    EXPECT_EQ(b.lb[i], a.lb[i] - std::min(uncancelled[i], 0.0)) << i;
  }
  EXPECT_EQ(a.A, b.A);
  EXPECT_EQ(a.l, b.l);
  EXPECT_EQ(a.u, b.u);
  // Active on joint 2: the command plus the push lands on the damper's bound.
  EXPECT_NEAR(plain.desired_acceleration()[1], a.ub[1], 1e-6);
  EXPECT_NEAR(pushed.desired_acceleration()[1] + uncancelled[1], a.ub[1], 1e-6);
  // A push larger than the room between the bounds: the far bound (the velocity limit's) moves by
  // a_u too, so the arm's acceleration spans the paper's [lb, ub], where splitting the difference
  // would have left it above ub.
  Eigen::VectorXd wide = Eigen::VectorXd::Zero(7);
  wide[4] = a.ub[4] - a.lb[4] + 1.0;
  ASSERT_EQ(pushed.update(model_, data_, q, qd, tau_ext, 1e-3, nullptr, &wide), phri::WholeBodyQpStatus::kOk);
  ASSERT_EQ(pushed.solve_count(), 2u) << "feasible with the shift: nothing relaxed";
  EXPECT_NEAR(pushed.qp_problem().lb[4], a.lb[4] - wide[4], 1e-9);
  EXPECT_NEAR(pushed.qp_problem().ub[4], a.ub[4] - wide[4], 1e-9);
  EXPECT_LE(pushed.desired_acceleration()[4] + wide[4], a.ub[4] + 1e-6);
  EXPECT_GE(pushed.desired_acceleration()[4] + wide[4], a.lb[4] - 1e-6);
  // Joint 2's upper bound is its joint-limit damper's (above), a position guard: a push the other way
  // that empties the interval does not move it; the two split the difference as before.
  Eigen::VectorXd against_limit = Eigen::VectorXd::Zero(7);
  against_limit[1] = -(a.ub[1] - a.lb[1] + 1.0);
  ASSERT_EQ(pushed.update(model_, data_, q, qd, tau_ext, 1e-3, nullptr, &against_limit), phri::WholeBodyQpStatus::kOk);
  EXPECT_EQ(pushed.qp_problem().lb[1], pushed.qp_problem().ub[1]);
  EXPECT_NEAR(pushed.qp_problem().ub[1], a.ub[1] + 0.5, 1e-9);
  // A push the torque limits cannot answer within the bounds: the shift is halved (a solve each) while
  // the QP is infeasible with it, then dropped (last), never the QP. 1e4 rad/s^2 on joint 2: between
  // one and four more solves; joint 2's upper bound below the paper's while a share is held, the
  // paper's once dropped; the other joints' bounds untouched.
  Eigen::VectorXd beyond = Eigen::VectorXd::Zero(7);
  beyond[1] = 1e4;
  const std::size_t solves = pushed.solve_count();
  ASSERT_EQ(pushed.update(model_, data_, q, qd, tau_ext, 1e-3, nullptr, &beyond), phri::WholeBodyQpStatus::kOk);
  const std::size_t extra = pushed.solve_count() - solves;
  ASSERT_GE(extra, 2u) << "infeasible with the whole shift";
  ASSERT_LE(extra, 5u) << "three halvings, then without it";
  if (extra == 5u) {
    EXPECT_EQ(pushed.qp_problem().ub[1], a.ub[1]) << "dropped: the paper's bound";
  } else {
    EXPECT_LT(pushed.qp_problem().ub[1], a.ub[1]) << "a share held";
  }
  for (int i = 0; i < 7; ++i) {
    if (i == 1) continue;
    EXPECT_EQ(pushed.qp_problem().ub[i], a.ub[i]) << i;
    EXPECT_EQ(pushed.qp_problem().lb[i], a.lb[i]) << i;
  }
  // Not finite: ignored (the bounds of tau_ext alone); the wrong size: invalid input.
  Eigen::VectorXd bad = uncancelled;
  bad[3] = std::numeric_limits<double>::quiet_NaN();
  ASSERT_EQ(pushed.update(model_, data_, q, qd, tau_ext, 1e-3, nullptr, &bad), phri::WholeBodyQpStatus::kOk);
  EXPECT_EQ(pushed.qp_problem().ub, a.ub);
  EXPECT_EQ(pushed.qp_problem().lb, a.lb);
  const Eigen::VectorXd short_vector = Eigen::VectorXd::Zero(6);
  EXPECT_EQ(pushed.update(model_, data_, q, qd, tau_ext, 1e-3, nullptr, &short_vector), phri::WholeBodyQpStatus::kInvalidInput);
}

// A guard on joint 5 of the kind a collision pair near the wrist makes: an upper bound on qdd_5 (and
// +-50 rad/s^2 on qdd_4), and a row on the motion l <= qdd_5 - 0.2 qdd_4 that braking joint 5 hard
// would cross (as a collision row reads braking toward the pair).
class WristGuard final : public phri::Constraint {
public:
  WristGuard(double upper, double row_lower) : upper_(upper), row_lower_(row_lower) {}
  std::string_view type() const override { return "wrist_guard"; }
  int num_rows() const override { return 1; }
  void bound(const phri::ConstraintContext&, Eigen::Ref<Eigen::VectorXd> lower, Eigen::Ref<Eigen::VectorXd> upper) override {
    upper[4] = std::min(upper[4], upper_);
    lower[3] = std::max(lower[3], -50.0);
    upper[3] = std::min(upper[3], 50.0);
  }
  void fill_rows(const phri::ConstraintContext&, Eigen::Ref<Eigen::MatrixXd> a, Eigen::Ref<Eigen::VectorXd> l,
                 Eigen::Ref<Eigen::VectorXd> u) override {
    a.setZero();
    a(0, 4) = 1.0;
    a(0, 3) = -0.2;
    l[0] = row_lower_;
    u[0] = std::numeric_limits<double>::infinity();
  }

private:
  double upper_, row_lower_;
};

// Rows on the motion hold the real acceleration qdd_d + a_u as the bounds do: both sides move by
// A a_u; the torque rows (the command's torque) stay. A push on the wrist that the bound answers by
// braking joint 5 hard: with the row read on the command alone the two contradict each other and the
// shift would be halved away (a UR5e's wrist, safety-fuzz seed 8128 push/dual/custom/3, reached
// 1.40x its speed limit that way); on the real motion they agree, solved at once.
TEST_F(WholeBodyQpTest, AnUncancelledPushShiftsTheRowsOnTheMotionButNotTheTorqueRows) {
  constexpr double kUpper = 20.0, kRowLower = -30.0, kPush = 500.0;
  phri::WholeBodyQp plain(model_, nullptr, loose_settings()), pushed(model_, nullptr, loose_settings());
  for (phri::WholeBodyQp* qp : {&plain, &pushed}) {
    qp->add_constraint(std::make_unique<WristGuard>(kUpper, kRowLower));
    set_tasks(*qp, 0.0, 0.0);
  }
  const Eigen::VectorXd tau_ext = Eigen::VectorXd::Zero(7);
  Eigen::VectorXd uncancelled = Eigen::VectorXd::Zero(7);
  uncancelled[3] = 40.0;
  uncancelled[4] = kPush;
  ASSERT_EQ(plain.update(model_, data_, q_, qd_, tau_ext, 1e-3), phri::WholeBodyQpStatus::kOk);
  const std::size_t solves = pushed.solve_count();
  ASSERT_EQ(pushed.update(model_, data_, q_, qd_, tau_ext, 1e-3, nullptr, &uncancelled), phri::WholeBodyQpStatus::kOk);
  EXPECT_EQ(pushed.solve_count() - solves, 1u) << "consistent on the real motion: nothing halved";

  const phri::QpProblem &a = plain.qp_problem(), &b = pushed.qp_problem();
  ASSERT_EQ(a.A.rows(), 8);  // the torque rows, then the guard's
  EXPECT_EQ(b.l.head(7), a.l.head(7));
  EXPECT_EQ(b.u.head(7), a.u.head(7));
  const double row_push = uncancelled[4] - 0.2 * uncancelled[3];
  EXPECT_NEAR(b.l[7], kRowLower - row_push, 1e-12);
  EXPECT_EQ(b.u[7], std::numeric_limits<double>::infinity());
  // The real acceleration keeps both the bound and the row; the command within its torque rows.
  const Eigen::VectorXd real = pushed.desired_acceleration() + uncancelled;
  EXPECT_NEAR(real[4], kUpper, 1e-6);
  EXPECT_GE(real[4] - 0.2 * real[3], kRowLower - 1e-9);
  const Eigen::VectorXd torque_rows = data_.mass_matrix * pushed.desired_acceleration();
  EXPECT_TRUE((torque_rows.array() >= b.l.head(7).array() - 1e-9).all());
  EXPECT_TRUE((torque_rows.array() <= b.u.head(7).array() + 1e-9).all());
  // The row read on the command alone contradicts the shifted bound (a separate solver).
  phri::QpProblem unshifted = b;
  unshifted.l[7] = kRowLower;
  phri::QpSolver separate(7, 0, unshifted.A.rows());
  EXPECT_EQ(separate.solve(unshifted), phri::QpStatus::kInfeasible);
  // In the cycle: no allocation.
  phri::test::AllocationCounter count;
  {
    phri::test::NoMallocScope no_malloc;
    EXPECT_EQ(pushed.update(model_, data_, q_, qd_, tau_ext, 1e-3, nullptr, &uncancelled), phri::WholeBodyQpStatus::kOk);
  }
  EXPECT_EQ(count.allocations(), 0u);
}

// UncancelledPush against closed forms: a_u = (M + B)^-1 (tau_fast - tau_ext) from the torque side
// (reference: Eigen's LDLT of M + diag(B)) and (qd - qd_prev) / dt - qdd_commanded from the motion;
// per joint the motion where it speeds the joint up (m qd > 0), else the smaller where they agree in
// sign, else 0. A torque-sensor spike the motion does not show is no push; one the motion shows
// speeding a joint up (the command cancelling a phantom) is; without a previous QP command there is
// no motion evidence.
TEST(UncancelledPush, IsTheMotionWhereItSpeedsAJointUpElseTheSmallerOfTheTwoWhereTheyAgree) {
  const phri::Model model = phri::Model::from_urdf_file(kGen3 + "gen3.urdf");
  phri::Data data(model);
  Eigen::VectorXd q(7), qd0(7);
  q << 0.2, 0.58, 3.0, -1.84, 0.3, 0.85, 1.57;
  qd0 << 0.1, -0.2, 0.3, 0.1, -0.2, 0.1, 0.3;
  phri::compute_all_terms(model, data, q, qd0);
  const Eigen::VectorXd rotor = Eigen::VectorXd::LinSpaced(7, 0.4, 0.1);
  Eigen::MatrixXd inertia = data.mass_matrix;
  inertia.diagonal() += rotor;
  const Eigen::VectorXd tau_ext = Eigen::VectorXd::LinSpaced(7, -3.0, 2.0);
  Eigen::VectorXd push(7);
  push << 4.0, -6.0, 1.5, 3.0, -2.0, 0.5, 1.0;
  const Eigen::VectorXd tau_fast = tau_ext + push;
  const Eigen::VectorXd truth = inertia.ldlt().solve(push);
  Eigen::VectorXd commanded(7);
  commanded << 1.0, -2.0, 0.5, 3.0, -1.0, 0.0, 2.0;
  const double dt = 1e-3;

  phri::UncancelledPush estimate(rotor, Eigen::VectorXd(), dt);
  // No previous sample: nothing.
  EXPECT_EQ(estimate.update(data, tau_ext, tau_fast, qd0, &commanded, dt), Eigen::VectorXd::Zero(7));
  struct Case {
    const char* what;
    double motion_share;  // the motion shows this share of the torque side's acceleration
  };
  int sped_up_any = 0, slowed_any = 0;
  for (const Case c : {Case{"the motion shows the whole push", 1.0}, Case{"the motion shows half of it", 0.5},
                       Case{"the motion shows more", 1.5}, Case{"the motion goes the other way", -1.0},
                       Case{"no motion beyond the command (a sensor spike)", 0.0}}) {
    SCOPED_TRACE(c.what);
    phri::UncancelledPush e(rotor, Eigen::VectorXd(), dt);
    e.update(data, tau_ext, tau_fast, qd0, &commanded, dt);
    const Eigen::VectorXd qd1 = qd0 + dt * (commanded + c.motion_share * truth);
    phri::test::AllocationCounter count;
    const Eigen::VectorXd& a = e.update(data, tau_ext, tau_fast, qd1, &commanded, dt);
    EXPECT_EQ(count.allocations(), 0u);
    EXPECT_LT((e.from_torque() - truth).cwiseAbs().maxCoeff(), 1e-9 * truth.cwiseAbs().maxCoeff());
    const double share = c.motion_share <= 0.0 ? 0.0 : std::min(c.motion_share, 1.0);
    const Eigen::VectorXd motion = c.motion_share * truth;
    int sped_up = 0;
    for (int i = 0; i < 7; ++i) {
      const bool speeds_up = motion[i] * qd1[i] > 0.0;
      sped_up += speeds_up ? 1 : 0;
      EXPECT_NEAR(a[i], speeds_up ? motion[i] : share * truth[i], 1e-6 * truth.cwiseAbs().maxCoeff()) << i;
    }
    if (c.motion_share != 0.0) {
      sped_up_any += sped_up;
      slowed_any += 7 - sped_up;
    }
  }
  EXPECT_GT(sped_up_any, 0) << "the cases exercise both rules";
  EXPECT_GT(slowed_any, 0) << "the cases exercise both rules";
  // The previous cycle sent no QP command, or the estimate was forgotten: no motion evidence.
  phri::UncancelledPush e(rotor, Eigen::VectorXd(), dt);
  e.update(data, tau_ext, tau_fast, qd0, &commanded, dt);
  EXPECT_EQ(e.update(data, tau_ext, tau_fast, qd0 + dt * truth, nullptr, dt), Eigen::VectorXd::Zero(7));
  e.forget();
  EXPECT_EQ(e.update(data, tau_ext, tau_fast, qd0 + 2 * dt * truth, &commanded, dt), Eigen::VectorXd::Zero(7));
  EXPECT_GT(e.update(data, tau_ext, tau_fast, qd0 + 2 * dt * truth + dt * (commanded + truth), &commanded, dt).norm(), 0.0);

  // Data carrying this B: M + B is factored beside M in compute_all_terms and the estimate reuses it,
  // bit for bit the estimate that factors it itself; another B in data is not taken for it.
  for (const bool same_rotor : {true, false}) {
    phri::Data with_rotors(model);
    with_rotors.rotor_inertia = same_rotor ? rotor : Eigen::VectorXd(2.0 * rotor);
    phri::compute_all_terms(model, with_rotors, q, qd0);
    ASSERT_TRUE(with_rotors.mass_matrix_with_rotors_llt.ok());
    phri::UncancelledPush reused(rotor, Eigen::VectorXd(), dt), alone(rotor, Eigen::VectorXd(), dt);
    const Eigen::VectorXd qd1 = qd0 + dt * (commanded + truth);
    reused.update(with_rotors, tau_ext, tau_fast, qd0, &commanded, dt);
    alone.update(data, tau_ext, tau_fast, qd0, &commanded, dt);
    phri::test::AllocationCounter count;
    reused.update(with_rotors, tau_ext, tau_fast, qd1, &commanded, dt);
    EXPECT_EQ(count.allocations(), 0u);
    alone.update(data, tau_ext, tau_fast, qd1, &commanded, dt);
    EXPECT_EQ(reused.from_torque(), alone.from_torque()) << "same rotor " << same_rotor;
    EXPECT_EQ(reused.acceleration(), alone.acceleration()) << "same rotor " << same_rotor;
  }
}

// Through an elastic transmission a command reaches the link as the spring winds: the estimate is
// scaled by the share f a held link sees of a torque step on average over the period. Reference:
// the rotor B theta'' = 1 - K theta integrated in 100000 explicit steps (semi-implicit Euler), the
// mean of K theta over [0, dt]. Rigid joints (no compliance) keep f = 1, as above.
TEST(UncancelledPush, AnElasticTransmissionPassesOnlyWhatItsSpringDeliversWithinThePeriod) {
  const double dt = 1e-3;
  const Eigen::VectorXd rotor = (Eigen::VectorXd(4) << 0.03, 0.03, 0.0135, 0.5).finished();
  const Eigen::VectorXd stiffness = (Eigen::VectorXd(4) << 13000.0, 1e9, 5500.0, 200.0).finished();
  const Eigen::VectorXd compliance = stiffness.cwiseInverse();
  const phri::UncancelledPush e(rotor, compliance, dt);
  for (int i = 0; i < 4; ++i) {
    constexpr int kSteps = 100000;
    const double h = dt / kSteps;
    double theta = 0.0, omega = 0.0, delivered = 0.0;
    for (int k = 0; k < kSteps; ++k) {
      omega += h * (1.0 - stiffness[i] * theta) / rotor[i];
      theta += h * omega;
      delivered += stiffness[i] * theta * h / dt;
    }
    EXPECT_NEAR(e.delivered_fraction()[i], delivered, 1e-4) << "joint " << i;
  }
  EXPECT_NEAR(e.delivered_fraction()[0], 0.07, 0.01);  // the Gen3's large joints: a tenth at most
  EXPECT_GT(e.delivered_fraction()[1], 0.99);          // a stiff spring: nearly rigid
  const phri::UncancelledPush rigid(rotor, Eigen::VectorXd(), dt);
  EXPECT_EQ(rigid.delivered_fraction(), Eigen::VectorXd::Ones(4));

  // The estimate itself: f times the rigid one, joint by joint.
  const phri::Model model = phri::Model::from_urdf_file(kGen3 + "gen3.urdf");
  phri::Data data(model);
  Eigen::VectorXd q(7), qd0(7);
  q << 0.2, 0.58, 3.0, -1.84, 0.3, 0.85, 1.57;
  qd0.setZero();
  phri::compute_all_terms(model, data, q, qd0);
  const Eigen::VectorXd b = Eigen::VectorXd::Constant(7, 0.03);
  const Eigen::VectorXd k = Eigen::VectorXd::LinSpaced(7, 1.0 / 13000.0, 1.0 / 2000.0);
  const Eigen::VectorXd tau_ext = Eigen::VectorXd::Zero(7);
  const Eigen::VectorXd tau_fast = Eigen::VectorXd::LinSpaced(7, 3.0, -2.0);
  const Eigen::VectorXd commanded = Eigen::VectorXd::Zero(7);
  phri::UncancelledPush elastic(b, k, dt), stiff(b, Eigen::VectorXd(), dt);
  for (phri::UncancelledPush* p : {&elastic, &stiff}) p->update(data, tau_ext, tau_fast, qd0, &commanded, dt);
  const Eigen::VectorXd qd1 = qd0 + dt * 10.0 * tau_fast;  // the motion shows more than the torque side
  const Eigen::VectorXd expected = elastic.delivered_fraction().cwiseProduct(stiff.update(data, tau_ext, tau_fast, qd1, &commanded, dt));
  EXPECT_LT((elastic.update(data, tau_ext, tau_fast, qd1, &commanded, dt) - expected).cwiseAbs().maxCoeff(), 1e-12);
  EXPECT_GT(expected.norm(), 0.0);
}

TEST_F(WholeBodyQpTest, InvalidInputHoldsTheLastCommandAndInfeasibleBrakes) {
  phri::WholeBodyQp qp(model_, nullptr, gen3_settings());
  set_tasks(qp, 0.0, 1.0);
  ASSERT_EQ(qp.update(model_, data_, q_, qd_, Eigen::VectorXd::Zero(7), 1e-3), phri::WholeBodyQpStatus::kOk);
  const Eigen::VectorXd good = qp.desired_torque();
  Eigen::VectorXd bad = Eigen::VectorXd::Zero(7);
  bad[3] = std::numeric_limits<double>::quiet_NaN();
  EXPECT_EQ(qp.update(model_, data_, q_, qd_, bad, 1e-3), phri::WholeBodyQpStatus::kInvalidInput);
  EXPECT_EQ(qp.desired_torque(), good);
  // A push no torque can cancel within the limits while the dampers demand braking: infeasible.
  Eigen::VectorXd q = q_, qd = Eigen::VectorXd::Zero(7);
  q[1] = 2.24 - 0.02;
  qd[1] = 1.3;
  phri::compute_all_terms(model_, data_, q, qd);
  Eigen::VectorXd huge = Eigen::VectorXd::Zero(7);
  huge[1] = 500.0;
  const auto status = qp.update(model_, data_, q, qd, huge, 1e-3);
  EXPECT_EQ(status, phri::WholeBodyQpStatus::kQpInfeasible);
  EXPECT_TRUE(qp.desired_torque().allFinite());
  EXPECT_TRUE((qp.desired_torque().cwiseAbs().array() <= qp.torque_limit().array() + 1e-9).all());
  // Joint 2's torque is beyond its limit with no brake at all: the brake never asks it for more
  // (braking the others through M would), so the fallback coasts rather than speeding joint 2 up.
  EXPECT_LE(qp.desired_acceleration()[1], 0.0);
  EXPECT_NEAR(qp.desired_torque()[1], -qp.torque_limit()[1], 1e-9);
}

// Joint 2 inside its damper band, running into it, with `hold` of its 30 N.m taken by holding a
// push; the others 15 N.m beyond what holds them.
struct BrakingCase {
  Eigen::VectorXd q, qd, tau_ext;
  phri::WholeBodyQpSettings settings;
};
BrakingCase braking_case(const Eigen::VectorXd& q0, const phri::Model& model, phri::Data& data, double hold) {
  BrakingCase c{q0, Eigen::VectorXd(7), Eigen::VectorXd::Zero(7), gen3_settings()};
  c.q[1] = 2.24 - 0.02;
  c.qd << 0.8, 1.3, -0.8, 0.8, -1.0, 1.0, -1.0;
  phri::compute_all_terms(model, data, c.q, c.qd);
  c.tau_ext[1] = data.nonlinear_effects[1] + hold;
  c.settings.torque_limit = data.nonlinear_effects.cwiseAbs() + Eigen::VectorXd::Constant(7, 15.0);
  c.settings.torque_limit[1] = 30.0;
  return c;
}

// The dampers ask joint 2 for more braking than the 3 N.m its limit leaves beyond holding a push
// (27 of 30 N.m): the QP answers with the largest common share of the bounds' braking demands the
// torque rows allow, not the fallback. Its torques are M qdd + h - tau_ext within the limits, the
// bounds it held are the demands scaled by that share, and 2^-9 more is infeasible (a separate solver).
TEST_F(WholeBodyQpTest, BrakingBeyondTheTorqueLeftIsScaledToTheLargestShareTheLimitsAllow) {
  const BrakingCase c = braking_case(q_, model_, data_, 27.0);
  phri::WholeBodyQp qp(model_, nullptr, c.settings);
  set_tasks(qp, 0.0, 1.0);
  ASSERT_EQ(qp.update(model_, data_, c.q, c.qd, c.tau_ext, 1e-3), phri::WholeBodyQpStatus::kBrakingScaled);
  EXPECT_TRUE(phri::solved(qp.status()));
  const double share = qp.braking_share();
  EXPECT_GT(share, 0.0);
  EXPECT_LT(share, 1.0);
  const Eigen::VectorXd realised = data_.mass_matrix * qp.desired_acceleration() + data_.nonlinear_effects - c.tau_ext;
  EXPECT_LT((realised - qp.desired_torque()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_TRUE((qp.desired_torque().cwiseAbs().array() <= c.settings.torque_limit.array() + 1e-9).all());
  // The problem as last solved carries the scaled bounds: joint 2's asks it to brake, and holds.
  phri::QpProblem problem = qp.qp_problem();
  ASSERT_LT(problem.ub[1], 0.0);
  EXPECT_TRUE((qp.desired_acceleration().array() <= problem.ub.array() + 1e-9).all());
  EXPECT_TRUE((qp.desired_acceleration().array() >= problem.lb.array() - 1e-9).all());
  const double more = (share + std::ldexp(1.0, -9)) / share;
  for (int i = 0; i < 7; ++i) {
    if (problem.ub[i] < 0.0) problem.ub[i] *= more;
    if (problem.lb[i] > 0.0) problem.lb[i] *= more;
  }
  phri::QpSolver separate(7, 0, problem.A.rows());
  EXPECT_EQ(separate.solve(problem), phri::QpStatus::kInfeasible);
  // The bisection's solves run in the cycle: no allocation.
  phri::test::AllocationCounter count;
  {
    phri::test::NoMallocScope no_malloc;
    EXPECT_EQ(qp.update(model_, data_, c.q, c.qd, c.tau_ext, 1e-3), phri::WholeBodyQpStatus::kBrakingScaled);
  }
  EXPECT_EQ(count.allocations(), 0u);
  // Within the limits the same state solves in full (share 1).
  phri::WholeBodyQpSettings roomy = c.settings;
  roomy.torque_limit[1] = 60.0;
  phri::WholeBodyQp full(model_, nullptr, roomy);
  set_tasks(full, 0.0, 1.0);
  EXPECT_EQ(full.update(model_, data_, c.q, c.qd, c.tau_ext, 1e-3), phri::WholeBodyQpStatus::kOk);
  EXPECT_EQ(full.braking_share(), 1.0);
}

// The fallback brake, scaled to the torque limits, is what the arm does when the QP is infeasible
// (here the same braking case with the scaled braking off): its torques are M qdd + h - tau_ext
// exactly (none clipped), within the limits, and it brakes every moving joint in the brake's
// direction; before, a joint near its limit lost the torque that braking its neighbours through M
// asked of it, and sped up (safety-fuzz seed 2718: 1.88 -> 2.51 rad/s).
TEST_F(WholeBodyQpTest, TheFallbackBrakeIsScaledToTheTorqueLimitsAndRealisesItsAcceleration) {
  const BrakingCase c = braking_case(q_, model_, data_, 27.0);
  const Eigen::VectorXd& q = c.q;
  const Eigen::VectorXd& qd = c.qd;
  const Eigen::VectorXd& tau_ext = c.tau_ext;
  phri::WholeBodyQpSettings settings = c.settings;
  settings.scale_braking = false;
  phri::WholeBodyQp qp(model_, nullptr, settings);
  set_tasks(qp, 0.0, 1.0);
  ASSERT_EQ(qp.update(model_, data_, q, qd, tau_ext, 1e-3), phri::WholeBodyQpStatus::kQpInfeasible);
  const Eigen::VectorXd realised = data_.mass_matrix * qp.desired_acceleration() + data_.nonlinear_effects - tau_ext;
  EXPECT_LT((realised - qp.desired_torque()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_TRUE((qp.desired_torque().cwiseAbs().array() <= settings.torque_limit.array() + 1e-9).all());
  const Eigen::VectorXd full = -settings.brake_damping * qd;
  double scale = -1.0;
  for (int i = 0; i < 7; ++i) {
    if (i == 1) continue;  // joint 2's brake is clipped by its damper's bounds
    const double s = qp.desired_acceleration()[i] / full[i];
    if (scale < 0.0) scale = s;
    EXPECT_NEAR(s, scale, 1e-9);  // one scale: the brake's direction kept
  }
  EXPECT_GT(scale, 0.0);
  EXPECT_LT(scale, 1.0);
}

TEST_F(WholeBodyQpTest, OneFullCycleDoesNotAllocate) {
  const phri::CollisionModel collision = phri::CollisionModel::from_yaml_file(kGen3 + "collision.yaml", model_);
  phri::WholeBodyQp qp(model_, &collision, gen3_settings());
  phri::ComplianceController compliance{phri::ComplianceSettings{}};
  compliance.initialise(phri::ComplianceMode::kDual, qp, data_);
  qp.posture().set_target(q_);
  phri::MomentumObserver observer(model_, 10.0);
  const Eigen::VectorXd tau_s = data_.gravity_torque;
  // Warm up once (first observer call resets), then count.
  phri::compute_all_terms(model_, data_, q_, qd_);
  phri::coriolis_transpose_times_velocity(model_, data_);
  observer.update(data_, qd_, tau_s, 1e-3);
  qp.update(model_, data_, q_, qd_, observer.external_torque(), 1e-3);
  phri::test::AllocationCounter count;
  {
    phri::test::NoMallocScope no_malloc;
    for (int k = 0; k < 10; ++k) {
      phri::compute_all_terms(model_, data_, q_, qd_);
      phri::coriolis_transpose_times_velocity(model_, data_);
      observer.update(data_, qd_, tau_s, 1e-3);
      compliance.update(k < 5 ? 10.0 : 1.0, qp, data_);
      qp.update(model_, data_, q_, qd_, observer.external_torque(), 1e-3);
    }
  }
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_EQ(compliance.touch_count(), 1);
  EXPECT_FALSE(compliance.touched());
}

// Dual compliance's Schmitt trigger (8 N up, 4 N down): update() reports the release, once, so the
// controller can re-anchor the posture where the hand left the arm.
TEST_F(WholeBodyQpTest, DualComplianceReportsTheReleaseOnceAfterTheSchmittTrigger) {
  phri::WholeBodyQp qp(model_, nullptr, gen3_settings());
  phri::ComplianceController compliance{phri::ComplianceSettings{}};
  compliance.initialise(phri::ComplianceMode::kDual, qp, data_);
  EXPECT_FALSE(compliance.update(5.0, qp, data_));  // below the touch threshold: nothing
  EXPECT_FALSE(compliance.touched());
  EXPECT_FALSE(compliance.update(9.0, qp, data_));  // touched
  EXPECT_TRUE(compliance.touched());
  EXPECT_FALSE(compliance.update(5.0, qp, data_));  // between the thresholds: still touched
  EXPECT_TRUE(compliance.touched());
  EXPECT_TRUE(compliance.update(3.0, qp, data_));  // released
  EXPECT_FALSE(compliance.touched());
  EXPECT_FALSE(compliance.update(3.0, qp, data_));  // only once
  EXPECT_FALSE(compliance.update(std::nan(""), qp, data_));
  compliance.set_mode(phri::ComplianceMode::kNullSpace, qp, data_);
  EXPECT_FALSE(compliance.update(20.0, qp, data_));  // no trigger outside dual compliance
  EXPECT_FALSE(compliance.touched());
  EXPECT_EQ(compliance.touch_count(), 1);
}

TEST_F(WholeBodyQpTest, TargetGovernorReachesAJumpedTargetWithBoundedSpeedAndTracksStreams) {
  phri::EndEffectorTask task(model_, model_.frame_id("end_effector_link"));
  task.hold_current_pose(data_);
  const Eigen::Isometry3d start = task.target_pose();
  Eigen::Isometry3d goal = start;
  goal.translation() += Eigen::Vector3d(0.1, 0.0, 0.0);
  task.set_target(goal);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(7);
  double max_speed = 0.0, time = 0.0;
  while (!task.target_reached() && time < 5.0) {
    task.update(model_, data_, zero, 1e-3);
    max_speed = std::max(max_speed, task.target_velocity().head<3>().norm());
    time += 1e-3;
  }
  // Triangular profile at 0.5 m/s^2 over 0.1 m: 2 sqrt(d / a) = 0.894 s, peak 0.224 m/s.
  EXPECT_NEAR(time, 2.0 * std::sqrt(0.1 / 0.5), 0.01);
  EXPECT_LE(max_speed, 0.25);
  EXPECT_LT((task.target_pose().translation() - goal.translation()).norm(), 1e-9);
  // A streamed trajectory at 0.1 m/s is tracked as given, feed-forward included.
  for (int k = 1; k <= 100; ++k) {
    Eigen::Isometry3d point = goal;
    point.translation().z() += 1e-4 * k;
    phri::Vector6d velocity = phri::Vector6d::Zero();
    velocity[2] = 0.1;
    task.set_target(point, velocity);
    task.update(model_, data_, zero, 1e-3);
    EXPECT_LT((task.target_pose().translation() - point.translation()).norm(), 1e-12);
    EXPECT_NEAR(task.target_velocity()[2], 0.1, 1e-12);
  }
}

TEST(ComplianceControllerTest, ReleaseThresholdAboveTheTouchThresholdIsAConfigError) {
  phri::ComplianceSettings inverted;
  inverted.touch_threshold = 4.0;
  inverted.release_threshold = 8.0;
  phri::test::expect_config_error([&] { phri::ComplianceController controller{inverted}; },
                                  {.element = "release_threshold", .mentions = {"touch_threshold"}});
}

}  // namespace

// The posture's stiction term (posture_task.hpp) against its closed form: at rest with a constant
// error e it grows at K_I e per second up to its clamp; it bleeds off (time constant 0.1 s) while
// the joint moves faster than 0.1 rad/s; it restarts from zero when the joint crosses its target;
// it never acts outside its zone or with zero stiffness.
TEST(PostureTaskTest, StictionTermIntegratesAtRestClampsBleedsAndResets) {
  const phri::Model model = phri::Model::from_urdf_file(kGen3 + "gen3.urdf");
  phri::PostureTask posture(model);
  posture.reset_gains(20.0, 9.0, 1.0, 0.0);
  const double gain = 200.0, limit = 40.0, zone = 0.3, dt = 1e-3;
  posture.set_integral(gain, limit, zone);
  Eigen::VectorXd target(7);
  target << 0, 0.58, 3.14, -1.84, 0, 0.85, 1.57;
  posture.set_target(target);
  Eigen::VectorXd q = target, qd = Eigen::VectorXd::Zero(7);
  const Eigen::VectorXd none = Eigen::VectorXd::Zero(7);
  q[1] -= 0.05;  // joint 2 stuck 0.05 rad short
  q[3] += 0.5;   // joint 4 outside the zone
  for (int k = 0; k < 100; ++k) posture.update(q, qd, none, dt);
  EXPECT_NEAR(posture.integral_term()[1], gain * 0.05 * 0.1, 1e-9);  // 0.1 s of K_I e
  EXPECT_EQ(posture.integral_term()[3], 0.0);
  EXPECT_NEAR(posture.reference()[1], 20.0 * 0.05 + gain * 0.05 * 0.1, 1e-9);
  for (int k = 0; k < 5000; ++k) posture.update(q, qd, none, dt);
  EXPECT_DOUBLE_EQ(posture.integral_term()[1], limit);
  qd[1] = 0.5;  // moving: bleeds with time constant 0.1 s
  for (int k = 0; k < 100; ++k) posture.update(q, qd, none, dt);
  EXPECT_NEAR(posture.integral_term()[1], limit * std::exp(-1.0), 1e-6);
  qd[1] = 0.0;
  q[1] = target[1] + 0.01;  // crossed the target: restarts from zero, on the other side
  posture.update(q, qd, none, dt);
  EXPECT_NEAR(posture.integral_term()[1], -gain * 0.01 * dt, 1e-12);
  posture.reset_gains(0.0, 9.0, 1.0, 0.0);  // no spring: no stiction term either
  posture.set_integral(gain, limit, zone);
  for (int k = 0; k < 100; ++k) posture.update(q, qd, none, dt);
  EXPECT_EQ(posture.integral_term()[1], 0.0);
}

// The end-effector task's weight near a singularity (singular_direction_weight.hpp) against the
// closed form from an SVD: W = U diag(min(1, (sigma / sigma_0)^2)) U^T.
TEST(SingularDirectionWeightTest, MatchesTheClosedFormFromTheSvdAndIsOffAboveTheThreshold) {
  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  const double sigma0 = 0.03;
  for (int trial = 0; trial < 50; ++trial) {
    // J = U S V^T with chosen singular values: the smallest below, at or above the threshold.
    Eigen::MatrixXd a = Eigen::MatrixXd::NullaryExpr(6, 6, [&] { return normal(rng); });
    Eigen::MatrixXd b = Eigen::MatrixXd::NullaryExpr(7, 7, [&] { return normal(rng); });
    const Eigen::MatrixXd u = Eigen::HouseholderQR<Eigen::MatrixXd>(a).householderQ();
    const Eigen::MatrixXd v = Eigen::HouseholderQR<Eigen::MatrixXd>(b).householderQ();
    Eigen::VectorXd sigma(6);
    sigma << 1.5, 1.1, 0.8, 0.4, 0.2, 0.0;
    const double ratios[] = {0.0, 0.01, 0.5, 0.99, 1.01, 3.0};
    sigma[5] = ratios[trial % 6] * sigma0;
    if (trial % 12 >= 6) sigma[4] = 0.5 * sigma0;  // two weak directions
    Eigen::MatrixXd s = Eigen::MatrixXd::Zero(6, 7);
    s.diagonal() = sigma;
    const Eigen::MatrixXd jacobian = u * s * v.transpose();

    phri::SingularDirectionWeight weight(sigma0);
    const bool below = sigma.minCoeff() < sigma0;
    ASSERT_EQ(weight.update(jacobian), below) << "trial " << trial << " sigma_min " << sigma.minCoeff();
    if (!below) continue;
    Eigen::VectorXd f = (sigma.array() / sigma0).square().min(1.0);
    const Eigen::MatrixXd expected = u * f.asDiagonal() * u.transpose();
    EXPECT_LT((weight.weight() - expected).norm(), 1e-9) << "trial " << trial;
    EXPECT_NEAR(weight.smallest_singular_value(), sigma.minCoeff(), 1e-7);
  }
  // Off: never active.
  phri::SingularDirectionWeight off(0.0);
  EXPECT_FALSE(off.update(Eigen::MatrixXd::Zero(6, 7)));
}

TEST(SingularDirectionWeightTest, IsContinuousThroughTheSingularity) {
  // A one-parameter family whose smallest singular value crosses zero: W moves by O(step).
  Eigen::MatrixXd base = Eigen::MatrixXd::Zero(6, 7);
  base.diagonal() << 1.0, 0.9, 0.8, 0.7, 0.6, 0.0;
  Eigen::MatrixXd direction = Eigen::MatrixXd::Zero(6, 7);
  direction(5, 5) = 1.0;
  direction(4, 5) = 0.3;
  phri::SingularDirectionWeight weight(0.03);
  Eigen::Matrix<double, 6, 6> last = Eigen::Matrix<double, 6, 6>::Identity();
  double worst = 0.0;
  for (int k = -100; k <= 100; ++k) {
    const double t = 0.05 * k / 100.0;  // sigma_min ~ |t| crosses 0 and leaves the zone
    Eigen::Matrix<double, 6, 6> w = Eigen::Matrix<double, 6, 6>::Identity();
    if (weight.update(base + t * direction)) w = weight.weight();
    if (k > -100) worst = std::max(worst, (w - last).norm());
    last = w;
  }
  // Step in t: 5e-4; f = (sigma / 0.03)^2 changes by at most 2 sigma dsigma / 0.03^2 ~ 0.04 a step.
  EXPECT_LT(worst, 0.05);
}

namespace {

// A random n x n orthogonal matrix (Q of a Gaussian matrix's QR), drawn from rng through normal.
Eigen::MatrixXd random_orthogonal(int n, std::mt19937& rng, std::normal_distribution<double>& normal) {
  return Eigen::HouseholderQR<Eigen::MatrixXd>(Eigen::MatrixXd::NullaryExpr(n, n, [&] { return normal(rng); })).householderQ();
}

}  // namespace

// Along a path that stays near a singularity (one weak direction, turning a little each step) the
// weight is tracked from the last weak direction instead of decomposed anew: the same W as a fresh
// eigen-decomposition to 1e-12; two weak directions, or a jump, go back to the decomposition.
TEST(SingularDirectionWeightTest, TrackingTheWeakDirectionGivesTheDecompositionsWeight) {
  std::mt19937 rng(11);
  std::normal_distribution<double> normal;
  const Eigen::MatrixXd v = random_orthogonal(7, rng, normal);
  auto jacobian_at = [&](double t, double second) {
    // U turns with t; the weakest singular value goes through zero and back, the second stays put.
    Eigen::Matrix<double, 6, 6> generator = Eigen::Matrix<double, 6, 6>::Zero();
    generator(0, 5) = 1.0, generator(5, 0) = -1.0, generator(2, 4) = 0.5, generator(4, 2) = -0.5;
    const Eigen::Matrix<double, 6, 6> u = (t * generator).exp();
    Eigen::MatrixXd s = Eigen::MatrixXd::Zero(6, 7);
    s.diagonal() << 1.5, 1.1, 0.8, 0.4, second, 0.02 * std::cos(3.0 * t);
    return Eigen::MatrixXd(u * s * v.transpose());
  };
  phri::SingularDirectionWeight tracked(0.03);
  double worst = 0.0;
  int steps = 0;
  for (double t = 0.0; t < 2.0; t += 1e-3, ++steps) {
    const Eigen::MatrixXd j = jacobian_at(t, 0.3);
    phri::SingularDirectionWeight fresh(0.03);
    ASSERT_EQ(tracked.update(j), fresh.update(j)) << "t " << t;
    if (!fresh.active()) continue;
    worst = std::max(worst, (tracked.weight() - fresh.weight()).norm());
    EXPECT_NEAR(tracked.smallest_singular_value(), fresh.smallest_singular_value(), 1e-10);
  }
  EXPECT_LT(worst, 1e-12);
  EXPECT_LT(tracked.decompositions(), steps / 10) << "tracked, not decomposed, on most steps";
  // A second weak direction: the decomposition decides, and agrees.
  const long before = tracked.decompositions();
  const Eigen::MatrixXd two = jacobian_at(2.0, 0.01);
  phri::SingularDirectionWeight fresh(0.03);
  ASSERT_TRUE(tracked.update(two) && fresh.update(two));
  EXPECT_EQ(tracked.decompositions(), before + 1);
  EXPECT_LT((tracked.weight() - fresh.weight()).norm(), 1e-12);
}

// While the weak direction is tracked, the other eigenvalues' check is carried by Weyl's certificate
// (lambda_1 >= 4 sigma_0^2 tested once, then ||A - A_c||_F < 3 sigma_0^2): along a path on which
// the second singular value comes down through the threshold and back, every answer and weight equals
// a fresh decomposition's, the certificate answers on most steps while sigma_1 is far, and never
// while sigma_1 is below sigma_0 (it carries lambda_1 > t, no more).
TEST(SingularDirectionWeightTest, TrackingCarriesTheOtherEigenvaluesCheckOnlyWhileItHolds) {
  std::mt19937 rng(5);
  std::normal_distribution<double> normal;
  const Eigen::MatrixXd v = random_orthogonal(7, rng, normal);
  const Eigen::MatrixXd u = random_orthogonal(6, rng, normal);
  const double sigma0 = 0.03;
  phri::SingularDirectionWeight tracked(sigma0, 7);
  double worst = 0.0;
  long second_below_steps = 0, far_tracked_steps = 0;
  for (double t = 0.0; t < 4.0; t += 1e-3) {
    // sigma_1: 0.3 -> 0.02 -> 0.3 (below sigma_0 for a while: two weak directions), sigma_min ~0.01.
    const double second = 0.16 + 0.14 * std::cos(0.5 * M_PI * t);
    Eigen::MatrixXd s = Eigen::MatrixXd::Zero(6, 7);
    s.diagonal() << 1.5, 1.1, 0.8, 0.4, second, 0.01 + 0.005 * std::sin(3.0 * t);
    const Eigen::MatrixXd jacobian = u * s * v.transpose() + 0.02 * std::sin(2.0 * t) * u.col(1) * v.col(6).transpose();
    phri::SingularDirectionWeight fresh(sigma0);
    const long certified_before = tracked.second_certified();
    ASSERT_EQ(tracked.update(jacobian), fresh.update(jacobian)) << "t " << t;
    ASSERT_TRUE(fresh.active());
    worst = std::max(worst, (tracked.weight() - fresh.weight()).norm());
    const bool certified = tracked.second_certified() > certified_before;
    if (second < sigma0) {
      EXPECT_FALSE(certified) << "t " << t << " sigma_1 " << second;
      ++second_below_steps;
    }
    far_tracked_steps += second > 0.1;
  }
  EXPECT_LT(worst, 1e-12);
  EXPECT_GT(second_below_steps, 100);
  EXPECT_GT(tracked.second_certified(), far_tracked_steps / 2) << "certified on most steps with sigma_1 far";
}

// Far from a singularity the weight answers from Weyl's certificate (sigma_i(J) >= sigma_i(J_c) -
// ||J - J_c||_F) instead of testing: along a path that approaches the threshold, leaves and comes
// back, its answers and weights equal a fresh weight's (which always tests) at every step, and most
// steps far from the threshold are certified.
TEST(SingularDirectionWeightTest, WeylCertificateGivesTheTestsAnswerAlongAPath) {
  std::mt19937 rng(23);
  std::normal_distribution<double> normal;
  const Eigen::MatrixXd v = random_orthogonal(7, rng, normal);
  const Eigen::MatrixXd u = random_orthogonal(6, rng, normal);
  const double sigma0 = 0.03;
  phri::SingularDirectionWeight certified(sigma0, 7);
  int far_steps = 0;
  for (double t = 0.0; t < 3.0; t += 1e-3) {
    // sigma_min sweeps 0.2 -> 0.01 -> 0.2 -> ...: far, near the threshold, below it, and back.
    const double smallest = 0.105 + 0.095 * std::cos(2.0 * M_PI * t);
    Eigen::MatrixXd s = Eigen::MatrixXd::Zero(6, 7);
    s.diagonal() << 1.5, 1.1, 0.8, 0.4, 0.3, smallest;
    const Eigen::MatrixXd jacobian = u * s * v.transpose() + 0.01 * std::sin(5.0 * t) * u.col(0) * v.col(6).transpose();
    phri::SingularDirectionWeight fresh(sigma0);
    const bool expected = fresh.update(jacobian);
    ASSERT_EQ(certified.update(jacobian), expected) << "t " << t << " sigma_min ~ " << smallest;
    if (expected) {
      EXPECT_LT((certified.weight() - fresh.weight()).norm(), 1e-12) << "t " << t;
    }
    far_steps += smallest > 2.5 * sigma0;
  }
  EXPECT_GT(certified.certified_skips(), far_steps / 2) << "certified on most steps far from the threshold";
  // A Jacobian of another width: tested every time, never certified from the 7-column one.
  const long skips = certified.certified_skips();
  EXPECT_FALSE(certified.update(Eigen::MatrixXd::Identity(6, 6)));
  EXPECT_FALSE(certified.update(Eigen::MatrixXd::Identity(6, 6)));
  EXPECT_EQ(certified.certified_skips(), skips);
}

// Near the Gen3's outstretched elbow (q4 = 0.07: sigma_min ~ 0.01, the arm cannot reach further
// out) five millimetres of pose error straight out ask the paper's task for ~100 rad/s^2 along the
// weak joint direction (joints 2, 4, 6: the task amplifies by up to 1 / (2 sqrt(w_0 / w_ee)) = 50);
// the weighted task asks for a fraction of it, and away from the singularity nothing changes.
TEST_F(WholeBodyQpTest, NearTheOutstretchedElbowTheTaskNoLongerAsksForHugeJointAccelerations) {
  Eigen::VectorXd q(7);
  q << 0.0, 0.4, 0.0, 0.07, 0.0, 0.9, 0.0;
  const Eigen::VectorXd qd = Eigen::VectorXd::Zero(7);
  const Eigen::VectorXd tau_ext = Eigen::VectorXd::Zero(7);
  phri::compute_all_terms(model_, data_, q, qd);
  auto solve = [&](double threshold) {
    phri::WholeBodyQpSettings s = loose_settings();
    s.singular_value_threshold = threshold;
    phri::WholeBodyQp qp(model_, nullptr, s);
    qp.end_effector().reset_gains(phri::Vector6d::Constant(400.0), phri::Vector6d::Constant(40.0), 1e4,
                                  phri::Vector6d::Zero());
    qp.end_effector().hold_current_pose(data_);
    Eigen::Isometry3d target = qp.end_effector().target_pose();
    target.translation() += 0.005 * Eigen::Vector3d(0.4, -0.03, 0.91).normalized();  // straight out
    qp.end_effector().set_target(target);
    qp.posture().reset_gains(20.0, 9.0, 1.0, 0.0);
    qp.posture().set_target(q);
    for (int k = 0; k < 2000 && !qp.end_effector().target_reached(); ++k) qp.update(model_, data_, q, qd, tau_ext, 1e-3);
    EXPECT_TRUE(qp.end_effector().target_reached());
    EXPECT_EQ(qp.update(model_, data_, q, qd, tau_ext, 1e-3), phri::WholeBodyQpStatus::kOk);
    // KKT of the unconstrained weighted least squares: H qdd + g = 0, W in place of I.
    const auto& ee = qp.end_effector();
    Eigen::Matrix<double, 6, 6> w = Eigen::Matrix<double, 6, 6>::Identity();
    phri::SingularDirectionWeight weight(threshold);
    EXPECT_EQ(weight.update(ee.jacobian()), threshold > 0.0);
    if (weight.active()) w = weight.weight();
    const Eigen::MatrixXd h = ee.weight() * ee.jacobian().transpose() * w * ee.jacobian() +
                              (qp.posture().weight() + s.regularization) * Eigen::MatrixXd::Identity(7, 7);
    const Eigen::VectorXd g = -ee.weight() * ee.jacobian().transpose() * w * ee.reference() -
                              qp.posture().weight() * qp.posture().reference();
    EXPECT_LT((h * qp.desired_acceleration() + g).norm(), 1e-6 * (1.0 + g.norm()));
    return Eigen::VectorXd(qp.desired_acceleration());
  };
  const Eigen::VectorXd paper = solve(0.0), weighted = solve(0.03);
  EXPECT_GT(paper.cwiseAbs().maxCoeff(), 50.0) << paper.transpose();
  EXPECT_LT(weighted.cwiseAbs().maxCoeff(), 0.3 * paper.cwiseAbs().maxCoeff()) << weighted.transpose();

  // Away from the singularity (the fixture's posture) the two are the same to the last bit.
  phri::compute_all_terms(model_, data_, q_, qd_);
  phri::WholeBodyQpSettings s = loose_settings();
  phri::WholeBodyQp a(model_, nullptr, s);
  s.singular_value_threshold = 0.0;
  phri::WholeBodyQp b(model_, nullptr, s);
  set_tasks(a, 0.0, 0.0);
  set_tasks(b, 0.0, 0.0);
  ASSERT_EQ(a.update(model_, data_, q_, qd_, tau_ext, 1e-3), phri::WholeBodyQpStatus::kOk);
  ASSERT_EQ(b.update(model_, data_, q_, qd_, tau_ext, 1e-3), phri::WholeBodyQpStatus::kOk);
  EXPECT_EQ(a.desired_acceleration(), b.desired_acceleration());
}

TEST_F(WholeBodyQpTest, ACycleNearTheSingularityDoesNotAllocate) {
  q_ << 0.0, 0.4, 0.0, 1e-3, 0.0, 0.9, 0.0;
  phri::WholeBodyQp qp(model_, nullptr, gen3_settings());
  qp.posture().set_target(q_);
  const Eigen::VectorXd tau_ext = Eigen::VectorXd::Zero(7);
  phri::compute_all_terms(model_, data_, q_, qd_);
  qp.update(model_, data_, q_, qd_, tau_ext, 1e-3);
  phri::test::AllocationCounter count;
  {
    phri::test::NoMallocScope no_malloc;
    for (int k = 0; k < 10; ++k) {
      q_[3] += 1e-4;
      phri::compute_all_terms(model_, data_, q_, qd_);
      qp.update(model_, data_, q_, qd_, tau_ext, 1e-3);
    }
  }
  EXPECT_EQ(count.allocations(), 0u);
  phri::SingularDirectionWeight probe(qp.settings().singular_value_threshold);
  EXPECT_TRUE(probe.update(qp.end_effector().jacobian()));  // the weighting was on
}
