// ctest-labels: unit physics
// The F/T wrench's plausibility (safety/wrench_supervisor.hpp): each check alone on made-up
// samples, then closed-loop reproducers of issue 37 point 4 on the simulated Gen3 in dual
// compliance: a hand pushes the tool, the wrench goes bad while it pushes (stuck, NaN, invalid,
// stale, 100 samples of 1e6 N), the hand leaves. The F/T source must be dropped, the touch trigger
// released and the arm held where it was when the fault began; the same run without a fault (and
// with a push on the elbow the F/T does not see) must raise no alarm.
#include <phri/app/fill_log_row.hpp>
#include <phri/app/logger.hpp>
#include <phri/control/controller.hpp>
#include <phri/dashboard/state_encoder.hpp>
#include <phri/core/error.hpp>
#include <phri/safety/wrench_supervisor.hpp>
#include <phri/sim/sim_robot.hpp>

#include "allocation_counter.hpp"
#include "gen3_settings.hpp"
#include "hand_push.hpp"

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
  EXPECT_NE(phri::Logger::legend_yaml().find("ft_status:\n  0: ok\n  1: no_signal\n  2: not_finite"), std::string::npos);
}

// ---------------------------------------------------------------- closed loop on the plant

const std::string kRoot = PHRI_SOURCE_DIR;

enum class Fault { kNone, kStuck, kNaN, kInvalid, kStale, kHuge, kOffset };
const char* name(Fault f) {
  switch (f) {
    case Fault::kNone: return "none";
    case Fault::kStuck: return "stuck";
    case Fault::kNaN: return "nan";
    case Fault::kInvalid: return "invalid";
    case Fault::kStale: return "stale";
    case Fault::kHuge: return "1e6 N x 100";
    case Fault::kOffset: return "+15 N offset";
  }
  return "?";
}

// Corrupts the wrench alone from start_s on (experiments/FaultInjectingRobot corrupts the joints
// too, or f_z only): what an F/T sensor or its driver does when it fails.
class WrenchFaultRobot final : public phri::RobotInterface {
public:
  WrenchFaultRobot(phri::RobotInterface& inner, Fault fault, double start_s)
      : inner_(inner), fault_(fault), start_s_(start_s), out_(inner.dof()) {}
  int dof() const override { return inner_.dof(); }
  double period_s() const override { return inner_.period_s(); }
  phri::WriteStatus write(const phri::RobotCommand& command) override { return inner_.write(command); }
  const phri::RobotState& read() override {
    out_ = inner_.read();
    if (fault_ == Fault::kNone || out_.time_s < start_s_) return out_;
    if (!started_) {
      started_ = true;
      held_ = out_.wrench_sensor;
      held_signal_ = out_.wrench;
      first_sequence_ = out_.wrench.sequence;
    }
    switch (fault_) {
      case Fault::kNone: break;
      case Fault::kStuck: out_.wrench_sensor = held_; break;  // the bus alive, the values stuck
      case Fault::kNaN: out_.wrench_sensor[2] = std::numeric_limits<double>::quiet_NaN(); break;
      case Fault::kInvalid: out_.wrench.valid = false; break;
      case Fault::kStale:  // the last sample again, sequence and stamp included
        out_.wrench_sensor = held_;
        out_.wrench = held_signal_;
        break;
      case Fault::kHuge:
        if (out_.wrench.sequence - first_sequence_ < 100) out_.wrench_sensor[2] += 1e6;
        break;
      case Fault::kOffset: out_.wrench_sensor[2] += 15.0; break;  // in range, noisy, fresh: a phantom
    }
    return out_;
  }

private:
  phri::RobotInterface& inner_;
  Fault fault_;
  double start_s_;
  phri::RobotState out_;
  bool started_ = false;
  Vector6 held_ = Vector6::Zero();
  phri::SignalStatus held_signal_;
  std::uint32_t first_sequence_ = 0;
};

struct Outcome {
  WrenchStatus status = WrenchStatus::kOk;
  double drop_latency_s = -1.0;       // drop time - fault start (-1: no drop)
  double drift_rad = 0.0;             // max |q - q(fault start)| at the end
  double max_drift_rad = 0.0;         // ... over the whole run after the fault
  double release_latency_s = -1.0;    // first cycle untouched after the fault's start - its start
  bool touched_at_end = false;
  double max_residual_ratio = 0.0;    // u / tolerance of the consistency check, largest
  phri::CycleStatus cycle_status = phri::CycleStatus::kOk;
  std::int32_t logged_ft_status = 0;
  std::string dashboard_frame;        // the dashboard stream's frame of the last cycle
  int touches = 0;
};

