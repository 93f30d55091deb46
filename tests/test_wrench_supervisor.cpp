// ctest-labels: unit
// The F/T wrench's plausibility (safety/wrench_supervisor.hpp): each check alone on made-up samples.
#include <phri/core/error.hpp>
#include <phri/safety/wrench_supervisor.hpp>

#include "allocation_counter.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace {

using phri::WrenchStatus;
using Vector6 = Eigen::Matrix<double, 6, 1>;

// ---------------------------------------------------------------- the checks alone

constexpr double kT = 1e-3;
constexpr double kObserverGain = 50.0;

// A 1 kHz stream of joint samples with an F/T sample every `every` cycles.
struct Stream {
  phri::RobotState state{7};
  Eigen::VectorXd qd = Eigen::VectorXd::Zero(7);
  Eigen::VectorXd observer = Eigen::VectorXd::Zero(7);
  long k = 0;
  int every = 1;
  double noise = 0.05;

  // The next cycle; a new F/T sample on every `every`-th (noisy around `w`).
  const phri::RobotState& next(const Vector6& w) {
    ++k;
    state.joints.stamp_s = static_cast<double>(k) * kT;
    state.time_s = state.joints.stamp_s;
    if (k % every == 0) {
      state.wrench.valid = true;
      ++state.wrench.sequence;
      state.wrench.stamp_s = state.joints.stamp_s;
      for (int i = 0; i < 6; ++i) state.wrench_sensor[i] = w[i] + noise * std::sin(0.7 * static_cast<double>(k) + i);
    }
    return state;
  }
};

phri::WrenchSupervisor make_supervisor(phri::WrenchSupervisorSettings s = {}) {
  return phri::WrenchSupervisor(s, kT, kObserverGain, 7);
}

Vector6 wrench(double fz) {
  Vector6 w = Vector6::Zero();
  w[2] = fz;
  return w;
}

TEST(WrenchSupervisor, NoSignalUntilTheFirstValidSampleThenOkAtTheSensorsOwnRate) {
  phri::WrenchSupervisor sup = make_supervisor();
  Stream s;
  s.state.wrench.valid = false;
  s.state.joints.stamp_s = kT;
  EXPECT_FALSE(sup.check(s.state, s.qd, s.observer));
  EXPECT_EQ(sup.status(), WrenchStatus::kNoSignal);  // no sensor: not a fault
  // A 100 Hz sensor (Bota's serial default) on the 1 kHz cycle: a new sample every 10 cycles.
  s.every = 10;
  int fresh = 0;
  for (int i = 0; i < 2000; ++i) fresh += sup.check(s.next(wrench(5.0)), s.qd, s.observer) ? 1 : 0;
  EXPECT_EQ(sup.status(), WrenchStatus::kOk);
  EXPECT_EQ(fresh, 200);
}

TEST(WrenchSupervisor, InvalidNotFiniteAndOutOfRangeDropAtOnce) {
  struct Case {
    const char* name;
    void (*corrupt)(phri::RobotState&);
    WrenchStatus expected;
  };
  const Case cases[] = {
      {"invalid", [](phri::RobotState& st) { st.wrench.valid = false; }, WrenchStatus::kInvalid},
      {"nan", [](phri::RobotState& st) { st.wrench_sensor[2] = std::numeric_limits<double>::quiet_NaN(); }, WrenchStatus::kNotFinite},
      {"inf", [](phri::RobotState& st) { st.wrench_sensor[4] = std::numeric_limits<double>::infinity(); }, WrenchStatus::kNotFinite},
      {"1e6 N", [](phri::RobotState& st) { st.wrench_sensor[2] += 1e6; }, WrenchStatus::kOutOfRange},
      {"moment", [](phri::RobotState& st) { st.wrench_sensor[5] = -25.0; }, WrenchStatus::kOutOfRange},
  };
  for (const Case& c : cases) {
    phri::WrenchSupervisor sup = make_supervisor();
    Stream s;
    for (int i = 0; i < 100; ++i) ASSERT_TRUE(sup.check(s.next(wrench(5.0)), s.qd, s.observer)) << c.name;
    phri::RobotState bad = s.next(wrench(5.0));
    c.corrupt(bad);
    EXPECT_FALSE(sup.check(bad, s.qd, s.observer)) << c.name;
    EXPECT_EQ(sup.status(), c.expected) << c.name;
    EXPECT_NEAR(sup.drop_time_s(), bad.joints.stamp_s, 1e-12) << c.name;
  }
  // Large but within the range: a reading.
  phri::WrenchSupervisor sup = make_supervisor();
  Stream s;
  for (int i = 0; i < 100; ++i) EXPECT_TRUE(sup.check(s.next(wrench(-450.0)), s.qd, s.observer));
  EXPECT_EQ(sup.status(), WrenchStatus::kOk);
}

