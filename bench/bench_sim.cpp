// The simulated Gen3 in closed loop: one iteration = one 1 kHz control cycle (read: 4 physics steps
// at 4 kHz with drives, friction, sensors and noise; a joint PD; write). The counter
// sim_s_per_wall_s is the real-time factor (simulated seconds per wall-clock second). Run:
//   build/release/bench/phri_bench --benchmark_filter=Sim --benchmark_repetitions=10
//     --benchmark_report_aggregates_only=true   (one line)
//
// SimOverhead/*: what phri's plant costs on top of MuJoCo, issue 44's "simulation per 1 ms <= 1.1x
// four raw mj_step on the same scene". In one run, blocks of the two alternate on the same scene
// and state, so that a loaded machine slows both alike:
//   (a) phri: kBlockPeriods SimRobot periods, each read() (4 physics steps at 4 kHz: MuJoCo's
//       mj_step1/mj_step2 plus drives, friction, sensor noise, external forces, the F/T sample
//       once per 1 ms) and write(); the closed loop's joint PD (a few ns) is inside the timing;
//   (b) raw:  kBlockPeriods x 4 mj_step on SimRobot's own mjModel (the scene as phri builds it:
//       MJCF with the F/T site sensors, its joint damping, armature and options, the sensor stage
//       disabled as phri leaves it between F/T samples) and on a copy of its mjData taken just
//       before the block (mj_copyData, untimed): the same state and the same applied forces
//       (qfrc_applied, xfrc_applied of phri's last step), held over the block.
// Counters: phri_us and raw_us, medians over the blocks of the time per 1 ms period; ratio (the
// issue's number) = the median over the iterations of (a) / (b), each from blocks run back to back,
// so that a load that changes during the run (other processes on a shared machine) cancels out.
// raw_ft_us adds to (b) one mj_rnePostConstraint per period, the stage MuJoCo's force/torque
// sensors need, i.e. raw MuJoCo sampling the F/T at 1 kHz as phri does; ratio_vs_raw_ft likewise.
// Run:
//   build/release/bench/phri_bench --benchmark_filter=SimOverhead
#include <phri/sim/sim_robot.hpp>

#include <benchmark/benchmark.h>
#include <mujoco/mujoco.h>

#include <algorithm>
#include <chrono>
#include <memory>
#include <vector>

namespace {

const std::vector<double> kTarget = {0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57};

phri::SimRobotConfig config() {
  auto c = phri::SimRobotConfig::from_yaml_file(std::string(PHRI_SOURCE_DIR) + "/configs/plant_gen3.yaml");
  c.initial_q_rad = kTarget;
  return c;
}

phri::SimRobotConfig drop_and_pushes_config() {
  auto c = config();
  c.drop_test.enabled = true;
  c.drop_test.release_time_s = 0.5;
  c.random_pushes.enabled = true;
  return c;
}

// The bench's controller: a joint PD in Current mode (gravity feed-forward of the start pose), or
// the vendor position servo holding kTarget.
class ClosedLoop {
public:
  ClosedLoop(phri::SimRobot& robot, bool current_pd)
      : robot_(robot), current_pd_(current_pd), n_(robot.dof()), cmd_(n_), gravity_(n_), ktg_(n_) {
    for (int i = 0; i < n_; ++i) ktg_[i] = robot.plant_actuators()[i].torque_per_amp();
    // The holding torque the plant starts with, read once from the initial motor currents.
    gravity_ = robot.state().current_A.cwiseProduct(ktg_);
    cmd_.mode = current_pd ? phri::LowLevelMode::kCurrent : phri::LowLevelMode::kPosition;
    for (int i = 0; i < n_; ++i) cmd_.q_rad[i] = kTarget[static_cast<std::size_t>(i)];
  }

