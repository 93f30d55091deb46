// ctest-labels: unit
// The velocity guard's coupling bound (torque_guards.hpp) against the eigenvalues it bounds and a
// closed-form pair of joints on one axis. The collision guard's tests are in test_collision.cpp.
#include <phri/control/torque_guards.hpp>

#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>

#include <random>

namespace {

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

}  // namespace