TEST(WrenchSupervisor, StaleWhenTheSequenceOrTheStampStopsForLongerThanTheBudget) {
  for (const bool stamp_only : {false, true}) {
    phri::WrenchSupervisor sup = make_supervisor();
    Stream s;
    for (int i = 0; i < 100; ++i) sup.check(s.next(wrench(5.0)), s.qd, s.observer);
    const std::uint32_t sequence = s.state.wrench.sequence;
    const double stamp = s.state.wrench.stamp_s;
    long cycles = 0;
    while (sup.status() == WrenchStatus::kOk && cycles < 1000) {
      s.next(wrench(5.0));
      s.state.wrench.stamp_s = stamp;                    // the stamp stops...
      if (!stamp_only) s.state.wrench.sequence = sequence;  // ...and the sequence too
      sup.check(s.state, s.qd, s.observer);
      ++cycles;
    }
    EXPECT_EQ(sup.status(), WrenchStatus::kStale) << stamp_only;
    EXPECT_GE(cycles, 50) << stamp_only;  // stale_s = 50 ms, flagged on the first cycle beyond it
    EXPECT_LE(cycles, 51) << stamp_only;
  }
}

TEST(WrenchSupervisor, FrozenOnlyWhileTheArmMovesOrCarriesALoad) {
  for (const int every : {1, 10}) {
    phri::WrenchSupervisor sup = make_supervisor();
    Stream s;
    s.every = every;
    for (int i = 0; i < 100; ++i) sup.check(s.next(wrench(5.0)), s.qd, s.observer);
    s.noise = 0.0;  // the same bits from here on
    for (int i = 0; i < 500; ++i) sup.check(s.next(wrench(5.0)), s.qd, s.observer);
    EXPECT_EQ(sup.status(), WrenchStatus::kOk) << "at rest, unloaded: a noise-free sensor is not flagged";
    s.qd[3] = 0.2;  // the arm moves
    long cycles = 0;
    while (sup.status() == WrenchStatus::kOk && cycles < 1000) {
      sup.check(s.next(wrench(5.0)), s.qd, s.observer);
      ++cycles;
    }
    EXPECT_EQ(sup.status(), WrenchStatus::kFrozen) << every;
    EXPECT_LE(cycles, 50 + every) << every;
  }
  // The observer sees a load, the arm at rest: the same.
  phri::WrenchSupervisor sup = make_supervisor();
  Stream s;
  s.noise = 0.0;
  s.observer[1] = 5.0;
  for (int i = 0; i < 100; ++i) sup.check(s.next(wrench(5.0)), s.qd, s.observer);
  EXPECT_EQ(sup.status(), WrenchStatus::kFrozen);
}

// Before any drop, a touch rests only on a wrench that keeps changing at the sensor's own rate.
TEST(WrenchSupervisor, FreshForAFewOfTheSensorsPeriodsOnly) {
  for (const int every : {1, 10}) {
    phri::WrenchSupervisor sup = make_supervisor();
    Stream s;
    s.every = every;
    long not_fresh = 0;
    for (int i = 0; i < 1000; ++i) {
      sup.check(s.next(wrench(5.0)), s.qd, s.observer);
      if (i >= 2 * every) not_fresh += sup.fresh() ? 0 : 1;  // from the second sample: its interval known
    }
    EXPECT_EQ(not_fresh, 0) << every;
    EXPECT_NEAR(sup.sample_interval_s(), every * kT, 1e-6) << every;
    s.noise = 0.0;  // stuck from here, at rest (not yet a frozen drop)
    long fresh = 0;
    for (int i = 0; i < 40; ++i) {
      sup.check(s.next(wrench(5.0)), s.qd, s.observer);
      fresh += sup.fresh() ? 1 : 0;
    }
    EXPECT_EQ(sup.status(), WrenchStatus::kOk) << every;
    EXPECT_LE(fresh, every + std::max(3, 3 * every) + 1) << every;  // the last change, then 3 periods (>= 3 ms)
  }
}

