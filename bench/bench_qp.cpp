// QpSolver on the controller's QP (7 joint accelerations) and on a random 30 x 60 problem.
//   ./build/release/phri_bench --benchmark_filter=Qp --benchmark_repetitions=10
//       --benchmark_report_aggregates_only=true
// Every solve factorises H (the controller's H changes every cycle) unless the name says Reuse.
#include <phri/qp/qp_solver.hpp>

#include <benchmark/benchmark.h>

#include <Eigen/QR>

#include <cmath>
#include <limits>
#include <random>
#include <vector>

namespace {

using Eigen::MatrixXd;
using Eigen::VectorXd;

constexpr double kInf = std::numeric_limits<double>::infinity();

MatrixXd gaussian(std::mt19937_64& rng, Eigen::Index rows, Eigen::Index cols) {
  std::normal_distribution<double> normal;
  MatrixXd m(rows, cols);
  for (Eigen::Index j = 0; j < cols; ++j)
    for (Eigen::Index i = 0; i < rows; ++i) m(i, j) = normal(rng);
  return m;
}

// The controller's QP: a heavily weighted end-effector task w_ee |J qdd - a|^2 (J 6 x 7), a light
// posture task w_0 |qdd - qdd_0|^2 and a tiny regularisation; 7 acceleration bounds, 7 torque
// rows tau_min - h <= M qdd <= tau_max - h, 10 one-sided self-collision rows. The limits are
// placed so that 4 constraints are active at the optimum (2 bounds, 1 torque row, 1 collision).
struct ControllerQp {
  phri::QpProblem problem;
  MatrixXd jacobian;
  VectorXd task;
  double w_ee = 1e4;
  double w_posture = 1.0;
  double regularisation = 1e-6;

  void set_task(const VectorXd& a) {
    task = a;
    problem.g = -w_ee * jacobian.transpose() * a;
  }
};

ControllerQp make_controller_qp() {
  std::mt19937_64 rng(42);
  ControllerQp c;
  constexpr Eigen::Index n = 7;
  c.problem.resize(n, 0, 17);
  c.jacobian = gaussian(rng, 6, n);
  c.problem.H = c.w_ee * c.jacobian.transpose() * c.jacobian +
                (c.w_posture + c.regularisation) * MatrixXd::Identity(n, n);
  c.set_task(20.0 * gaussian(rng, 6, 1).col(0));

  const MatrixXd b = gaussian(rng, n, n);
  const MatrixXd mass = 0.1 * b * b.transpose() + 0.2 * MatrixXd::Identity(n, n);
  const VectorXd bias = gaussian(rng, n, 1).col(0);
  const MatrixXd collision = gaussian(rng, 10, n);

  // Place the limits around the unconstrained optimum.
  const VectorXd x_free = -c.problem.H.llt().solve(c.problem.g);
  const VectorXd tau = mass * x_free;
  const VectorXd dist = collision * x_free;
  for (Eigen::Index j = 0; j < n; ++j) {
    const double limit = (j == 1 || j == 4) ? 0.7 * std::abs(x_free(j)) : 2.0 * std::abs(x_free(j)) + 1.0;
    c.problem.lb(j) = -limit;
    c.problem.ub(j) = limit;
  }
  c.problem.A.topRows(n) = mass;
  for (Eigen::Index i = 0; i < n; ++i) {
    // |M qdd + h| <= tau_max, i.e. -tau_max - h <= M qdd <= tau_max - h.
    const double tau_max = (i == 2) ? 0.6 * std::abs(tau(i) + bias(i)) : 2.0 * std::abs(tau(i) + bias(i)) + 5.0;
    c.problem.l(i) = -tau_max - bias(i);
    c.problem.u(i) = tau_max - bias(i);
  }
  c.problem.A.bottomRows(10) = collision;
  for (Eigen::Index i = 0; i < 10; ++i) {
    // a_i qdd >= b_i: cuts off the unconstrained optimum for row 6 only.
    c.problem.l(n + i) = (i == 6) ? dist(i) + 0.5 * std::abs(dist(i)) + 1.0 : dist(i) - std::abs(dist(i)) - 1.0;
    c.problem.u(n + i) = kInf;
  }
  return c;
}

phri::QpProblem make_random_qp(Eigen::Index n, Eigen::Index m) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  phri::QpProblem p;
  p.resize(n, 0, m);
  const MatrixXd q = Eigen::HouseholderQR<MatrixXd>(gaussian(rng, n, n)).householderQ();
  VectorXd eig(n);
  for (Eigen::Index i = 0; i < n; ++i) eig(i) = std::pow(10.0, 3.0 * static_cast<double>(i) / static_cast<double>(n - 1));
  p.H = q * eig.asDiagonal() * q.transpose();
  p.H = 0.5 * (p.H + p.H.transpose()).eval();
  p.g = 30.0 * gaussian(rng, n, 1).col(0);
  const VectorXd x_f = gaussian(rng, n, 1).col(0);
  p.A = gaussian(rng, m, n);
  const VectorXd v = p.A * x_f;
  for (Eigen::Index i = 0; i < m; ++i) {
    p.l(i) = v(i) - 2.0 * unit(rng);
    p.u(i) = v(i) + 2.0 * unit(rng);
  }
  return p;
}

