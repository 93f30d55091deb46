// ctest-labels: unit
// The torque guards behind the QP (torque_guards.hpp): the velocity guard's coupling bound against
// the eigenvalues it bounds and a closed-form pair of joints on one axis; the collision guard
// against its formula and, from rest, against the distance it opens (finite differences).
#include <phri/control/torque_guards.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/collision_model.hpp>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <random>

namespace {

const std::string kGen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";
constexpr double kPeriod = 1e-3;

// The largest eigenvalue of T D^1/2 (M^-1)_SS D^1/2 over the guarded set S, by Eigen's solver.
double largest_step(const Eigen::MatrixXd& mobility, const Eigen::VectorXd& damping, const Eigen::VectorXd& excess) {
  std::vector<int> guarded;
  for (int i = 0; i < excess.size(); ++i) {
    if (excess[i] > 0.0) guarded.push_back(i);
  }
  const int m = static_cast<int>(guarded.size());
  Eigen::MatrixXd a(m, m);
  for (int r = 0; r < m; ++r) {
    for (int c = 0; c < m; ++c) {
      a(r, c) = kPeriod * std::sqrt(damping[guarded[r]] * damping[guarded[c]]) * mobility(guarded[r], guarded[c]);
    }
  }
  return Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(a).eigenvalues().maxCoeff();
}

TEST(GuardCouplingScale, KeepsTheLargestEigenvalueWithinTheStep) {
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  constexpr double kMaxStep = 1.5;
  int scaled = 0;
  for (int sample = 0; sample < 2000; ++sample) {
    const int n = 2 + sample % 6;
    Eigen::MatrixXd a = Eigen::MatrixXd::NullaryExpr(n, n, [&] { return u(rng); });
    // Near-singular inertias too (a coupled pair): the smallest eigenvalue down to 1e-3.
    const Eigen::MatrixXd inertia = a * a.transpose() + std::pow(10.0, -3.0 + 3.0 * (0.5 + 0.5 * u(rng))) * Eigen::MatrixXd::Identity(n, n);
    const Eigen::MatrixXd mobility = inertia.llt().solve(Eigen::MatrixXd::Identity(n, n));
    const Eigen::VectorXd damping = 300.0 * inertia.diagonal();
    Eigen::VectorXd excess = Eigen::VectorXd::Zero(n);
    for (int i = 0; i < n; ++i) excess[i] = u(rng) > 0.0 ? 0.1 : 0.0;
    if (excess.isZero()) {
      EXPECT_EQ(phri::guard_coupling_scale(mobility, damping, excess, kPeriod, kMaxStep), 1.0);
      continue;
    }
    const double scale = phri::guard_coupling_scale(mobility, damping, excess, kPeriod, kMaxStep);
    const double unscaled = largest_step(mobility, damping, excess);
    ASSERT_GT(scale, 0.0);
    ASSERT_LE(scale, 1.0);
    EXPECT_LE(scale * unscaled, kMaxStep * (1.0 + 1e-12));
    // Gershgorin is conservative, but a row's absolute sum is at most sqrt(m) times the largest
    // eigenvalue (m guarded joints): it never scales by more than that.
    const double m = static_cast<double>((excess.array() > 0.0).count());
    EXPECT_GE(scale, std::min(1.0, kMaxStep / (std::sqrt(m) * unscaled)) * (1.0 - 1e-12));
    if ((excess.array() > 0.0).count() == 1) {
      // One joint: the bound is exact, T D_ii (M^-1)_ii.
      int i = 0;
      excess.maxCoeff(&i);
      EXPECT_NEAR(scale, std::min(1.0, kMaxStep / (kPeriod * damping[i] * mobility(i, i))), 1e-12);
    }
    scaled += scale < 1.0;
  }
  EXPECT_GT(scaled, 100);  // the near-singular inertias do need it
}

// Joint 1 turns a light link A and, through joint 2 on the same axis, a heavy body B: the Gen3's
// joints 1 and 3 near q2 = 0. M = [[I_A + I_B, I_B], [I_B, I_B]], M^-1 = [[1, -1], [-1, 1 + I_A/I_B]] / I_A,
// so M_11 (M^-1)_11 = 1 + I_B / I_A. Both joints above the guard speed, the guard damping
// D = rate diag(M) on the latest sample: e' = (I - T M^-1 s D) e, with s the coupling scale.
TEST(GuardCouplingScale, StopsTheRingingOfTwoJointsOnOneAxis) {
  const double light = 0.02, heavy = 0.13;  // kg m^2: M_11 (M^-1)_11 = 7.5
  Eigen::Matrix2d inertia;
  inertia << light + heavy, heavy, heavy, heavy;
  const Eigen::MatrixXd mobility = inertia.inverse();
  EXPECT_NEAR(inertia(0, 0) * mobility(0, 0), 7.5, 1e-12);
  const Eigen::VectorXd damping = 300.0 * inertia.diagonal();
  const Eigen::VectorXd excess = Eigen::Vector2d(0.1, 0.1);
  auto final_excess = [&](double scale) {
    Eigen::Vector2d e(0.1, -0.05);
    for (int k = 0; k < 40; ++k) e -= kPeriod * mobility * (scale * damping.asDiagonal() * e);
    return e.norm();
  };
  const double scale = phri::guard_coupling_scale(mobility, damping, excess, kPeriod, 1.5);
  EXPECT_LT(scale, 1.0);
  // Per cycle each mode's excess is multiplied by 1 - lambda, lambda an eigenvalue of T M^-1 s D.
  auto worst_factor = [&](double s) {
    const Eigen::MatrixXd step = kPeriod * mobility * (s * damping).asDiagonal();
    return (1.0 - step.eigenvalues().real().array()).abs().maxCoeff();
  };
  // Unscaled: the relative mode's lambda is above 2, each cycle overshoots by more than the excess
  // it removes: it grows, alternating in sign.
  EXPECT_GT(worst_factor(1.0), 1.0);
  EXPECT_GT(final_excess(1.0), 10.0 * 0.1);
  // Scaled: lambda <= 1.5, the excess decays.
  EXPECT_LT(worst_factor(scale), 1.0);
  EXPECT_LT(final_excess(scale), 0.1 * 0.1);
}

class Gen3CollisionGuard : public ::testing::Test {
protected:
  phri::Model model_ = phri::Model::from_urdf_file(kGen3 + "gen3.urdf");
  phri::CollisionModel collision_ = phri::CollisionModel::from_yaml_file(kGen3 + "collision.yaml", model_);
  phri::Data data_{model_};
  phri::CollisionData pairs_{model_, collision_};
};

TEST_F(Gen3CollisionGuard, TorqueIsTheFormulaOnThePairsInsideTheSafetyDistance) {
  Eigen::VectorXd q(7), qd(7);
  q << 0, 1.2, 0, 2.5, 0, 2.0, 0;  // folded: some pairs close
  qd << 0.3, -0.2, 0.1, 0.4, -0.3, 0.2, 0.1;
  phri::compute_all_terms(model_, data_, q, qd);
  phri::compute_collision_distances(model_, data_, collision_, pairs_, true);
  const double safety_distance = pairs_.distance.minCoeff() + 0.02;  // some pairs inside, not all
  const double k = 6000.0, c = 150.0;
  Eigen::VectorXd tau = Eigen::VectorXd::Constant(7, 1.0), expected = tau;
  int inside = 0;
  for (int p = 0; p < collision_.num_pairs(); ++p) {
    if (pairs_.distance[p] >= safety_distance) continue;
    ++inside;
    const double force = k * (safety_distance - pairs_.distance[p]) + c * std::max(-pairs_.velocity[p], 0.0);
    expected += force * pairs_.jacobian.row(p).transpose();
  }
  ASSERT_GT(inside, 0);
  ASSERT_LT(inside, collision_.num_pairs());
  EXPECT_TRUE(phri::add_collision_guard(pairs_, safety_distance, k, c, tau));
  EXPECT_TRUE(tau.isApprox(expected, 1e-14));
  // Every pair outside: nothing added.
  Eigen::VectorXd untouched = Eigen::VectorXd::Constant(7, 1.0);
  EXPECT_FALSE(phri::add_collision_guard(pairs_, pairs_.distance.minCoeff() - 1e-3, k, c, untouched));
  EXPECT_EQ(untouched, Eigen::VectorXd::Constant(7, 1.0));
}

// From rest the guard's torque alone accelerates the arm by M^-1 tau; after a short time h the
// pair inside d_s must have opened by h^2 / 2 J M^-1 J^T F > 0, measured on the distances
// themselves (no Jacobian): the torque separates the pair it answers.
TEST_F(Gen3CollisionGuard, FromRestTheTorqueOpensThePair) {
  Eigen::VectorXd q(7);
  q << 0, 1.2, 0, 2.5, 0, 2.0, 0;
  const Eigen::VectorXd rest = Eigen::VectorXd::Zero(7);
  phri::compute_all_terms(model_, data_, q, rest);
  phri::compute_collision_distances(model_, data_, collision_, pairs_, true);
  int closest = 0;
  const double d0 = pairs_.distance.minCoeff(&closest);
  const double safety_distance = d0 + 0.005;
  // Only the closest pair inside d_s.
  Eigen::VectorXd sorted = pairs_.distance;
  std::sort(sorted.data(), sorted.data() + sorted.size());
  ASSERT_GT(sorted[1], safety_distance);
  Eigen::VectorXd tau = Eigen::VectorXd::Zero(7);
  ASSERT_TRUE(phri::add_collision_guard(pairs_, safety_distance, 6000.0, 150.0, tau));
  const Eigen::LLT<Eigen::MatrixXd> inertia(data_.mass_matrix);
  const Eigen::VectorXd qdd = inertia.solve(tau);
  const double h = 1e-3, force = 6000.0 * 0.005;
  const Eigen::VectorXd jacobian = pairs_.jacobian.row(closest).transpose();
  const double predicted = 0.5 * h * h * force * jacobian.dot(inertia.solve(jacobian));
  phri::forward_kinematics(model_, data_, q + 0.5 * h * h * qdd);
  phri::CollisionData after(model_, collision_);
  phri::compute_collision_distances(model_, data_, collision_, after, false);
  const double opened = after.distance[closest] - d0;
  EXPECT_GT(opened, 0.0);
  EXPECT_NEAR(opened, predicted, 1e-3 * predicted);
  std::printf("closest pair %d at %.2f mm: opened %.3e m in 1 ms from rest (predicted %.3e)\n", closest, 1e3 * d0,
              opened, predicted);
}

}  // namespace
