// How the cost grows with the arm (issue 16): the model terms and the whole controller cycle on
// generated serial chains of 6, 7, 14 and 30 DoF (tests/support/random_chain.hpp: random axes,
// offsets, rotated inertials, fixed links between, one in four joints prismatic on average), and
// the capsule distances with their derivatives for 10, 50 and 200 pairs on the 30-DoF chain.
//   build/release/bench/phri_bench --benchmark_filter=Scaling --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// The whole cycle: phri::Controller::step (custom torque loop, null-space compliance, no collision
// model) on a 1 kHz stream of states of the generated chain at rest with sensor noise; the cycle
// must stay on its normal path (status ok), or the benchmark reports an error.
#include <phri/control/controller.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/collision_model.hpp>
#include <phri/model/model.hpp>

#include "../tests/support/random_chain.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <sstream>

namespace {

struct Chain {
  explicit Chain(int dof) : chain(make(dof)), model(phri::Model::from_urdf_string(chain.urdf)), data(model) {
    std::mt19937 rng(static_cast<unsigned>(dof));
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    q.resize(dof);
    qd.resize(dof);
    qdd.resize(dof);
    for (int i = 0; i < dof; ++i) {
      q[i] = u(rng);
      qd[i] = u(rng);
      qdd[i] = 5.0 * u(rng);
    }
    phri::compute_all_terms(model, data, q, qd);
  }
  static phri::test::RandomChain make(int dof) {
    std::mt19937 rng(static_cast<unsigned>(1000 + dof));
    return phri::test::make_random_chain(dof, rng);
  }
  phri::test::RandomChain chain;
  phri::Model model;
  phri::Data data;
  Eigen::VectorXd q, qd, qdd;
};

void ScalingAllTerms(benchmark::State& state) {
  Chain c(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(phri::compute_all_terms(c.model, c.data, c.q, c.qd));
}
BENCHMARK(ScalingAllTerms)->Arg(6)->Arg(7)->Arg(14)->Arg(30);

void ScalingCrba(benchmark::State& state) {
  Chain c(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(phri::crba(c.model, c.data, c.q).data());
}
BENCHMARK(ScalingCrba)->Arg(6)->Arg(7)->Arg(14)->Arg(30);

void ScalingRnea(benchmark::State& state) {
  Chain c(static_cast<int>(state.range(0)));
  for (auto _ : state) benchmark::DoNotOptimize(phri::rnea(c.model, c.data, c.q, c.qd, c.qdd).data());
}
BENCHMARK(ScalingRnea)->Arg(6)->Arg(7)->Arg(14)->Arg(30);

void ScalingTipJacobian(benchmark::State& state) {
  Chain c(static_cast<int>(state.range(0)));
  const int tip = c.model.frame_id(c.chain.tip_link);
  Eigen::MatrixXd jacobian(6, c.model.nv());
  for (auto _ : state) {
    phri::frame_jacobian(c.model, c.data, tip, phri::ReferenceFrame::kLocalWorldAligned, jacobian);
    benchmark::DoNotOptimize(jacobian.data());
  }
}
BENCHMARK(ScalingTipJacobian)->Arg(6)->Arg(7)->Arg(14)->Arg(30);

// Capsules on every moving link of the 30-DoF chain; the first `pairs` non-adjacent pairs.
std::string capsules_yaml(const phri::test::RandomChain& chain, int pairs) {
  std::ostringstream yaml;
  yaml << "capsules:\n";
  std::vector<std::string> links;
  for (const std::string& link : chain.link_names) {
    if (link.rfind("link_", 0) != 0) continue;
    links.push_back(link);
    yaml << "  - {link: " << link << ", p0: [0, 0, 0], p1: [0, 0, 0.1], radius: 0.02}\n";
  }
  yaml << "pairs:\n";
  int written = 0;
  for (std::size_t i = 0; i < links.size() && written < pairs; ++i) {
    for (std::size_t j = i + 2; j < links.size() && written < pairs; ++j, ++written) {
      yaml << "  - [" << links[i] << ", " << links[j] << "]\n";
    }
  }
  return yaml.str();
}

void ScalingCapsulePairs(benchmark::State& state) {
  Chain c(30);
  const phri::CollisionModel collision =
      phri::CollisionModel::from_yaml_string(capsules_yaml(c.chain, static_cast<int>(state.range(0))), c.model);
  if (collision.num_pairs() != state.range(0)) state.SkipWithError("not enough capsule pairs");
  phri::CollisionData out(c.model, collision);
  for (auto _ : state) {
    phri::compute_collision_distances(c.model, c.data, collision, out, true);
    benchmark::DoNotOptimize(out.distance.data());
  }
}
BENCHMARK(ScalingCapsulePairs)->Arg(10)->Arg(50)->Arg(200);

// A drive table for the generated chain: the same drive on every joint, strong enough to hold
// the 30-DoF chain against gravity (2000 N.m), so that every chain runs the normal cycle.
phri::ActuatorTable generic_drives(const phri::Model& model) {
  std::vector<phri::ActuatorParameters> joints;
  for (const phri::Joint& joint : model.joints()) {
    phri::ActuatorParameters a;
    a.joint_name = joint.name;
    a.gear_ratio = 100.0;
    a.torque_constant_Nm_per_A = 0.1;
    a.rotor_inertia_kgm2 = 3e-6;
    a.reflected_inertia_kgm2 = 0.03;
    a.current_limit_A = 200.0;
    a.torque_limit_Nm = 1500.0;
    a.velocity_limit_rad_s = 1.5;
    joints.push_back(a);
  }
  return phri::ActuatorTable(std::move(joints));
}

// The arm at rest near q0: gravity on the torque sensors, a few micro-units of sensor noise (a
// bit-identical stream would be refused as frozen by the supervisor), the commanded mode echoed.
void next_state(phri::RobotState& s, const Eigen::VectorXd& q0, const Eigen::VectorXd& gravity,
                const phri::RobotCommand& command) {
  s.time_s += 1e-3;
  ++s.cycle;
  const double k = static_cast<double>(s.cycle);
  for (int i = 0; i < q0.size(); ++i) {
    s.q_rad[i] = q0[i] + 1e-6 * std::sin(0.37 * k + i);
    s.qd_rad_s[i] = 1e-4 * std::sin(0.21 * k + i);
    s.tau_sensor_Nm[i] = gravity[i] + 0.01 * std::sin(0.13 * k + i);
    s.current_A[i] = s.tau_sensor_Nm[i] / 10.0;
  }
  s.mode = command.mode;
  for (phri::SignalStatus* signal : {&s.joints, &s.torque, &s.current, &s.wrench}) {
    signal->valid = true;
    ++signal->sequence;
    signal->stamp_s = s.time_s;
  }
}

void ScalingControllerCycle(benchmark::State& state) {
  Chain c(static_cast<int>(state.range(0)));
  phri::ControllerSettings settings;
  settings.end_effector_frame = c.chain.tip_link;
  settings.payloads.clear();
  settings.initial_loop = phri::LowLevelMode::kCurrent;
  phri::Model model = phri::Model::from_urdf_string(c.chain.urdf, phri::Controller::model_options(settings));
  const int n = model.nq();
  phri::Controller cycle(std::move(model), generic_drives(c.model), std::nullopt, settings);
  const Eigen::VectorXd q0 = 0.1 * c.q;
  const Eigen::VectorXd gravity = phri::compute_gravity(c.model, c.data, q0);
  phri::RobotState s(n);
  phri::RobotCommand command(n);
  for (int k = 0; k < 500; ++k) {  // past the F/T bias window and the start-up transients
    next_state(s, q0, gravity, command);
    cycle.step(s, command);
  }
  if (cycle.status() != phri::CycleStatus::kOk) {
    state.SkipWithError(("cycle status " + std::string(phri::to_string(cycle.status()))).c_str());
  }
  for (auto _ : state) {
    next_state(s, q0, gravity, command);
    cycle.step(s, command);
    benchmark::DoNotOptimize(command.current_A.data());
  }
  if (cycle.status() != phri::CycleStatus::kOk) state.SkipWithError("the cycle left its normal path");
}
BENCHMARK(ScalingControllerCycle)->Arg(6)->Arg(7)->Arg(14)->Arg(30);

}  // namespace