void report(benchmark::State& state, const phri::QpSolver& solver) {
  if (solver.status() != phri::QpStatus::kOptimal) state.SkipWithError("QP not solved to optimality");
  state.counters["active"] = static_cast<double>(solver.active_count());
  state.counters["iterations"] = static_cast<double>(solver.iterations());
}

void BM_QpControllerCold(benchmark::State& state) {
  const ControllerQp c = make_controller_qp();
  phri::QpSolver solver(7, 0, 17);
  for (auto _ : state) {
    solver.solve(c.problem);
    benchmark::DoNotOptimize(solver.x().data());
  }
  report(state, solver);
}
BENCHMARK(BM_QpControllerCold);

void BM_QpControllerWarm(benchmark::State& state) {
  const ControllerQp c = make_controller_qp();
  phri::QpSolver solver(7, 0, 17);
  solver.solve(c.problem);
  for (auto _ : state) {
    solver.solve(c.problem, {.warm_start = true});
    benchmark::DoNotOptimize(solver.x().data());
  }
  report(state, solver);
}
BENCHMARK(BM_QpControllerWarm);

void BM_QpControllerWarmReuseFactor(benchmark::State& state) {
  const ControllerQp c = make_controller_qp();
  phri::QpSolver solver(7, 0, 17);
  solver.solve(c.problem);
  for (auto _ : state) {
    solver.solve(c.problem, {.warm_start = true, .reuse_hessian_factor = true});
    benchmark::DoNotOptimize(solver.x().data());
  }
  report(state, solver);
}
BENCHMARK(BM_QpControllerWarmReuseFactor);

// Successive cycles: the task target drifts a little each millisecond, the warm start is the
// previous cycle's active set.
void BM_QpControllerWarmDrifting(benchmark::State& state) {
  ControllerQp c = make_controller_qp();
  std::mt19937_64 rng(3);
  std::vector<phri::QpProblem> cycles;
  VectorXd task = c.task;
  for (int k = 0; k < 64; ++k) {
    task += 0.05 * gaussian(rng, 6, 1).col(0);
    c.set_task(task);
    cycles.push_back(c.problem);
  }
  phri::QpSolver solver(7, 0, 17);
  solver.solve(cycles.front());
  std::size_t k = 0;
  for (auto _ : state) {
    solver.solve(cycles[k], {.warm_start = true});
    benchmark::DoNotOptimize(solver.x().data());
    k = (k + 1) % cycles.size();
  }
  report(state, solver);
}
BENCHMARK(BM_QpControllerWarmDrifting);

void BM_QpRandom30x60Cold(benchmark::State& state) {
  const phri::QpProblem p = make_random_qp(30, 60);
  phri::QpSolver solver(30, 0, 60);
  for (auto _ : state) {
    solver.solve(p);
    benchmark::DoNotOptimize(solver.x().data());
  }
  report(state, solver);
}
BENCHMARK(BM_QpRandom30x60Cold);

void BM_QpRandom30x60Warm(benchmark::State& state) {
  const phri::QpProblem p = make_random_qp(30, 60);
  phri::QpSolver solver(30, 0, 60);
  solver.solve(p);
  for (auto _ : state) {
    solver.solve(p, {.warm_start = true});
    benchmark::DoNotOptimize(solver.x().data());
  }
  report(state, solver);
}
BENCHMARK(BM_QpRandom30x60Warm);

}  // namespace