// The fault begins 10 ms before the hand lets go (a stuck sensor then holds the push's 12 N).
constexpr double kPushStart = 0.5, kPushEnd = 1.5, kFaultStart = 1.49, kEnd = 2.8;

// Dual compliance, the paper's fused external torque; a hand pushes the tool with 12 N from 0.5 to
// 1.5 s (the touch trigger fires, the hand drags the end effector); the fault (if any) from 1.49 s.
Outcome run_dual(Fault fault, bool elbow_push = false, double ft_rate_Hz = 1000.0) {
  phri::SimRobotConfig config = phri::SimRobotConfig::from_yaml_file(kRoot + "/configs/plant_gen3.yaml");
  config.initial_q_rad = {0, 0.58, 3.14, -1.84, 0, 0.85, 1.57};  // the paper demo's postureTarget
  config.mismatch.enabled = true;
  config.ft_sensor.rate_Hz = ft_rate_Hz;
  config.disturbances = {phri::test::hand_push("tool", Eigen::Vector3d(0, 0, 0.05), Eigen::Vector3d(0, 12, 0), kPushStart,
                                               kPushEnd - kPushStart)};
  // A hand on the forearm (seen by the observer, not by the F/T) after the release: one-sided check.
  if (elbow_push) config.disturbances.push_back(phri::test::hand_push("forearm_link", Eigen::Vector3d::Zero(), Eigen::Vector3d(0, 30, 0), 1.8, 0.6));
  phri::SimRobot plant(config);
  WrenchFaultRobot robot(plant, fault, kFaultStart);
  phri::ControllerSettings settings = phri::test::gen3_controller_settings(phri::ComplianceMode::kDual, phri::LowLevelMode::kCurrent);
  settings.external_torque_source = phri::ExternalTorqueSource::kFused;
  // The bias is averaged over a count of samples (WrenchEstimatorSettings): 0.2 s at either rate,
  // the arm at rest before the push.
  settings.wrench.bias_samples = static_cast<int>(std::lround(0.2 * ft_rate_Hz));
  phri::Controller cycle(settings);
  phri::RobotCommand command(7);
  Outcome out;
  Eigen::VectorXd q_fault;
  const long n = std::lround(kEnd / robot.period_s());
  for (long k = 0; k < n; ++k) {
    const phri::RobotState& state = robot.read();
    cycle.step(state, command);
    robot.write(command);
    if (q_fault.size() == 0 && state.time_s >= kFaultStart) q_fault = state.q_rad;
    if (q_fault.size() != 0 && out.release_latency_s < 0.0 && !cycle.compliance().touched()) {
      out.release_latency_s = state.time_s - kFaultStart;
    }
    if (q_fault.size() != 0) out.max_drift_rad = std::max(out.max_drift_rad, (state.q_rad - q_fault).cwiseAbs().maxCoeff());
  }
  const phri::RobotState& last = plant.read();
  const phri::WrenchSupervisor& sup = cycle.wrench_supervisor();
  out.status = sup.status();
  out.drop_latency_s = sup.dropped() ? sup.drop_time_s() - kFaultStart : -1.0;
  out.drift_rad = (last.q_rad - q_fault).cwiseAbs().maxCoeff();
  out.touched_at_end = cycle.compliance().touched();
  out.touches = cycle.compliance().touch_count();
  out.max_residual_ratio = sup.max_residual_ratio();
  out.cycle_status = cycle.status();
  phri::LogRow row;
  phri::fill_log_row(row, last, cycle);
  out.logged_ft_status = row.ft_status;
  phri::StateEncoderSettings encoder_settings;
  encoder_settings.end_effector_frame = settings.end_effector_frame;
  phri::StateEncoder encoder(cycle.model(), nullptr, encoder_settings);
  phri::LiveSnapshot snapshot;
  snapshot.row = row;
  snapshot.dof = 7;
  out.dashboard_frame = encoder.frame_json(snapshot);
  return out;
}

TEST(WrenchFaultClosedLoop, AFaultFreeDualComplianceRunRaisesNoAlarm) {
  for (const double rate : {1000.0, 100.0}) {
    const Outcome o = run_dual(Fault::kNone, /*elbow_push=*/true, rate);
    std::printf("fault-free (F/T at %.0f Hz, elbow push after the release): status %s, touches %d, max residual / "
                "tolerance %.2f\n",
                rate, std::string(phri::to_string(o.status)).c_str(), o.touches, o.max_residual_ratio);
    EXPECT_EQ(o.status, WrenchStatus::kOk) << rate;
    EXPECT_EQ(o.touches, 1) << rate;  // the hand's push did free the end effector
    EXPECT_FALSE(o.touched_at_end) << rate;
    EXPECT_LT(o.max_residual_ratio, 0.8) << rate;  // a margin to the tolerance
    EXPECT_EQ(o.logged_ft_status, 0) << rate;
  }
}

