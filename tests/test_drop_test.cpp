// ctest-labels: physics evaluate
// The drop-test experiment (experiments/drop_test.hpp): its metrics against the closed form of an
// exponential decay, and a short run whose catch comes after a free fall over the cable's slack.
#include <phri/core/error.hpp>
#include <phri/experiments/drop_test.hpp>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;

// e(t) = A exp(-t / tau) + r: peak A + r, residual r (the decay is gone by the last second),
// stabilisation in an absolute band b where A exp(-t / tau) falls to b: t = tau ln(A / b).
TEST(DropMetrics, ExponentialDecayMatchesItsClosedForm) {
  const double dt = 1e-3, a = 3.0, r = 0.2, tau = 0.15, band = 0.1;
  std::vector<float> e;
  for (int k = 0; k < 6000; ++k) e.push_back(static_cast<float>(a * std::exp(-k * dt / tau) + r));
  double peak = 0, residual = 0;
  phri::drop_metrics(e, dt, 1.0, peak, residual);
  EXPECT_NEAR(peak, a + r, 1e-6);
  EXPECT_NEAR(residual, r, 1e-6);
  const phri::Stabilisation s = phri::drop_stabilisation(e, dt, 1.0, band);
  EXPECT_FALSE(s.censored);
  EXPECT_NEAR(s.time_s, tau * std::log(a / band), 2 * dt);
}

// A slowly decaying swing (1 Hz, amplitude 3 exp(-t / 2) mm: 0.25 mm at 5 s) still outside a 0.1 mm
// band when the last second starts is censored at window - 1 s, never reported as a settling time;
// the same trace settles in a 1 mm band.
TEST(DropMetrics, NotSettledInTheWindowIsCensored) {
  const double dt = 1e-3, a = 3.0, tau = 2.0;
  std::vector<float> e;
  for (int k = 0; k < 6000; ++k) e.push_back(static_cast<float>(a * std::exp(-k * dt / tau) * std::cos(2 * M_PI * k * dt)));
  const phri::Stabilisation narrow = phri::drop_stabilisation(e, dt, 1.0, 0.1);
  EXPECT_TRUE(narrow.censored);
  EXPECT_NEAR(narrow.time_s, 5.0, dt);
  const phri::Stabilisation wide = phri::drop_stabilisation(e, dt, 1.0, 1.0);
  EXPECT_FALSE(wide.censored);
  EXPECT_LT(wide.time_s, 5.0);
}

// A negative error counts by its magnitude; an error that never leaves the band settles at once.
TEST(DropMetrics, SignAndAlreadySettled) {
  std::vector<float> e(3000, -0.5f);
  double peak = 0, residual = 0;
  phri::drop_metrics(e, 1e-3, 1.0, peak, residual);
  EXPECT_NEAR(peak, 0.5, 1e-6);
  EXPECT_NEAR(residual, 0.5, 1e-6);
  const phri::Stabilisation s = phri::drop_stabilisation(e, 1e-3, 1.0, 0.1);
  EXPECT_EQ(s.time_s, 0.0);
  EXPECT_FALSE(s.censored);
}

// One drop per mode, short: the catch comes a free fall of the slack length after the release,
// t = sqrt(2 (L + dz) / g) with |dz| at most the release's vertical spread.
TEST(DropTest, CatchFollowsAFreeFallAndBothModesRecover) {
  phri::DropTestOptions o;
  for (std::string* p : {&o.plant_config_path, &o.urdf_path, &o.actuators_path, &o.collision_path}) *p = kRoot + "/" + *p;
  o.output_dir.clear();
  o.figure_script.clear();
  o.drops = 1;
  o.release_s = 2.0;
  o.window_s = 2.0;
  const phri::DropTestResult r = phri::run_drop_test(o);
  ASSERT_EQ(r.runs.size(), 2u);
  const double spread = 0.02, length = 0.25, g = 9.81;
  for (const phri::DropRun& d : r.runs) {
    const double fall = d.catch_s - o.release_s;
    EXPECT_GT(fall, std::sqrt(2 * (length - spread) / g) - 2e-3) << to_string(d.mode);
    EXPECT_LT(fall, std::sqrt(2 * (length + spread) / g) + 2e-3) << to_string(d.mode);
    EXPECT_GT(d.peak_mm, 0.05);          // the catch moves the end effector
    EXPECT_LT(d.residual_mm, d.peak_mm);  // and it comes back
    EXPECT_EQ(d.qp_fallbacks, 0);
    EXPECT_EQ(d.invalid_reason(), "") << to_string(d.mode);  // no safe stop, no fallback, the mode's own loop
    EXPECT_EQ(d.loop_ran, d.mode == phri::DropMode::kTorque ? "custom" : "position");
    std::printf("%s: catch %.3f s after release, peak %.3f mm, stabilisation %.3f s, residual %.4f mm\n",
                to_string(d.mode), fall, d.peak_mm, d.stabilisation_s, d.residual_mm);
  }
}

TEST(DropTest, BadOptionsNameTheField) {
  phri::DropTestOptions o;
  o.drops = 0;
  EXPECT_THROW(phri::run_drop_test(o), phri::ConfigError);
  o.drops = 1;
  o.release_s = 0.5;
  EXPECT_THROW(phri::run_drop_test(o), phri::ConfigError);
}

}  // namespace
