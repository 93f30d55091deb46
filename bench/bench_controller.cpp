// One full controller cycle, phri::Controller::step — model terms, momentum observer, F/T
// wrench, compliance logic, QP build and solve, inverse dynamics, custom low-level torque loop —
// timed cycle by cycle over 100,000 cycles of a closed-loop run on the simulated Gen3 (SimRobot
// with its noise, friction and 5 % mismatch; pushes on the elbow and on the tool every few
// seconds, dual compliance on so the trigger fires, self-collision rows in). The plant's own time
// is not counted. Reports median, p99, p99.9 and max in microseconds; and, timed the same way on
// the same states in the same run, the safety supervisor's plausibility check alone (a second
// StateSupervisor built like the controller's: supervisor_median_us, the part of the cycle it adds):
//   build/release/bench/phri_bench --benchmark_filter=ControllerCycle
// ControllerCyclePowerForceLimit: the same with the power-and-force limit off and on.
#include <phri/config/robot_bundle.hpp>
#include <phri/control/controller.hpp>
#include <phri/control/singular_direction_weight.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/core/statistics.hpp>
#include <phri/sim/sim_robot.hpp>

#include "pushed_gen3.hpp"

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <functional>
#include <vector>

namespace {

// The closed-loop run above with `configure` applied to the controller's settings.
void time_cycles(benchmark::State& state, const std::function<void(phri::ControllerSettings&)>& configure) {
  const std::string root = PHRI_SOURCE_DIR;
  constexpr int kCycles = 100000;
  const phri::SimRobotConfig plant = pushed_gen3_plant(kCycles * 1e-3);
  phri::SimRobot robot(plant);
  phri::ControllerSettings settings;
  phri::RobotBundle::from_folder(root + "/robots/kinova_gen3").apply_to(settings);  // files, frames, end of arm
  settings.initial_compliance = phri::ComplianceMode::kDual;
  configure(settings);
  phri::Controller cycle(settings);
  phri::RobotCommand command(robot.dof());

  phri::StateSupervisor supervisor(cycle.supervisor().ranges(), cycle.supervisor().settings());
  std::vector<double> micros(kCycles), supervisor_micros(kCycles);
  for (auto _ : state) {
    for (int k = 0; k < kCycles; ++k) {
      const phri::RobotState& s = robot.read();
      const auto check_start = std::chrono::steady_clock::now();
      benchmark::DoNotOptimize(supervisor.check(s));
      supervisor_micros[static_cast<std::size_t>(k)] =
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - check_start).count();
      const auto start = std::chrono::steady_clock::now();
      cycle.step(s, command);
      micros[static_cast<std::size_t>(k)] =
          std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
      robot.write(command);
    }
  }
  state.counters["median_us"] = phri::percentile(micros, 0.5);
  state.counters["p99_us"] = phri::percentile(micros, 0.99);
  state.counters["p99.9_us"] = phri::percentile(micros, 0.999);
  state.counters["max_us"] = phri::percentile(micros, 1.0);
  state.counters["touches"] = cycle.compliance().touch_count();
  state.counters["supervisor_median_us"] = phri::percentile(supervisor_micros, 0.5);
  state.counters["supervisor_p99_us"] = phri::percentile(supervisor_micros, 0.99);
  // The cycles the singular-direction weight answered from its Weyl certificate, without a test,
  // and those it decomposed J J^T on (the rest: a Cholesky test, or the weak direction tracked);
  // weight_second_certified: tracked cycles whose other eigenvalues the certificate answered.
  const phri::SingularDirectionWeight& weight = cycle.qp().end_effector().singular_weight();
  state.counters["weight_certified"] = static_cast<double>(weight.certified_skips()) / kCycles;
  state.counters["weight_decomposed"] = static_cast<double>(weight.decompositions()) / kCycles;
  state.counters["weight_second_certified"] = static_cast<double>(weight.second_certified()) / kCycles;
  state.counters["implausible"] = static_cast<double>(cycle.supervisor().implausible_samples());
}
void ControllerCycle(benchmark::State& state) {
  // Arg: the end-effector task's singular-value threshold in thousandths (30: the default; 0: the
  // paper's task, for the cost of the weight's test in one run).
  time_cycles(state, [&](phri::ControllerSettings& s) { s.qp.singular_value_threshold = state.range(0) / 1000.0; });
}
BENCHMARK(ControllerCycle)->Arg(30)->Arg(0)->Iterations(1)->Unit(benchmark::kMillisecond);

// The same run with the power-and-force-limiting constraint (control/power_force_limit.hpp) off
// (Arg 0) and on (Arg 1, the hand/fingers region of configs/iso_ts_15066_regions.yaml: k 75 N/mm,
// m_H 0.6 kg, F_QS 140 N, transient x2): its cost, same run.
void ControllerCyclePowerForceLimit(benchmark::State& state) {
  time_cycles(state, [&](phri::ControllerSettings& s) {
    if (state.range(0) == 0) return;
    phri::PowerForceLimitSettings limit;
    limit.regions.region = {"hand_fingers", 75e3, 0.6, 140.0, 2.0};
    s.qp.power_force_limit = limit;
  });
}
BENCHMARK(ControllerCyclePowerForceLimit)->Arg(0)->Arg(1)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace

// What the end-effector task's singular-direction weight adds to a cycle (singular_direction_weight.hpp):
// Arg 0, away from singularities with a Jacobian that stays within Weyl's certificate (42
// multiply-adds); Arg 2, the same posture alternating with one 0.3 rad away on every joint, so that
// each update tests (J J^T, the 6 x 6 Cholesky at sigma_0, then at 2 and 4 sigma_0 for a new
// certificate); Arg 1, the weighted path near a singularity (the weak direction tracked).
// Gen3 end-effector Jacobians.
void SingularDirectionWeightTest(benchmark::State& state) {
  const phri::Model model = phri::Model::from_urdf_file(std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/gen3.urdf");
  phri::Data data(model);
  auto jacobian_at = [&](const Eigen::VectorXd& q) {
    phri::forward_kinematics(model, data, q);
    phri::update_frame_placements(model, data);
    Eigen::MatrixXd jacobian(6, 7);
    phri::frame_jacobian(model, data, model.frame_id("end_effector_link"), phri::ReferenceFrame::kLocalWorldAligned, jacobian);
    return jacobian;
  };
  Eigen::VectorXd q(7);
  if (state.range(0) == 1) {
    q << 0.0, 0.4, 0.0, 0.07, 0.0, 0.9, 0.0;  // the outstretched elbow: sigma_min ~ 0.01
  } else {
    q << 0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57;  // the demo's posture: sigma_min 0.21
  }
  const Eigen::MatrixXd jacobians[2] = {jacobian_at(q), jacobian_at(q + Eigen::VectorXd::Constant(7, state.range(0) == 2 ? 0.3 : 0.0))};
  phri::SingularDirectionWeight weight(0.03, 7);
  int k = 0;
  for (auto _ : state) {
    benchmark::DoNotOptimize(weight.update(jacobians[k ^= 1]));
    benchmark::DoNotOptimize(weight.weight().data());
  }
  state.SetLabel(state.range(0) == 0 ? "certified (demo posture)" : state.range(0) == 2 ? "tested (demo posture, alternating)" : "weighted (q4 = 0.07)");
}
BENCHMARK(SingularDirectionWeightTest)->Arg(0)->Arg(2)->Arg(1);