TEST(WrenchFaultClosedLoop, ABadWrenchIsDroppedTheTriggerReleasedAndTheArmHeld) {
  // The reference: the same run without a fault (the hand lets go 10 ms after 1.49 s, the trigger
  // releases as the wrench falls, the arm coasts on and comes back to where it was released).
  const Outcome clean = run_dual(Fault::kNone);
  std::printf("fault-free reference: touch released %5.1f ms after 1.49 s, arm at the end %.4f rad from its pose "
              "at 1.49 s (max %.4f)\n",
              1e3 * clean.release_latency_s, clean.drift_rad, clean.max_drift_rad);
  struct Case {
    Fault fault;
    WrenchStatus expected;
    double max_latency_s;
  };
  for (const Case c : {Case{Fault::kStuck, WrenchStatus::kFrozen, 0.06}, Case{Fault::kNaN, WrenchStatus::kNotFinite, 0.002},
                       Case{Fault::kInvalid, WrenchStatus::kInvalid, 0.002}, Case{Fault::kStale, WrenchStatus::kStale, 0.06},
                       Case{Fault::kHuge, WrenchStatus::kOutOfRange, 0.002}}) {
    const Outcome o = run_dual(c.fault);
    std::printf("fault %-13s: %-12s dropped after %5.1f ms, touch released after %5.1f ms; arm at the end %.4f rad "
                "from its pose at the fault's start (max %.4f), cycle status %s\n",
                name(c.fault), std::string(phri::to_string(o.status)).c_str(), 1e3 * o.drop_latency_s,
                1e3 * o.release_latency_s, o.drift_rad, o.max_drift_rad, std::string(phri::to_string(o.cycle_status)).c_str());
    EXPECT_EQ(o.status, c.expected) << name(c.fault);
    EXPECT_GE(o.drop_latency_s, 0.0) << name(c.fault);
    EXPECT_LE(o.drop_latency_s, c.max_latency_s) << name(c.fault);
    EXPECT_FALSE(o.touched_at_end) << name(c.fault);
    EXPECT_LE(o.release_latency_s, std::max(clean.release_latency_s, 0.0) + 0.01) << name(c.fault);
    EXPECT_LT(o.drift_rad, 0.05) << name(c.fault);
    EXPECT_LT(o.max_drift_rad, clean.max_drift_rad + 0.02) << name(c.fault);
    EXPECT_EQ(o.cycle_status, phri::CycleStatus::kOk) << name(c.fault);  // the joints' status is not the F/T's
    EXPECT_EQ(o.logged_ft_status, static_cast<std::int32_t>(c.expected)) << name(c.fault);
    const std::string streamed = "\"ft\":\"" + std::string(phri::to_string(c.expected)) + "\"";
    EXPECT_NE(o.dashboard_frame.find(streamed), std::string::npos) << name(c.fault) << ": " << streamed;
  }
}

// A phantom within range, fresh and noisy (a +15 N offset on f_z from the moment the hand lets go):
// only the observer can tell. Caught by the consistency check, slower (its filter, 0.15 s, is what
// keeps a fast release from reading as one), so the end effector coasts free meanwhile; without the
// check the trigger stayed touched for good.
TEST(WrenchFaultClosedLoop, APhantomWrenchInRangeIsCaughtByTheObserver) {
  const Outcome o = run_dual(Fault::kOffset);
  std::printf("fault %-13s: %-12s dropped after %5.1f ms, touch released after %5.1f ms; arm at the end %.4f rad "
              "from its pose at the fault's start (max %.4f)\n",
              name(Fault::kOffset), std::string(phri::to_string(o.status)).c_str(), 1e3 * o.drop_latency_s,
              1e3 * o.release_latency_s, o.drift_rad, o.max_drift_rad);
  EXPECT_EQ(o.status, WrenchStatus::kInconsistent);
  EXPECT_GE(o.drop_latency_s, 0.0);
  EXPECT_LT(o.drop_latency_s, 0.2);
  EXPECT_FALSE(o.touched_at_end);
  EXPECT_LT(o.drift_rad, 0.25);
  EXPECT_EQ(o.logged_ft_status, static_cast<std::int32_t>(WrenchStatus::kInconsistent));
}

}  // namespace
