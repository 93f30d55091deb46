// ctest-labels: unit
// The named filters of core (filters.hpp, smoothed_vector.hpp) against closed forms:
//   LowPassFilter        y_k = y_{k-1} + a (x_k - y_{k-1}), a = dt / (T + dt): step response
//                        1 - (1 - a)^k, decay from a reset value, steady-state sinusoid
//                        Im(H(e^{jwT}) e^{jwkT}) with H(z) = a / (1 - (1 - a) z^-1);
//   ComplementaryFilter  out = low + high - LP_g(high), g = 1 - exp(-K dt): constant inputs give
//                        low + high (1 - g)^k (so the output converges to `low`), `low` passes
//                        unchanged, and `high` sees H(z) = (1 - g)(1 - z^-1) / (1 - (1 - g) z^-1),
//                        close to the continuous s / (s + K) well below the sampling rate;
//   soft_deadband        the values sign(x) max(|x| - b, 0), oddness, continuity at +-b and slope 1
//                        outside (Lipschitz constant 1);
//   SmoothedVector       every entry the step response of the low-pass toward its target.
// The expected values are written from these formulas, never from the functions under test.
#include <phri/core/filters.hpp>
#include <phri/core/smoothed_vector.hpp>

#include "allocation_counter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

namespace {

using Complex = std::complex<double>;
constexpr double kDt = 1e-3;

// e^{-j w dt}: z^-1 on the unit circle.
Complex z_inverse(double w) { return std::polar(1.0, -w * kDt); }

// ------------------------------------------------------------------------------------ LowPassFilter
TEST(LowPassFilter, StepResponseIsOneMinusOneMinusAlphaToTheK) {
  const double T = 0.01;
  const double a = 1.0 / 11.0;  // dt / (T + dt) = 0.001 / 0.011
  phri::LowPassFilter filter(T, kDt);
  EXPECT_EQ(filter.value(), 0.0);
  for (int k = 1; k <= 300; ++k) {
    const double y = filter.update(1.0);
    ASSERT_NEAR(y, 1.0 - std::pow(1.0 - a, k), 1e-14) << k;
    ASSERT_EQ(filter.value(), y);
  }
  // One time constant (k = T / dt = 10 samples) reaches 1 - (10/11)^10 = 0.6145, the backward-Euler
  // counterpart of the continuous 1 - 1/e = 0.6321.
  phri::LowPassFilter again(T, kDt);
  for (int k = 0; k < 9; ++k) again.update(1.0);
  EXPECT_NEAR(again.update(1.0), 0.61445671, 1e-8);
}

TEST(LowPassFilter, ZeroTimeConstantAndDefaultPassTheInputThrough) {
  phri::LowPassFilter zero(0.0, kDt), unset;
  for (const double x : {3.0, -1.5, 0.0, 1e6}) {
    EXPECT_EQ(zero.update(x), x);
    EXPECT_EQ(unset.update(x), x);
  }
}

TEST(LowPassFilter, ResetValueDecaysGeometricallyTowardTheInput) {
  const double a = 1e-3 / (0.05 + 1e-3);
  phri::LowPassFilter filter(0.05, kDt);
  filter.reset(2.0);
  EXPECT_EQ(filter.value(), 2.0);
  for (int k = 1; k <= 100; ++k) ASSERT_NEAR(filter.update(-1.0), -1.0 + 3.0 * std::pow(1.0 - a, k), 1e-13) << k;
}

TEST(LowPassFilter, SinusoidalSteadyStateMatchesTheDiscreteTransferFunction) {
  const double T = 0.01, a = kDt / (T + kDt);
  for (const double w : {1.0, 30.0, 100.0, 1000.0}) {
    SCOPED_TRACE("w = " + std::to_string(w) + " rad/s");
    const Complex h = a / (1.0 - (1.0 - a) * z_inverse(w));
    phri::LowPassFilter filter(T, kDt);
    double worst = 0.0;
    for (int k = 0; k < 1200; ++k) {
      const double y = filter.update(std::sin(w * k * kDt));
      if (k >= 1000) {  // the transient (10/11)^k is below 1e-41 by then
        worst = std::max(worst, std::abs(y - (h * std::polar(1.0, w * k * kDt)).imag()));
      }
    }
    EXPECT_LT(worst, 1e-12);
    // Well below the sampling rate it is the continuous 1 / (1 + j w T), within O(w dt).
    if (w <= 100.0) {
      EXPECT_LT(std::abs(h - 1.0 / Complex(1.0, w * T)), 0.3 * w * kDt);
    }
  }
}

// ------------------------------------------------------------------------------ ComplementaryFilter
TEST(ComplementaryFilter, ConstantInputsConvergeToTheLowInputAsOneMinusGToTheK) {
  const double K = 50.0, g = 1.0 - std::exp(-K * kDt);
  phri::ComplementaryFilter filter(3, K, kDt);
  Eigen::VectorXd low(3), high(3);
  low << 1.0, -2.0, 3.0;
  high << 10.0, 5.0, -7.0;
  for (int k = 1; k <= 1000; ++k) {
    const Eigen::VectorXd& out = filter.update(low, high);
    const Eigen::VectorXd expected = low + high * std::pow(1.0 - g, k);
    ASSERT_LT((out - expected).cwiseAbs().maxCoeff(), 1e-12) << k;
    ASSERT_EQ(&out, &filter.value());
  }
  // After 1 s the transient is e^-50 of `high`: the output is `low` (to rounding of high - LP(high)).
  EXPECT_LT((filter.value() - low).cwiseAbs().maxCoeff(), 1e-13);
}

TEST(ComplementaryFilter, TheLowInputPassesUnchanged) {
  phri::ComplementaryFilter filter(2, 10.0, kDt);
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(2);
  for (int k = 0; k < 50; ++k) {
    const Eigen::Vector2d low(std::sin(0.3 * k), std::cos(0.7 * k) + k);
    EXPECT_EQ(filter.update(low, zero), Eigen::VectorXd(low));
  }
}

TEST(ComplementaryFilter, HighInputSeesTheAnalyticHighPassAtEachFrequency) {
  const double K = 50.0, g = 1.0 - std::exp(-K * kDt);
  for (const double w : {5.0, 50.0, 500.0, 2000.0}) {
    SCOPED_TRACE("w = " + std::to_string(w) + " rad/s");
    const Complex zi = z_inverse(w);
    const Complex h = (1.0 - g) * (1.0 - zi) / (1.0 - (1.0 - g) * zi);
    phri::ComplementaryFilter filter(1, K, kDt);
    const Eigen::VectorXd zero = Eigen::VectorXd::Zero(1);
    Eigen::VectorXd x(1);
    double worst = 0.0;
    for (int k = 0; k < 1200; ++k) {
      x[0] = std::sin(w * k * kDt);
      const double y = filter.update(zero, x)[0];
      if (k >= 1000) worst = std::max(worst, std::abs(y - (h * std::polar(1.0, w * k * kDt)).imag()));  // e^-50
    }
    EXPECT_LT(worst, 1e-12);
    // Below the sampling rate: the continuous high-pass s / (s + K), within a relative K dt / 2.
    if (w <= 500.0) {
      const Complex s(0.0, w), continuous = s / (s + K);
      EXPECT_LT(std::abs(h - continuous), 0.55 * K * kDt * std::abs(continuous));
    }
  }
  // At the crossover itself: continuous |H| = 1/sqrt(2) = 0.707 and +45 deg; discrete 0.690 and 45.0 deg.
  const Complex zi = z_inverse(K);
  const Complex h = (1.0 - g) * (1.0 - zi) / (1.0 - (1.0 - g) * zi);
  EXPECT_NEAR(std::abs(h), std::numbers::sqrt2 / 2.0, 0.02);
  EXPECT_NEAR(std::arg(h) * 180.0 / std::numbers::pi, 45.0, 0.1);
}

TEST(ComplementaryFilter, UpdateDoesNotAllocate) {
  phri::ComplementaryFilter filter(7, 50.0, kDt);
  const Eigen::VectorXd low = Eigen::VectorXd::Constant(7, 1.0), high = Eigen::VectorXd::Constant(7, 2.0);
  phri::test::AllocationCounter count;
  {
    phri::test::NoMallocScope no_malloc;
    for (int k = 0; k < 10; ++k) filter.update(low, high);
  }
  EXPECT_EQ(count.allocations(), 0u);
}

// ------------------------------------------------------------------------------------ soft_deadband
TEST(SoftDeadband, ValuesOutsideInsideAndAtTheEdges) {
  struct Case {
    double x, band, expected;
  };
  for (const Case& c : {Case{3.0, 1.0, 2.0}, Case{-3.0, 1.0, -2.0}, Case{0.5, 1.0, 0.0}, Case{-0.999, 1.0, 0.0},
                        Case{1.0, 1.0, 0.0}, Case{-1.0, 1.0, 0.0}, Case{1.25, 1.0, 0.25}, Case{0.0, 0.4, 0.0},
                        Case{-0.7, 0.4, -0.3}, Case{2.5, 0.0, 2.5}, Case{-2.5, 0.0, -2.5}}) {
    EXPECT_NEAR(phri::soft_deadband(c.x, c.band), c.expected, 1e-15) << "x " << c.x << ", band " << c.band;
  }
}

TEST(SoftDeadband, IsOddContinuousAtTheEdgesAndHasSlopeOneOutside) {
  const double band = 0.4;
  // Approaching +-band from either side: the output tends to 0 (no step at the edge).
  for (const double eps : {1e-3, 1e-6, 1e-9}) {
    EXPECT_NEAR(phri::soft_deadband(band + eps, band), eps, 1e-15);
    EXPECT_EQ(phri::soft_deadband(band - eps, band), 0.0);
    EXPECT_NEAR(phri::soft_deadband(-band - eps, band), -eps, 1e-15);
    EXPECT_EQ(phri::soft_deadband(-band + eps, band), 0.0);
  }
  // On a fine grid: odd, never larger than the input, Lipschitz with constant 1 (so continuous), and
  // exactly slope 1 outside the band.
  double previous_x = -2.0, previous_y = phri::soft_deadband(-2.0, band);
  for (int i = 1; i <= 4000; ++i) {
    const double x = -2.0 + 1e-3 * i, y = phri::soft_deadband(x, band);
    ASSERT_EQ(phri::soft_deadband(-x, band), -y) << x;
    ASSERT_LE(std::abs(y), std::abs(x)) << x;
    ASSERT_LE(std::abs(y - previous_y), (x - previous_x) * (1.0 + 1e-12)) << x;
    if (std::abs(x) > band && std::abs(previous_x) > band && x * previous_x > 0) {
      ASSERT_NEAR(y - previous_y, x - previous_x, 1e-12) << x;
    }
    previous_x = x;
    previous_y = y;
  }
}

TEST(SoftDeadband, VectorFormAppliesEachEntrysBandWithoutAllocating) {
  Eigen::VectorXd x(4), band(4), out(4);
  x << 2.0, -0.3, -5.0, 0.45;
  band << 1.0, 0.4, 0.4, 0.4;
  phri::test::AllocationCounter count;
  phri::soft_deadband(x, band, out);
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_NEAR(out[0], 1.0, 1e-15);
  EXPECT_EQ(out[1], 0.0);
  EXPECT_NEAR(out[2], -4.6, 1e-15);
  EXPECT_NEAR(out[3], 0.05, 1e-15);
}

// ----------------------------------------------------------------------------------- SmoothedVector
TEST(SmoothedVector, EachEntryFollowsTheLowPassStepResponseTowardItsTarget) {
  const double T = 0.1, a = kDt / (T + kDt);
  Eigen::VectorXd initial(3), target(3);
  initial << 1.0, 0.0, -2.0;
  target << 4.0, 0.0, 2.0;
  phri::SmoothedVector v(initial, T);
  EXPECT_EQ(v.value(), initial);
  v.set_target(target);
  EXPECT_EQ(v.target(), target);
  EXPECT_EQ(v.value(), initial) << "a new target does not move the value before a step";
  for (int k = 1; k <= 500; ++k) {
    v.step(kDt);
    const Eigen::VectorXd expected = target + (initial - target) * std::pow(1.0 - a, k);
    ASSERT_LT((v.value() - expected).cwiseAbs().maxCoeff(), 1e-12) << k;
  }
  // A slower time constant from here on: the remaining distance shrinks by (1 - a2) per step.
  const Eigen::VectorXd from = v.value();
  const double a2 = kDt / (0.5 + kDt);
  v.set_time_constant(0.5);
  v.set_target_constant(-1.0);
  for (int k = 1; k <= 100; ++k) v.step(kDt);
  const Eigen::VectorXd expected =
      Eigen::VectorXd::Constant(3, -1.0) + (from - Eigen::VectorXd::Constant(3, -1.0)) * std::pow(1.0 - a2, 100);
  EXPECT_LT((v.value() - expected).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(SmoothedVector, ZeroTimeConstantJumpsAndResetSetsValueAndTarget) {
  phri::SmoothedVector v(Eigen::VectorXd::Zero(2), 0.0);
  v.set_target(Eigen::Vector2d(3.0, -4.0));
  v.step(kDt);
  EXPECT_EQ(v.value(), Eigen::VectorXd(Eigen::Vector2d(3.0, -4.0)));
  phri::SmoothedVector w(Eigen::VectorXd::Zero(2), 0.2);
  w.set_target(Eigen::Vector2d(1.0, 1.0));
  w.reset(Eigen::Vector2d(-1.0, 2.0));
  EXPECT_EQ(w.value(), Eigen::VectorXd(Eigen::Vector2d(-1.0, 2.0)));
  EXPECT_EQ(w.target(), w.value());
  w.step(kDt);
  EXPECT_EQ(w.value(), Eigen::VectorXd(Eigen::Vector2d(-1.0, 2.0))) << "at its target: it stays";
}

TEST(SmoothedVector, FixedSizeTargetsAndStepsDoNotAllocate) {
  phri::SmoothedVector v(Eigen::VectorXd::Zero(6), 0.1);
  const Eigen::Matrix<double, 6, 1> target = Eigen::Matrix<double, 6, 1>::Constant(2.0);
  phri::test::AllocationCounter count;
  {
    phri::test::NoMallocScope no_malloc;
    v.set_target(target);
    v.step(kDt);
    v.set_target_constant(1.0);
    v.step(kDt);
    v.reset(target);
  }
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_EQ(v.value(), Eigen::VectorXd(target));
}

}  // namespace
