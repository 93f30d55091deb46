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

#include <algorithm>
#include <cmath>
#include <string>

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

// The whole current law against hand-computed values from actuators.yaml's numbers (K_T G_r 11 and
// 7.6 N.m/A, I_r G_r^2 0.03 kg.m^2, friction 2.15 + 2.00 qd (large) and 1.60 + 1.36 qd (small),
// thresholds 0.1 rad/s and 1 rad/s^2, integrator clamp 5 % of 95 / 26 / 45 N.m) and the paper's
// H(z) = (0.020175 - 0.036975 z^-1 + 0.016917 z^-2) / (1 - 1.975063 z^-1 + 0.97518 z^-2), for a
// constant torque error e = tau_d - tau_s: its first two output samples b0 e and
// (b0 + b1 - a1 b0) e, and after 6 s (slow pole 0.9937: the transient is down by e^-37) its DC
// value H(1) e (both coefficient sums cancel to 1.17e-4: rounding leaves ~1e-12, hence 1e-9);
// the leaky integrator's ZOH samples (K_I / theta) e (1 - exp(-theta k T)), or its clamp.
TEST_F(CustomLoop, CurrentLawMatchesHandComputedTermsAtStartAndInSteadyState) {
  phri::CustomTorqueSettings s;  // lambda 5, K_I 20, theta 1, clamp 5 %, both feed-forwards
  phri::CustomTorqueController loop(table_, s);
  Eigen::VectorXd tau_d(7), qdd(7), tau_s(7), qd(7);
  tau_d << 10, -5, 3, 8, 1, -0.5, 0.2;
  qdd << 2, -1.5, 0.3, 0.5, 4, -0.2, 0.1;
  tau_s = tau_d * 0.9;  // e = 0.1 tau_d
  qd << 0.5, -0.01, 0.0, 0.2, -0.05, 0.0, 0.3;
  const double e[7] = {1.0, -0.5, 0.3, 0.8, 0.1, -0.05, 0.02};
  // Friction, case by case: sliding (|qd| >= 0.1): coulomb sign(qd) + viscous qd; static
  // (|qd| < 0.1, |qdd_d| >= 1): static sign(qdd_d); otherwise none.
  const double friction[7] = {2.15 + 2.0 * 0.5, -2.15, 0.0, 2.15 + 2.0 * 0.2, 1.60, 0.0, 1.60 + 1.36 * 0.3};
  const phri::FrictionCase cases[7] = {phri::FrictionCase::kSliding, phri::FrictionCase::kStatic,
                                       phri::FrictionCase::kNone,    phri::FrictionCase::kSliding,
                                       phri::FrictionCase::kStatic,  phri::FrictionCase::kNone,
                                       phri::FrictionCase::kSliding};
  const double torque_per_amp[7] = {11.0, 11.0, 11.0, 11.0, 7.6, 7.6, 7.6};
  const double clamp[7] = {0.05 * 95, 0.05 * 95, 0.05 * 95, 0.05 * 95, 0.05 * 26, 0.05 * 45, 0.05 * 26};
  const double b0 = 0.020175, b1 = -0.036975, b2 = 0.016917, a1 = -1.975063, a2 = 0.97518;
  const double h_dc = (b0 + b1 + b2) / (1.0 + a1 + a2);

  // k: number of updates; h: H(z)'s response to a unit step after k samples.
  auto check = [&](int k, double h) {
    for (int i = 0; i < 7; ++i) {
      SCOPED_TRACE("joint " + std::to_string(i + 1) + " after " + std::to_string(k) + " periods");
      const double integral = std::clamp(20.0 * e[i] * (1.0 - std::exp(-1e-3 * k)), -clamp[i], clamp[i]);
      const double torque = tau_d[i] + 0.03 * qdd[i] + friction[i] + 5.0 * h * e[i] + integral;
      EXPECT_NEAR(loop.friction_term()[i], friction[i], 1e-12);
      EXPECT_EQ(loop.friction_cases()[static_cast<std::size_t>(i)], cases[i]);
      EXPECT_NEAR(loop.rotor_term()[i], 0.03 * qdd[i], 1e-12);
      EXPECT_NEAR(loop.filter_term()[i], 5.0 * h * e[i], 1e-9);
      EXPECT_NEAR(loop.integral_term()[i], integral, 1e-9);
      EXPECT_NEAR(loop.current()[i], torque / torque_per_amp[i], 1e-9);
    }
  };
  loop.update(tau_d, qdd, tau_s, qd);
  check(1, b0);
  loop.update(tau_d, qdd, tau_s, qd);
  check(2, b0 + b1 - a1 * b0);
  for (int k = 3; k <= 6000; ++k) loop.update(tau_d, qdd, tau_s, qd);
  check(6000, h_dc);
  // Nothing saturated: the largest command, joint 1, is 10 + 0.06 + 3.15 + 5 + 4.75 N.m << 105 N.m.
  EXPECT_EQ(loop.saturated_count(), 0);
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

// A joint at rest that the previous loop held against static friction: the entry keeps the
// present current (the integrator carries the gap), but once the joint slides, the friction share
// of that gap leaves the integrator: the friction compensation supplies it from then on. (Carried
// on with the integrator's 1 s leak, it added to the compensation and ran a joint of the safety
// fuzz's warm-up away at 1.25 rad/s, seed 20261127.)
TEST_F(CustomLoop, FrictionHoldAtEntryIsNotCarriedIntoSliding) {
  const phri::CustomTorqueSettings settings;
  const double leak = std::exp(-settings.integral_leak * settings.period_s);
  const double input = settings.integral_gain * (1.0 - leak) / settings.integral_leak;
  Eigen::VectorXd load(7), hold(7), current_now(7), tau_s(7);
  load << 3.0, -20.0, 1.5, 8.0, -0.4, 1.2, 0.05;
  tau_s = load + Eigen::VectorXd::Constant(7, 0.1);  // a sensor offset: not friction
  for (int i = 0; i < 7; ++i) {
    // Joints 1-6 held within the friction band; joint 7 beyond it (a drive constant off).
    const double share = i == 6 ? 3.0 : (i % 2 == 0 ? 0.9 : -0.9);
    hold[i] = share * table_[i].friction.static_Nm;
    current_now[i] = (tau_s[i] + hold[i]) / table_[i].torque_per_amp();
  }
  phri::CustomTorqueController loop(table_, settings);
  loop.reset(current_now, load, zero_, tau_s, zero_);
  EXPECT_LT((loop.current() - current_now).cwiseAbs().maxCoeff(), 1e-12);  // no current step
  // The entry hold: the gap less what the sensor sees, at most the static friction level (it
  // differs from `hold` by H(z)'s and the integrator's first outputs on the 0.1 N.m error).
  const Eigen::VectorXd hold0 = loop.entry_hold(), integral0 = loop.integral_term();
  for (int i = 0; i < 6; ++i) EXPECT_NEAR(hold0[i], hold[i], 0.02) << "joint " << i + 1;
  EXPECT_DOUBLE_EQ(hold0[6], table_[6].friction.static_Nm);
  // At rest nothing changes: the hold is a share of the integrator and leaks with it.
  phri::CustomTorqueController at_rest(table_, settings);
  at_rest.reset(current_now, load, zero_, tau_s, zero_);
  for (int k = 0; k < 250; ++k) at_rest.update(load, zero_, tau_s, zero_);
  for (int i = 0; i < 7; ++i) EXPECT_NEAR(at_rest.entry_hold()[i], hold0[i] * std::pow(leak, 250), 1e-12);
  // Sliding from the next sample on: the integrator drops the hold, so the command is
  // tau_d + friction model + H(z) + the integrator without the friction share.
  const Eigen::VectorXd qd = Eigen::VectorXd::Constant(7, -0.3);
  loop.update(load, zero_, tau_s, qd);
  for (int i = 0; i < 7; ++i) {
    const auto& f = table_[i].friction;
    const double integral = leak * (integral0[i] - hold0[i]) + input * (load[i] - tau_s[i]);
    const double expected = load[i] + (-f.coulomb_Nm - 0.3 * f.viscous_Nms_per_rad) + loop.filter_term()[i] + integral;
    EXPECT_NEAR(loop.torque_command()[i], expected, 1e-12) << "joint " << i + 1;
    EXPECT_EQ(loop.entry_hold()[i], 0.0);
  }
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

namespace {

// The vendor loops' breakaway feed-forward (low_level_controller.hpp): a stuck joint asked to
// accelerate beyond the friction model's threshold gets half its static friction added to tau_d in
// the direction asked; a moving joint, or one asked for less, gets nothing.
TEST(VendorLoops, BreakawayFeedForwardOnlyForAStuckJointAskedToMove) {
  const phri::ActuatorTable table = phri::ActuatorTable::from_yaml_file(kActuators);
  phri::LowLevelController low(table, phri::CustomTorqueSettings{}, phri::LowLevelMode::kKinovaTorque);
  phri::RobotState state(7);
  state.q_rad.setZero();
  state.qd_rad_s.setZero();
  state.qd_rad_s[2] = 0.5;  // joint 3 slides
  state.tau_sensor_Nm.setZero();
  state.current.valid = false;
  Eigen::VectorXd tau_d = Eigen::VectorXd::Zero(7), qdd = Eigen::VectorXd::Zero(7);
  qdd[0] = 5.0;   // stuck, asked to move: + half its static friction
  qdd[1] = -5.0;  // the other way
  qdd[2] = 5.0;   // moving: nothing
  qdd[3] = 0.5;   // below the 1 rad/s^2 threshold: nothing
  phri::RobotCommand command(7);
  low.enable_breakaway_ramp(false);  // the base share (the ramp has its own test)
  for (int k = 0; k < 400; ++k) low.update(state, tau_d, qdd, command);  // the entry offset fades (50 ms)
  const double half = phri::LowLevelController::kVendorBreakawayShare;
  EXPECT_NEAR(command.tau_Nm[0], half * table[0].friction.static_Nm, 1e-6);
  EXPECT_NEAR(command.tau_Nm[1], -half * table[1].friction.static_Nm, 1e-6);
  EXPECT_NEAR(command.tau_Nm[2], 0.0, 1e-6);
  EXPECT_NEAR(command.tau_Nm[3], 0.0, 1e-6);
}

// Entering a Kinova torque loop while a drive carries its full current, with the breakaway
// feed-forward on top: tau_d + entry offset + breakaway would exceed what the drive can give, a
// set-point the robot refuses (SimRobot::validate, Kortex); the command is held at the range.
TEST(VendorLoops, TorqueSetPointStaysWithinTheDrivesRangeAtAFullCurrentEntry) {
  const phri::ActuatorTable table = phri::ActuatorTable::from_yaml_file(kActuators);
  phri::LowLevelController low(table, phri::CustomTorqueSettings{}, phri::LowLevelMode::kKinovaTorqueHighVelocity);
  phri::RobotState state(7);
  state.q_rad.setZero();
  state.qd_rad_s.setZero();
  state.tau_sensor_Nm.setZero();
  state.current.valid = true;
  state.current_A = Eigen::VectorXd::Zero(7);
  state.current_A[6] = table[6].current_limit_A;  // joint 7 at its full current
  Eigen::VectorXd tau_d = Eigen::VectorXd::Zero(7), qdd = Eigen::VectorXd::Zero(7);
  qdd[6] = 5.0;  // stuck and asked to move: the breakaway share is added
  phri::RobotCommand command(7);
  low.update(state, tau_d, qdd, command);
  const double range = table[6].max_motor_torque_Nm();
  const double unsaturated = range + phri::LowLevelController::kVendorBreakawayShare * table[6].friction.static_Nm;
  ASSERT_GT(unsaturated, range);
  EXPECT_DOUBLE_EQ(command.tau_Nm[6], range);
  for (int i = 0; i < 7; ++i) EXPECT_LE(std::abs(command.tau_Nm[i]), table[i].max_motor_torque_Nm()) << "joint " << i + 1;
}

// A 7-joint arm at rest at zero, no torque, no current reading.
phri::RobotState resting_state() {
  phri::RobotState state(7);
  state.q_rad.setZero();
  state.qd_rad_s.setZero();
  state.tau_sensor_Nm.setZero();
  state.current.valid = false;
  return state;
}

TEST(VendorLoops, BreakawayShareGrowsWhileAJointStaysStuckAndStartsAgainWhenItMoves) {
  const phri::ActuatorTable table = phri::ActuatorTable::from_yaml_file(kActuators);
  phri::LowLevelController low(table, phri::CustomTorqueSettings{}, phri::LowLevelMode::kKinovaTorque);
  phri::RobotState state = resting_state();
  Eigen::VectorXd tau_d = Eigen::VectorXd::Zero(7), qdd = Eigen::VectorXd::Zero(7);
  qdd[4] = 5.0;  // joint 5 stuck, asked to move
  phri::RobotCommand command(7);
  const double base = phri::LowLevelController::kVendorBreakawayShare;
  const double rate = phri::LowLevelController::kBreakawayShareRate_per_s;
  const double fs = table[4].friction.static_Nm;
  for (int k = 0; k < 300; ++k) low.update(state, tau_d, qdd, command);
  // First cycle at the base share, then + rate * dt per cycle: 299 cycles of growth.
  EXPECT_NEAR(low.breakaway()[4], std::min(base + rate * 0.299, 1.0) * fs, 1e-9);
  for (int k = 0; k < 2000; ++k) low.update(state, tau_d, qdd, command);
  EXPECT_NEAR(low.breakaway()[4], fs, 1e-12);  // never beyond the whole static friction
  state.qd_rad_s[4] = 0.5;  // it breaks free: nothing while it slides
  low.update(state, tau_d, qdd, command);
  EXPECT_EQ(low.breakaway()[4], 0.0);
  state.qd_rad_s[4] = 0.0;  // stuck again: from the base share
  low.update(state, tau_d, qdd, command);
  EXPECT_NEAR(low.breakaway()[4], base * fs, 1e-12);
  qdd[4] = -5.0;  // asked the other way: from the base share, the other sign
  low.update(state, tau_d, qdd, command);
  EXPECT_NEAR(low.breakaway()[4], -base * fs, 1e-12);
}

// A joint the vendor loop leaves crawling (its velocity feedback, friction it does not compensate)
// keeps the assist while it slides slowly the way the task still accelerates it: a share of the
// Coulomb friction along the motion, growing like the breakaway share; nothing when the task
// brakes it, above kSlowSlideFactor times the velocity threshold, or with the ramp off.
TEST(VendorLoops, FrictionAssistFollowsASlowSlideTheTaskStillAccelerates) {
  const phri::ActuatorTable table = phri::ActuatorTable::from_yaml_file(kActuators);
  phri::LowLevelController low(table, phri::CustomTorqueSettings{}, phri::LowLevelMode::kKinovaTorque);
  phri::RobotState state = resting_state();
  Eigen::VectorXd tau_d = Eigen::VectorXd::Zero(7), qdd = Eigen::VectorXd::Zero(7);
  phri::RobotCommand command(7);
  const phri::FrictionParameters& f = table[5].friction;
  const double base = phri::LowLevelController::kVendorBreakawayShare;
  const double rate = phri::LowLevelController::kBreakawayShareRate_per_s;
  const double slow = 0.5 * (1.0 + phri::LowLevelController::kSlowSlideFactor) * f.velocity_threshold_rad_s;
  qdd[5] = -5.0;
  low.update(state, tau_d, qdd, command);  // stuck, asked negative: breakaway at the base share
  EXPECT_NEAR(low.breakaway()[5], -base * f.static_Nm, 1e-12);
  state.qd_rad_s[5] = -slow;  // sliding slowly the same way: the share goes on growing, on Coulomb
  low.update(state, tau_d, qdd, command);
  EXPECT_NEAR(low.breakaway()[5], -(base + rate * 1e-3) * f.coulomb_Nm, 1e-12);
  EXPECT_NEAR(command.tau_Nm[5], low.breakaway()[5], 1e-12);  // tau_d = 0, entry offset tau_s - tau_d = 0
  qdd[5] = 5.0;  // the task brakes the slide: nothing
  low.update(state, tau_d, qdd, command);
  EXPECT_EQ(low.breakaway()[5], 0.0);
  qdd[5] = -5.0;
  state.qd_rad_s[5] = -1.01 * phri::LowLevelController::kSlowSlideFactor * f.velocity_threshold_rad_s;  // fast
  low.update(state, tau_d, qdd, command);
  EXPECT_EQ(low.breakaway()[5], 0.0);
  state.qd_rad_s[5] = -slow;  // slow again, from the base share
  low.update(state, tau_d, qdd, command);
  EXPECT_NEAR(low.breakaway()[5], -base * f.coulomb_Nm, 1e-12);
  low.enable_breakaway_ramp(false);  // dual compliance, placed by hand: the breakaway case only
  low.update(state, tau_d, qdd, command);
  EXPECT_EQ(low.breakaway()[5], 0.0);
}

}  // namespace

// A loop entered from the drives' current starts from its average over the cycles before the
// switch (first order, kEntryCurrentTime_s), so one noisy sample is not held as an offset: closed
// forms for the custom loop's first current, a vendor loop's first set-point, and the average's
// restart after a hold (the first reading then counts whole).
TEST(LoopEntry, StartsFromTheMeasuredCurrentAveragedBeforeTheSwitchNotItsLastSample) {
  const phri::ActuatorTable table = phri::ActuatorTable::from_yaml_file(kActuators);
  const phri::CustomTorqueSettings settings;
  const double weight = settings.period_s / (phri::LowLevelController::kEntryCurrentTime_s + settings.period_s);
  const Eigen::VectorXd tau_d = Eigen::VectorXd::Zero(7), qdd = Eigen::VectorXd::Zero(7);
  Eigen::VectorXd steady(7), spike(7);
  for (int i = 0; i < 7; ++i) {
    steady[i] = 0.05 + 0.01 * i;
    spike[i] = i % 2 == 0 ? 0.05 : -0.03;
  }
  for (const phri::LowLevelMode loop : {phri::LowLevelMode::kCurrent, phri::LowLevelMode::kKinovaTorque}) {
    SCOPED_TRACE(std::string(phri::to_string(loop)));
    phri::LowLevelController low(table, settings, phri::LowLevelMode::kPosition);
    phri::RobotState state = resting_state();
    state.current.valid = true;
    state.current_A = steady;
    phri::RobotCommand command(7);
    for (int k = 0; k < 400; ++k) low.update(state, tau_d, qdd, command);
    state.current_A = steady + spike;  // the switch cycle's sample is off by the spike
    low.request(loop);
    low.update(state, tau_d, qdd, command);
    ASSERT_EQ(command.mode, loop);
    for (int i = 0; i < 7; ++i) {
      const double entry = steady[i] + weight * spike[i];  // the average: the spike enters by its weight
      if (loop == phri::LowLevelMode::kCurrent) {
        EXPECT_NEAR(command.current_A[i], entry, 1e-12) << "joint " << i + 1;
      } else {
        EXPECT_NEAR(command.tau_Nm[i], table[i].torque_per_amp() * entry, 1e-12) << "joint " << i + 1;
      }
    }
    // A hold starts the average again: the next entry reads the first sample after it whole.
    low.hold(state.q_rad, command);
    const Eigen::VectorXd after = steady - spike;
    state.current_A = after;
    low.request(loop);
    low.update(state, tau_d, qdd, command);
    for (int i = 0; i < 7; ++i) {
      if (loop == phri::LowLevelMode::kCurrent) {
        EXPECT_NEAR(command.current_A[i], after[i], 1e-12) << "joint " << i + 1;
      } else {
        EXPECT_NEAR(command.tau_Nm[i], table[i].torque_per_amp() * after[i], 1e-12) << "joint " << i + 1;
      }
    }
  }
}
