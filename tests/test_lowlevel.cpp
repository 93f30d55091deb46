// ctest-labels: unit
// The custom low-level torque loop against closed forms: the friction model's three cases at and
// around its thresholds, the leaky integrator's ZOH response and leak, the whole current law, the
// current saturation with anti-windup, bumpless entry, zero allocation.
#include <phri/core/error.hpp>
#include <phri/lowlevel/custom_torque_controller.hpp>
#include <phri/lowlevel/low_level_controller.hpp>

#include "allocation_counter.hpp"
#include "config_error.hpp"

#include <gtest/gtest.h>

namespace {

const std::string kActuators = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/actuators.yaml";

TEST(FrictionCompensation, ThreeCasesAtAndAroundTheThresholds) {
  phri::FrictionParameters p;
  p.coulomb_Nm = 2.15;
  p.viscous_Nms_per_rad = 2.0;
  p.static_Nm = 2.4;
  p.velocity_threshold_rad_s = 0.1;
  p.acceleration_threshold_rad_s2 = 1.0;
  phri::FrictionCase which;
  // Sliding, at and above the velocity threshold, both directions.
  EXPECT_DOUBLE_EQ(phri::friction_compensation(p, 0.1, 0.0, &which), 2.15 + 0.2);
  EXPECT_EQ(which, phri::FrictionCase::kSliding);
  EXPECT_DOUBLE_EQ(phri::friction_compensation(p, -0.5, 5.0, &which), -2.15 - 1.0);  // velocity wins
  // Just below the velocity threshold: the desired acceleration decides.
  EXPECT_DOUBLE_EQ(phri::friction_compensation(p, 0.0999, 1.0, &which), 2.4);
  EXPECT_EQ(which, phri::FrictionCase::kStatic);
  EXPECT_DOUBLE_EQ(phri::friction_compensation(p, 0.05, -3.0, &which), -2.4);  // against the motion: breakaway asked
  EXPECT_DOUBLE_EQ(phri::friction_compensation(p, 0.0, 0.999, &which), 0.0);
  EXPECT_EQ(which, phri::FrictionCase::kNone);
  EXPECT_DOUBLE_EQ(phri::friction_compensation(p, -0.0999, -0.5, &which), 0.0);
}

class CustomLoop : public ::testing::Test {
protected:
  phri::ActuatorTable table_ = phri::ActuatorTable::from_yaml_file(kActuators);
  Eigen::VectorXd zero_ = Eigen::VectorXd::Zero(7);
};

TEST_F(CustomLoop, CurrentLawIsTheSumOfItsTermsOverKtGr) {
  phri::CustomTorqueSettings s;
  phri::CustomTorqueController loop(table_, s);
  phri::DiscreteTransferFunction reference = phri::DiscreteTransferFunction::kinova_high_velocity();
  Eigen::VectorXd tau_d(7), qdd(7), tau_s(7), qd(7);
  tau_d << 10, -5, 3, 8, 1, -0.5, 0.2;
  qdd << 2, -1.5, 0.3, 0.5, 4, -0.2, 0.1;
  tau_s = tau_d * 0.9;
  qd << 0.5, -0.01, 0.0, 0.2, -0.05, 0.0, 0.3;
  const double a = std::exp(-s.integral_leak * s.period_s);
  double integral = 0.0;
  for (int k = 0; k < 20; ++k) {
    loop.update(tau_d, qdd, tau_s, qd);
    const double e = tau_d[0] - tau_s[0];
    const double y = reference.step(e);
    integral = a * integral + s.integral_gain * (1.0 - a) / s.integral_leak * e;
    const auto& j = table_[0];
    const double friction = phri::friction_compensation(j.friction, qd[0], qdd[0]);
    const double expected = (tau_d[0] + j.reflected_inertia_kgm2 * qdd[0] + friction + s.transfer_gain * y + integral) /
                            j.torque_per_amp();
    EXPECT_NEAR(loop.current()[0], expected, 1e-12);
  }
  // Joint 2 (|qd| < threshold, |qdd_d| > threshold): the static case, against the motion asked.
  EXPECT_EQ(loop.friction_cases()[1], phri::FrictionCase::kStatic);
  EXPECT_DOUBLE_EQ(loop.friction_term()[1], -table_[1].friction.static_Nm);
}

TEST_F(CustomLoop, LeakyIntegratorStepResponseAndLeak) {
  phri::CustomTorqueSettings s;
  s.transfer_gain = 0.0;
  s.friction_compensation = false;
  s.rotor_inertia_compensation = false;
  s.integral_limit_fraction = 1.0;  // no clamp in this test
  phri::CustomTorqueController loop(table_, s);
  Eigen::VectorXd tau_d = Eigen::VectorXd::Constant(7, 0.5), tau_s = zero_;
  // Constant error e: x[k] = (K_I / theta) e (1 - a^k) with a = exp(-theta T), the samples of
  // the continuous step response (ZOH is exact for an error held over each period).
  const double a = std::exp(-s.integral_leak * s.period_s);
  for (int k = 1; k <= 2000; ++k) {
    loop.update(tau_d, zero_, tau_s, zero_);
    const double expected = s.integral_gain / s.integral_leak * 0.5 * (1.0 - std::pow(a, k));
    ASSERT_NEAR(loop.integral_term()[0], expected, 1e-9) << k;
  }
  // Error gone: the integral leaks away with time constant 1 / theta.
  const double start = loop.integral_term()[0];
  for (int k = 0; k < 1000; ++k) loop.update(tau_s, zero_, tau_s, zero_);
  EXPECT_NEAR(loop.integral_term()[0] / start, std::exp(-s.integral_leak * 1.0), 1e-9);
}

TEST_F(CustomLoop, SaturatesCurrentWithoutWindUp) {
  phri::CustomTorqueSettings s;
  s.integral_limit_fraction = 1.0;
  phri::CustomTorqueController loop(table_, s);
  Eigen::VectorXd tau_d = Eigen::VectorXd::Constant(7, 500.0);  // far beyond the drives
  for (int k = 0; k < 500; ++k) loop.update(tau_d, zero_, zero_, zero_);
  for (int i = 0; i < 7; ++i) EXPECT_DOUBLE_EQ(loop.current()[i], table_[i].current_limit_A);
  EXPECT_EQ(loop.saturated_count(), 7);
  // The integrator did not grow while the current was saturated (anti-windup); without the
  // clamp it would be at K_I / theta * 500 * (1 - e^-0.5) = 3935 N.m.
  EXPECT_LT(loop.integral_term().cwiseAbs().maxCoeff(), 1e-9);
}

TEST_F(CustomLoop, BumplessEntryAndNoAllocation) {
  phri::CustomTorqueController loop(table_, phri::CustomTorqueSettings{});
  Eigen::VectorXd current_now(7), tau_d(7), tau_s(7), qd = Eigen::VectorXd::Constant(7, 0.01);
  current_now << 1.0, -0.5, 0.2, 0.8, 0.05, -0.1, 0.02;
  tau_d << 12, -4, 2, 9, 0.5, -0.8, 0.1;
  tau_s = tau_d;
  loop.reset(current_now, tau_d, zero_, tau_s, qd);
  // The first output is the current the drives carried (within the integrator's clamp).
  EXPECT_LT((loop.current() - current_now).cwiseAbs().maxCoeff(), 1e-12);
  Eigen::VectorXd previous = loop.current();
  double max_change = 0.0;
  phri::test::AllocationCounter count;
  for (int k = 0; k < 100; ++k) {
    loop.update(tau_d, zero_, tau_s, qd);
    max_change = std::max(max_change, (loop.current() - previous).cwiseAbs().maxCoeff());
    previous = loop.current();
  }
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_LT(max_change, 0.05);  // A: the integrator leaks the entry offset away, no jump
}

TEST_F(CustomLoop, RejectsBadSettingsNamingTheKey) {
  using phri::test::expect_config_error;
  phri::CustomTorqueSettings s;
  s.integral_leak = 0.0;
  expect_config_error([&] { phri::CustomTorqueController(table_, s); },
                      {.element = "integral_leak", .mentions = {"> 0"}});
  s = {};
  s.transfer_gain = -1.0;
  expect_config_error([&] { phri::CustomTorqueController(table_, s); },
                      {.element = "transfer_gain", .mentions = {">= 0"}});
  s = {};
  s.integral_limit_fraction = 1.5;
  expect_config_error([&] { phri::CustomTorqueController(table_, s); }, {.element = "integral_limit_fraction"});
}

}  // namespace
