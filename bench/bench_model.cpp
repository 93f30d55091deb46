// Rigid-body algorithms on the Kinova Gen3 (7 DoF). Run:
//   build/release/bench/phri_bench --benchmark_filter=Model --benchmark_repetitions=10 --benchmark_report_aggregates_only=true
#include <phri/control/power_force_limit.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/fixed_size_ldlt.hpp>
#include <phri/model/collision_model.hpp>
#include <phri/model/model.hpp>
#include <phri/model/small_cholesky.hpp>

#include <benchmark/benchmark.h>

#include <Eigen/Cholesky>

#include <random>

namespace {

struct Gen3 {
  phri::Model model = phri::Model::from_urdf_file(std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/gen3.urdf");
  phri::Data data{model};
  Eigen::VectorXd q = Eigen::VectorXd::Zero(7), qd = Eigen::VectorXd::Zero(7), qdd = Eigen::VectorXd::Zero(7);
  Eigen::MatrixXd jacobian = Eigen::MatrixXd::Zero(6, 7);
  int ee = model.frame_id("end_effector_link");
  Gen3() {
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(-1.0, 1.0);
    for (int i = 0; i < 7; ++i) {
      q[i] = 2.0 * u(rng);
      qd[i] = u(rng);
      qdd[i] = 5.0 * u(rng);
    }
    phri::compute_all_terms(model, data, q, qd);
  }
};

void ModelForwardKinematics(benchmark::State& state) {
  Gen3 g;
  for (auto _ : state) {
    phri::forward_kinematics(g.model, g.data, g.q);
    phri::update_frame_placements(g.model, g.data);
    benchmark::DoNotOptimize(g.data.frame_placements.data());
  }
}
BENCHMARK(ModelForwardKinematics);

void ModelFrameJacobian(benchmark::State& state) {
  Gen3 g;
  for (auto _ : state) {
    phri::frame_jacobian(g.model, g.data, g.ee, phri::ReferenceFrame::kLocalWorldAligned, g.jacobian);
    benchmark::DoNotOptimize(g.jacobian.data());
  }
}
BENCHMARK(ModelFrameJacobian);

void ModelJdotQdot(benchmark::State& state) {
  // Velocities and drift accelerations (forward pass with qdd = 0), then the frame's bias.
  Gen3 g;
  const Eigen::VectorXd zero = Eigen::VectorXd::Zero(7);
  for (auto _ : state) {
    phri::forward_kinematics(g.model, g.data, g.q, g.qd, zero);
    g.data.frame_placements[static_cast<std::size_t>(g.ee)] =
        g.data.body_placements[static_cast<std::size_t>(g.model.frame(g.ee).body)] * g.model.frame(g.ee).placement;
    benchmark::DoNotOptimize(phri::frame_jdot_qdot(g.model, g.data, g.ee, phri::ReferenceFrame::kLocalWorldAligned));
  }
}
BENCHMARK(ModelJdotQdot);

void ModelCrba(benchmark::State& state) {
  Gen3 g;
  for (auto _ : state) {
    benchmark::DoNotOptimize(phri::crba(g.model, g.data, g.q).data());
  }
}
BENCHMARK(ModelCrba);

// The mass matrix's factor and one solve, phri::SmallCholesky (what Data holds) against Eigen's
// LLT<MatrixXd> on the same M; Arg: the Gen3's M (7), or a 30 x 30 SPD matrix (dynamic-size path).
Eigen::MatrixXd cholesky_input(int n) {
  if (n == 7) return Gen3().data.mass_matrix;
  std::mt19937 rng(30);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::MatrixXd a = Eigen::MatrixXd::NullaryExpr(n, n, [&] { return u(rng); });
  return a * a.transpose() + n * Eigen::MatrixXd::Identity(n, n);
}
void SmallCholeskyFactor(benchmark::State& state) {
  const Eigen::MatrixXd m = cholesky_input(static_cast<int>(state.range(0)));
  phri::SmallCholesky factor(m.rows());
  for (auto _ : state) benchmark::DoNotOptimize(factor.compute(m));
}
BENCHMARK(SmallCholeskyFactor)->Arg(7)->Arg(30);
void EigenLltCholeskyFactor(benchmark::State& state) {
  const Eigen::MatrixXd m = cholesky_input(static_cast<int>(state.range(0)));
  Eigen::LLT<Eigen::MatrixXd> factor(m.rows());
  for (auto _ : state) {
    factor.compute(m);
    benchmark::DoNotOptimize(factor.matrixLLT().data());
  }
}
BENCHMARK(EigenLltCholeskyFactor)->Arg(7)->Arg(30);
void SmallCholeskySolve(benchmark::State& state) {
  const Eigen::MatrixXd m = cholesky_input(static_cast<int>(state.range(0)));
  phri::SmallCholesky factor(m.rows());
  factor.compute(m);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(m.rows(), -1.0, 1.0);
  Eigen::VectorXd x = b;
  for (auto _ : state) {
    x = b;
    factor.solve_in_place(x);
    benchmark::DoNotOptimize(x.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(SmallCholeskySolve)->Arg(7)->Arg(30);
void EigenLltCholeskySolve(benchmark::State& state) {
  const Eigen::MatrixXd m = cholesky_input(static_cast<int>(state.range(0)));
  const Eigen::LLT<Eigen::MatrixXd> factor(m);
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(m.rows(), -1.0, 1.0);
  Eigen::VectorXd x = b;
  for (auto _ : state) {
    x = b;
    factor.solveInPlace(x);
    benchmark::DoNotOptimize(x.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(EigenLltCholeskySolve)->Arg(7)->Arg(30);

// The singular-direction weight's 6 x 6 step: factor J J^T (the Gen3's end-effector Jacobian at the
// fixture's posture; positive definite, so that neither stops early) and solve once,
// phri::FixedSizeLdlt<6> against Eigen's LLT<Matrix<double, 6, 6>>:
//   build/release/bench/phri_bench --benchmark_filter=6FactorSolve
Eigen::Matrix<double, 6, 6> task_space_input() {
  Gen3 g;
  phri::frame_jacobian(g.model, g.data, g.ee, phri::ReferenceFrame::kLocalWorldAligned, g.jacobian);
  return g.jacobian * g.jacobian.transpose();
}
void FixedSizeLdlt6FactorSolve(benchmark::State& state) {
  const Eigen::Matrix<double, 6, 6> a = task_space_input();
  const Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::LinSpaced(-1.0, 1.0);
  phri::FixedSizeLdlt<6> ldlt;
  for (auto _ : state) {
    benchmark::DoNotOptimize(ldlt.compute(a));
    Eigen::Matrix<double, 6, 1> x = b;
    ldlt.solve_in_place(x);
    benchmark::DoNotOptimize(x.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(FixedSizeLdlt6FactorSolve);
void EigenLlt6FactorSolve(benchmark::State& state) {
  const Eigen::Matrix<double, 6, 6> a = task_space_input();
  const Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::LinSpaced(-1.0, 1.0);
  Eigen::LLT<Eigen::Matrix<double, 6, 6>> llt(6);
  for (auto _ : state) {
    llt.compute(a);
    benchmark::DoNotOptimize(llt.info());
    Eigen::Matrix<double, 6, 1> x = llt.solve(b);
    benchmark::DoNotOptimize(x.data());
    benchmark::ClobberMemory();
  }
}
BENCHMARK(EigenLlt6FactorSolve);

void ModelRnea(benchmark::State& state) {
  Gen3 g;
  for (auto _ : state) {
    benchmark::DoNotOptimize(phri::rnea(g.model, g.data, g.q, g.qd, g.qdd).data());
  }
}
BENCHMARK(ModelRnea);

// What the controller needs each cycle: placements, velocities, M and its Cholesky factor, h,
// and the end effector's Jacobian and J̇q̇.
void ModelAllTogether(benchmark::State& state) {
  Gen3 g;
  for (auto _ : state) {
    phri::compute_all_terms(g.model, g.data, g.q, g.qd);
    phri::frame_jacobian(g.model, g.data, g.ee, phri::ReferenceFrame::kLocalWorldAligned, g.jacobian);
    benchmark::DoNotOptimize(phri::frame_jdot_qdot(g.model, g.data, g.ee, phri::ReferenceFrame::kLocalWorldAligned));
    benchmark::DoNotOptimize(g.jacobian.data());
  }
}
BENCHMARK(ModelAllTogether);

// The same plus a separate RNEA with a desired acceleration (the controller's tau_d).
void ModelAllTogetherPlusRnea(benchmark::State& state) {
  Gen3 g;
  for (auto _ : state) {
    phri::compute_all_terms(g.model, g.data, g.q, g.qd);
    phri::frame_jacobian(g.model, g.data, g.ee, phri::ReferenceFrame::kLocalWorldAligned, g.jacobian);
    benchmark::DoNotOptimize(phri::frame_jdot_qdot(g.model, g.data, g.ee, phri::ReferenceFrame::kLocalWorldAligned));
    benchmark::DoNotOptimize(phri::rnea(g.model, g.data, g.q, g.qd, g.qdd).data());
  }
}
BENCHMARK(ModelAllTogetherPlusRnea);

// What a run adds per cycle with body_regions (app/run_session.cpp, outside the controller's timed
// step): the terms of the judged state, then every monitored link's power-and-force-limiting figures.
void PowerForceLimitMonitorCycle(benchmark::State& state) {
  Gen3 g;
  const phri::CollisionModel capsules =
      phri::CollisionModel::from_yaml_file(std::string(PHRI_SOURCE_DIR) + "/robots/kinova_gen3/collision.yaml", g.model);
  phri::BodyRegionMap regions;
  regions.region = {"lower_arm_wrist", 40000.0, 2.0, 160.0, 2.0};
  phri::PowerForceLimitMonitor monitor(g.model, capsules, Eigen::VectorXd::Constant(7, 0.3), regions);
  for (auto _ : state) {
    phri::compute_all_terms(g.model, g.data, g.q, g.qd);
    monitor.update(g.model, g.data);
    benchmark::DoNotOptimize(monitor.worst_link());
  }
  state.counters["links"] = monitor.num_links();
}
BENCHMARK(PowerForceLimitMonitorCycle);

}  // namespace
