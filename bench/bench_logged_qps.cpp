// LoggedQpReplay: the controller's own QPs, recorded in the demo session (bench/data/demo_qps.bin,
// bench/data/README.md; phri_record_qps), replayed through phri::QpSolver tick by tick, each solve
// timed alone (steady_clock): LoggedQpReplay/warm from the active set the controller's solver
// started from, with its options, as in the session; LoggedQpReplay/cold from the unconstrained
// minimum. Reports per tick (its fastest of 5 passes) the median, p99 and worst in microseconds, the
// worst tick's index in the file and its session cycle; the active-set changes (QpSolver::iterations)
// in all and the ticks with at least one; and max |x - x_recorded|: 0 when warm and the solver's
// arithmetic is the recording's (bit for bit), rounding otherwise (~2e-11 since the unconstrained
// start takes x from L instead of J = L^-T, after the file was recorded):
//   build/release/bench/phri_bench --benchmark_filter=LoggedQpReplay
#include "logged_qps.hpp"

#include <phri/core/error.hpp>
#include <phri/core/statistics.hpp>

#include <benchmark/benchmark.h>

#include <algorithm>
#include <chrono>
#include <cstddef>
#include <limits>
#include <optional>
#include <string>
#include <vector>

namespace {

// The file, read once for both variants; an unreadable file skips the benchmark with its reason.
const phri::LoggedQps* demo_qps(std::string& error) {
  static std::string load_error;
  static const std::optional<phri::LoggedQps> qps = []() -> std::optional<phri::LoggedQps> {
    try {
      return phri::read_logged_qps(std::string(PHRI_SOURCE_DIR) + "/bench/data/demo_qps.bin");
    } catch (const phri::IoError& e) {
      load_error = e.what();
      return std::nullopt;
    }
  }();
  error = load_error;
  return qps ? &*qps : nullptr;
}

// One pass over the file: each tick's solve timed alone into micros; the solver's figures summed.
struct PassResult {
  double changes = 0, ticks_with_changes = 0, max_abs_dx = 0;
};
PassResult replay_pass(const phri::LoggedQps& qps, phri::QpSolver& solver, bool warm, std::vector<double>& micros) {
  PassResult r;
  for (std::size_t k = 0; k < qps.ticks.size(); ++k) {
    const phri::LoggedQpTick& tick = qps.ticks[k];
    const phri::QpSolveOptions options = phri::prepare_replay(tick, solver, warm);
    const auto start = std::chrono::steady_clock::now();
    solver.solve(tick.problem, options);
    micros[k] = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    r.changes += solver.iterations();
    r.ticks_with_changes += solver.iterations() > 0 ? 1 : 0;
    r.max_abs_dx = std::max(r.max_abs_dx, (solver.x() - tick.x).cwiseAbs().maxCoeff());
  }
  return r;
}

// kPasses passes; a tick's time is its fastest: a preemption or an interrupt (this is a shared
// machine) seldom hits the same tick in every pass. worst_any_pass_us keeps the slowest solve seen.
void LoggedQpReplay(benchmark::State& state, bool warm) {
  constexpr int kPasses = 5;
  std::string error;
  const phri::LoggedQps* qps = demo_qps(error);
  if (qps == nullptr) {
    state.SkipWithError(error.c_str());
    return;
  }
  phri::QpSolver solver(qps->n, qps->m_eq, qps->m_in);
  solver.settings() = qps->settings;
  const std::size_t ticks = qps->ticks.size();
  std::vector<double> micros(ticks), fastest(ticks);
  PassResult result;
  double worst_any_pass = 0.0;
  for (auto _ : state) {
    std::fill(fastest.begin(), fastest.end(), std::numeric_limits<double>::infinity());
    for (int pass = 0; pass < kPasses; ++pass) {
      result = replay_pass(*qps, solver, warm, micros);
      for (std::size_t k = 0; k < ticks; ++k) fastest[k] = std::min(fastest[k], micros[k]);
      worst_any_pass = std::max(worst_any_pass, *std::max_element(micros.begin(), micros.end()));
    }
  }
  const auto worst = static_cast<std::size_t>(std::max_element(fastest.begin(), fastest.end()) - fastest.begin());
  state.counters["ticks"] = static_cast<double>(ticks);
  state.counters["median_us"] = phri::percentile(fastest, 0.5);
  state.counters["p99_us"] = phri::percentile(fastest, 0.99);
  state.counters["worst_us"] = fastest[worst];
  state.counters["worst_tick"] = static_cast<double>(worst);
  state.counters["worst_cycle"] = qps->ticks[worst].cycle;
  state.counters["worst_any_pass_us"] = worst_any_pass;
  state.counters["as_changes"] = result.changes;
  state.counters["ticks_changed"] = result.ticks_with_changes;
  state.counters["max_abs_dx"] = result.max_abs_dx;
}
BENCHMARK_CAPTURE(LoggedQpReplay, warm, true)->Iterations(1)->Unit(benchmark::kMillisecond);
BENCHMARK_CAPTURE(LoggedQpReplay, cold, false)->Iterations(1)->Unit(benchmark::kMillisecond);

}  // namespace