// J^T F against the observer's tau_ext, fed directly.
TEST(WrenchSupervisor, ConsistencyFlagsAWrenchTheObserverDoesNotSeeOnly) {
  Eigen::VectorXd pattern(7);
  pattern << 0.5, -3.0, 0.8, 2.5, -0.3, 1.2, 0.1;  // |J^T F| of a ~10 N push, about 4.3 N.m
  auto run = [&](auto observer_of, int cycles) {
    phri::WrenchSupervisor sup = make_supervisor();
    Stream s;
    Eigen::VectorXd observer = Eigen::VectorXd::Zero(7), ft = Eigen::VectorXd::Zero(7);
    const double a = 1.0 - std::exp(-kObserverGain * kT);
    for (int k = 0; k < cycles && !sup.dropped(); ++k) {
      sup.check(s.next(wrench(5.0)), s.qd, observer);
      ft = pattern;
      observer += a * (observer_of(k) - observer);  // the observer: a first-order lag of the true torque
      sup.check_consistency(ft, observer);
    }
    return sup;
  };
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(7);
  Eigen::VectorXd elbow = Eigen::VectorXd::Zero(7), opposing = Eigen::VectorXd::Zero(7);
  elbow << 2.0, 8.0, -1.0, 6.0, 0.0, 0.0, 0.0;  // a push on the forearm (10 N.m): the F/T does not see it
  opposing << 2.0, 8.0, -1.0, -6.0, 0.0, 0.0, 0.0;  // the same, nearly cancelling J^T F (cos -0.9)
  // The push is real: the observer finds it (with 10 % model error and a 1 N.m bias) -> ok.
  phri::WrenchSupervisor real = run([&](int) -> Eigen::VectorXd { return 0.9 * pattern + Eigen::VectorXd::Constant(7, 0.4); }, 2000);
  EXPECT_EQ(real.status(), WrenchStatus::kOk);
  EXPECT_LT(real.max_residual_ratio(), 0.5);
  // The observer sees more than the F/T (a hand on the elbow besides): not the F/T's fault.
  phri::WrenchSupervisor more = run([&](int) -> Eigen::VectorXd { return pattern + elbow; }, 2000);
  EXPECT_EQ(more.status(), WrenchStatus::kOk);
  // The known limit: joint torques cannot tell that second hand from no hand on the tool when it
  // cancels J^T F; the F/T is dropped (its use lost, nothing driven).
  phri::WrenchSupervisor cancelled = run([&](int) -> Eigen::VectorXd { return pattern + opposing; }, 2000);
  EXPECT_EQ(cancelled.status(), WrenchStatus::kInconsistent);
  // A phantom: the F/T reads a push nobody makes (stuck after the hand left, an offset).
  phri::WrenchSupervisor phantom = run([&](int) -> Eigen::VectorXd { return zero; }, 2000);
  EXPECT_EQ(phantom.status(), WrenchStatus::kInconsistent);
  // A stuck reading after the hand left: the observer decays, the F/T does not.
  phri::WrenchSupervisor stuck = run([&](int k) -> Eigen::VectorXd { return k < 500 ? pattern : zero; }, 2000);
  EXPECT_EQ(stuck.status(), WrenchStatus::kInconsistent);
  EXPECT_GT(stuck.drop_time_s(), 0.5);
  EXPECT_LT(stuck.drop_time_s(), 0.5 + 0.2);
}

TEST(WrenchSupervisor, ADropLatchesUntilResetAndTheChecksDoNotAllocate) {
  phri::WrenchSupervisor sup = make_supervisor();
  Stream s;
  const Eigen::VectorXd ft = Eigen::VectorXd::Zero(7);
  phri::test::AllocationCounter count;
  {
    phri::test::NoMallocScope no_malloc;
    for (int i = 0; i < 100; ++i) {
      sup.check(s.next(wrench(5.0)), s.qd, s.observer);
      sup.check_consistency(ft, s.observer);
    }
    phri::RobotState& bad = s.state;
    s.next(wrench(5.0));
    bad.wrench_sensor[0] = std::numeric_limits<double>::quiet_NaN();
    sup.check(bad, s.qd, s.observer);
    for (int i = 0; i < 2000; ++i) EXPECT_FALSE(sup.check(s.next(wrench(5.0)), s.qd, s.observer));
  }
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_EQ(sup.status(), WrenchStatus::kNotFinite);  // 2 s of good samples: still dropped
  sup.reset();
  EXPECT_EQ(sup.status(), WrenchStatus::kNoSignal);
  EXPECT_TRUE(sup.check(s.next(wrench(5.0)), s.qd, s.observer));
  EXPECT_EQ(sup.status(), WrenchStatus::kOk);
}

TEST(WrenchSupervisor, BadSettingsAreConfigErrors) {
  phri::WrenchSupervisorSettings s;
  s.force_range_N = 0.0;
  EXPECT_THROW(make_supervisor(s), phri::ConfigError);
  s = {};
  s.stale_s = 0.0;
  EXPECT_THROW(make_supervisor(s), phri::ConfigError);
}

}  // namespace
