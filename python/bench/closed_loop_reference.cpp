// The C++ side of python/bench/bench_loop.py: the closed loop a C++ user writes (read, controller
// step, write, a refused write reported as a fault), on the same scenario as the script's Python
// runs, timed around the loop only. Prints the loop's wall time and the final joint positions
// (hexadecimal floats), which the script compares with its own runs: the same loop, bit for bit.
//
//   phri_loop_reference [--seconds S] [--repetitions R]
#include <phri/config/robot_bundle.hpp>
#include <phri/control/controller.hpp>
#include <phri/sim/sim_robot.hpp>

#include "pushed_gen3.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <string>

namespace {

// The scenario, as python/bench/bench_loop.py builds it: the controller benchmarks' pushed Gen3
// (bench/pushed_gen3.hpp: the paper demo's posture, 5 % model mismatch, a push on the elbow and one on
// the tool every 6 s), dual compliance, the custom loop.
phri::ControllerSettings controller_settings() {
  const std::string gen3 = std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/";
  phri::ControllerSettings settings;
  phri::RobotBundle::from_folder(gen3).apply_to(settings);  // files, frames, end of arm (as Python's ControllerSettings())
  settings.initial_compliance = phri::ComplianceMode::kDual;
  return settings;
}

void run_once(double seconds) {
  phri::SimRobot robot(pushed_gen3_plant(seconds));
  phri::Controller controller(controller_settings());
  phri::RobotCommand command(robot.dof());
  const phri::ControllerTargets targets(robot.dof());
  const long cycles = static_cast<long>(seconds / robot.period_s() + 0.5);
  const auto start = std::chrono::steady_clock::now();
  for (long k = 0; k < cycles; ++k) {
    const phri::RobotState& state = robot.read();
    controller.step(state, targets, command);
    if (robot.write(command) != phri::WriteStatus::kOk) controller.report_fault(phri::SafetyFault::kWriteRefused, state.time_s);
  }
  const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("loop_s %.9f\nfinal_q", elapsed);
  for (int i = 0; i < robot.dof(); ++i) std::printf(" %a", robot.state().q_rad[i]);
  std::printf("\n");
}

}  // namespace

int main(int argc, char** argv) {
  double seconds = 10.0;
  int repetitions = 1;
  for (int i = 1; i + 1 < argc; i += 2) {
    if (std::strcmp(argv[i], "--seconds") == 0) seconds = std::atof(argv[i + 1]);
    if (std::strcmp(argv[i], "--repetitions") == 0) repetitions = std::atoi(argv[i + 1]);
  }
  for (int r = 0; r < repetitions; ++r) run_once(seconds);
  return 0;
}