  // One control period: read (the physics steps), the PD, write.
  const phri::RobotState& period() {
    const phri::RobotState& s = robot_.read();
    if (current_pd_) {
      for (int i = 0; i < n_; ++i) {
        const double tau = gravity_[i] + 400.0 * (kTarget[static_cast<std::size_t>(i)] - s.q_rad[i]) - 20.0 * s.qd_rad_s[i];
        const double limit = robot_.plant_actuators()[i].current_limit_A;
        cmd_.current_A[i] = std::clamp(tau / ktg_[i], -limit, limit);
      }
    }
    robot_.write(cmd_);
    return s;
  }

private:
  phri::SimRobot& robot_;
  bool current_pd_;
  int n_;
  phri::RobotCommand cmd_;
  Eigen::VectorXd gravity_, ktg_;
};

void run(benchmark::State& state, phri::SimRobot& robot, bool current_pd) {
  ClosedLoop loop(robot, current_pd);
  for (auto _ : state) {
    const phri::RobotState& s = loop.period();
    benchmark::DoNotOptimize(s.q_rad.data());
  }
  state.counters["sim_s_per_wall_s"] =
      benchmark::Counter(robot.period_s() * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}

double median(std::vector<double> v) {
  if (v.empty()) return 0.0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

// One iteration = one block of (a) and one of (b) (then the raw one with the F/T stage), in
// alternating order; see the file's head.
void overhead(benchmark::State& state, const phri::SimRobotConfig& c, bool current_pd) {
  constexpr int kBlockPeriods = 8;
  using Clock = std::chrono::steady_clock;
  phri::SimRobot robot(c);
  ClosedLoop loop(robot, current_pd);
  const mjModel* m = robot.mujoco_model();
  const std::unique_ptr<mjData, void (*)(mjData*)> raw(mj_makeData(m), mj_deleteData);
  const int steps = robot.config().substeps_per_cycle();
  std::vector<double> phri_s, raw_s, raw_ft_s, ratio, ratio_ft;
  for (auto* v : {&phri_s, &raw_s, &raw_ft_s, &ratio, &ratio_ft}) v->reserve(1 << 20);

  auto time_phri = [&] {
    const auto t0 = Clock::now();
    for (int k = 0; k < kBlockPeriods; ++k) benchmark::DoNotOptimize(loop.period().q_rad.data());
    return std::chrono::duration<double>(Clock::now() - t0).count();
  };
  auto time_raw = [&](bool ft_stage) {
    mj_copyData(raw.get(), m, robot.mujoco_data());
    const auto t0 = Clock::now();
    for (int k = 0; k < kBlockPeriods; ++k) {
      for (int s = 0; s < steps; ++s) mj_step(m, raw.get());
      if (ft_stage) mj_rnePostConstraint(m, raw.get());
    }
    benchmark::DoNotOptimize(raw->qpos);
    return std::chrono::duration<double>(Clock::now() - t0).count();
  };

  bool phri_first = true;
  for (auto _ : state) {
    double a = 0.0, b = 0.0, b_ft = 0.0;
    if (phri_first) {
      a = time_phri();
      b = time_raw(false);
      b_ft = time_raw(true);
    } else {
      b_ft = time_raw(true);
      b = time_raw(false);
      a = time_phri();
    }
    phri_first = !phri_first;
    if (robot.state().fault) {
      state.SkipWithError("the simulation faulted");
      break;
    }
    phri_s.push_back(a / kBlockPeriods);
    raw_s.push_back(b / kBlockPeriods);
    raw_ft_s.push_back(b_ft / kBlockPeriods);
    ratio.push_back(a / b);
    ratio_ft.push_back(a / b_ft);
    state.SetIterationTime(a + b + b_ft);
  }
  state.counters["phri_us"] = 1e6 * median(phri_s);
  state.counters["raw_us"] = 1e6 * median(raw_s);
  state.counters["raw_ft_us"] = 1e6 * median(raw_ft_s);
  state.counters["ratio"] = median(ratio);
  state.counters["ratio_vs_raw_ft"] = median(ratio_ft);
}

// The benchmark: a joint PD in Current mode (plant substeps, drives, sensors included).
void SimClosedLoopCurrentPd(benchmark::State& state) {
  phri::SimRobot robot(config());
  run(state, robot, true);
}
BENCHMARK(SimClosedLoopCurrentPd)->UseRealTime()->MinTime(2.0);

// The heavier case: the vendor position servo (noise drawn every physics step) with the drop test
// (free body, latch and cable) and random pushes.
void SimPositionDropAndPushes(benchmark::State& state) {
  phri::SimRobot robot(drop_and_pushes_config());
  run(state, robot, false);
}
BENCHMARK(SimPositionDropAndPushes)->UseRealTime()->MinTime(2.0);

// phri vs raw MuJoCo on the Gen3 scene (configs/plant_gen3.yaml), joint PD in Current mode.
void SimOverheadGen3(benchmark::State& state) { overhead(state, config(), true); }
BENCHMARK(SimOverheadGen3)->UseManualTime()->MinTime(3.0);

// phri vs raw MuJoCo on the drop-test scene (drop mass, latch, cable; random pushes), position servo.
void SimOverheadDropTest(benchmark::State& state) { overhead(state, drop_and_pushes_config(), false); }
BENCHMARK(SimOverheadDropTest)->UseManualTime()->MinTime(3.0);

}  // namespace
