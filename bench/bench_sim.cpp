// The simulated Gen3 in closed loop: one iteration = one 1 kHz control cycle (read: 4 physics steps
// at 4 kHz with drives, friction, sensors and noise; a joint PD; write). The counter
// sim_s_per_wall_s is the real-time factor (simulated seconds per wall-clock second). Run:
//   build/release/bench/phri_bench --benchmark_filter=Sim --benchmark_repetitions=10
//     --benchmark_report_aggregates_only=true   (one line)
#include <phri/sim/sim_robot.hpp>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <vector>

namespace {

const std::vector<double> kTarget = {0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57};

phri::SimRobotConfig config() {
  auto c = phri::SimRobotConfig::from_yaml_file(std::string(PHRI_SOURCE_DIR) + "/configs/plant_gen3.yaml");
  c.initial_q_rad = kTarget;
  return c;
}

void run(benchmark::State& state, phri::SimRobot& robot, bool current_pd) {
  phri::RobotCommand cmd(robot.dof());
  const int n = robot.dof();
  Eigen::VectorXd gravity(n), ktg(n);
  for (int i = 0; i < n; ++i) ktg[i] = robot.plant_actuators()[i].torque_per_amp();
  // Gravity feed-forward of the start pose (the PD does the rest): the holding torque the plant
  // starts with, read once from the initial motor currents.
  gravity = robot.state().current_A.cwiseProduct(ktg);
  cmd.mode = current_pd ? phri::LowLevelMode::kCurrent : phri::LowLevelMode::kPosition;
  for (int i = 0; i < n; ++i) cmd.q_rad[i] = kTarget[static_cast<std::size_t>(i)];
  for (auto _ : state) {
    const phri::RobotState& s = robot.read();
    if (current_pd) {
      for (int i = 0; i < n; ++i) {
        const double tau = gravity[i] + 400.0 * (kTarget[static_cast<std::size_t>(i)] - s.q_rad[i]) - 20.0 * s.qd_rad_s[i];
        const double limit = robot.plant_actuators()[i].current_limit_A;
        cmd.current_A[i] = std::clamp(tau / ktg[i], -limit, limit);
      }
    }
    robot.write(cmd);
    benchmark::DoNotOptimize(s.q_rad.data());
  }
  state.counters["sim_s_per_wall_s"] =
      benchmark::Counter(robot.period_s() * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
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
  auto c = config();
  c.drop_test.enabled = true;
  c.drop_test.release_time_s = 0.5;
  c.random_pushes.enabled = true;
  phri::SimRobot robot(c);
  run(state, robot, false);
}
BENCHMARK(SimPositionDropAndPushes)->UseRealTime()->MinTime(2.0);

}  // namespace
