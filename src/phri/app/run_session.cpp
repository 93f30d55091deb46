#include <phri/app/run_session.hpp>

#include <phri/app/log_row.hpp>
#include <phri/app/loop_clock.hpp>
#include <phri/core/statistics.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <ostream>
#include <unistd.h>

namespace phri {
namespace {

struct PhaseAccumulator {
  double pos_max = 0, pos_sq = 0, ori_max = 0, ori_sq = 0, wrench_max = 0;
  long n = 0;
  int compliance_switches = 0, loop_switches = 0;
  std::size_t first_cycle = 0;
};

}  // namespace

RunSummary run_session(RobotInterface& robot, Controller& cycle, Fsm& fsm, Gamepad* gamepad, Logger* logger,
                       const RunOptions& options, std::ostream& out) {
  RunSummary summary;
  const double period = robot.period_s();
  const std::size_t max_cycles = static_cast<std::size_t>(std::ceil(options.duration_s / period));
  std::vector<double> micros(max_cycles, 0.0);  // before the loop: no allocation inside it
  std::vector<PhaseMark> phases = options.phases;
  if (phases.empty()) phases.push_back({0.0, "run"});
  std::vector<PhaseAccumulator> acc(phases.size());
  std::size_t phase = 0;
  const bool tty = options.status_line && isatty(fileno(stdout));

  RobotCommand command(robot.dof());
  LogRow row;
  LoopClock clock(period, options.real_time ? LoopClock::Pacing::kRealTime : LoopClock::Pacing::kLockstep);
  const auto wall_start = std::chrono::steady_clock::now();
  int consecutive_overruns = 0;
  double next_status = 0.0;
  ComplianceMode last_mode = cycle.compliance().mode();
  int last_touches = cycle.compliance().touch_count();
  int last_loop_switches = cycle.low_level().switch_count();
  std::size_t k = 0;
  for (; k < max_cycles; ++k) {
    const RobotState& state = robot.read();
    const double t = state.time_s;
    while (phase + 1 < phases.size() && t >= phases[phase + 1].start_s) {
      ++phase;
      acc[phase].first_cycle = k;
      if (!tty) out << "[" << t << " s] phase: " << phases[phase].name << "\n";
    }
    const auto start = std::chrono::steady_clock::now();
    if (gamepad) {
      Event event;
      while (gamepad->poll(event)) fsm.post(event);
    }
    const CycleStatus status = cycle.step(state, fsm.update(t, state, cycle), command);
    const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    micros[k] = us;
    robot.write(command);
    if (logger) {
      fill_log_row(row, state, cycle, fsm);
      row.cycle_time_s = 1e-6 * us;
      logger->push(row);
    }

    // ---- per-phase statistics
    PhaseAccumulator& a = acc[phase];
    const Vector6d& error = cycle.qp().end_effector().error();
    const double pos = 1e3 * error.head<3>().norm(), ori = error.tail<3>().norm() * 180.0 / M_PI;
    a.pos_max = std::max(a.pos_max, pos);
    a.pos_sq += pos * pos;
    a.ori_max = std::max(a.ori_max, ori);
    a.ori_sq += ori * ori;
    a.wrench_max = std::max(a.wrench_max, cycle.wrench().norm());
    ++a.n;
    if (cycle.compliance().mode() != last_mode || cycle.compliance().touch_count() != last_touches) ++a.compliance_switches;
    if (cycle.low_level().switch_count() != last_loop_switches) ++a.loop_switches;
    last_mode = cycle.compliance().mode();
    last_touches = cycle.compliance().touch_count();
    last_loop_switches = cycle.low_level().switch_count();

    // ---- safety: stale or invalid data, or two overruns in a row
    if (!summary.safe_hold && (status == CycleStatus::kStaleState || status == CycleStatus::kInvalidState)) {
      summary.safe_hold = true;
      summary.safe_hold_reason = std::string("sensor data ") + std::string(to_string(status)) + " at t = " + std::to_string(t) + " s";
      fsm.post(Event::kStop);
      out << "phri: SAFE HOLD: " << summary.safe_hold_reason << "; braking to rest\n";
    }
    const double late = clock.wait_next();
    consecutive_overruns = late > 0.0 ? consecutive_overruns + 1 : 0;
    if (consecutive_overruns >= 2 && !summary.safe_hold) {
      summary.safe_hold = true;
      summary.safe_hold_reason = "two consecutive overruns of the " + std::to_string(1e3 * period) + " ms period at t = " + std::to_string(t) + " s";
      fsm.post(Event::kStop);
      out << "phri: SAFE HOLD: " << summary.safe_hold_reason << "; braking to rest\n";
    }

    // ---- status
    if (options.status_line && t >= next_status) {
      next_status = t + (tty ? 0.2 : 5.0);
      char line[200];  // string_views printed with %.*s: no allocation in the loop
      const std::string_view mode = to_string(cycle.compliance().mode());
      const std::string_view loop = to_string(cycle.low_level().loop());
      std::snprintf(line, sizeof line, "t %6.2f s | %-10.*s | loop %-27.*s | EE error %6.2f mm | wrench %5.1f | cycle %5.1f us",
                    t, static_cast<int>(mode.size()), mode.data(), static_cast<int>(loop.size()), loop.data(), pos,
                    cycle.wrench().norm(), us);
      if (tty) {
        out << "\r" << line << std::flush;
      } else {
        out << line << "\n";
      }
    }
    if (fsm.finished()) {
      ++k;
      break;
    }
  }
  if (tty) out << "\n";
  summary.cycles = k;
  summary.simulated_s = static_cast<double>(k) * period;
  summary.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  summary.overruns = clock.overruns();
  summary.held_cycles = cycle.held_cycles();
  for (std::size_t p = 0; p < phases.size(); ++p) {
    PhaseSummary s;
    s.name = phases[p].name;
    s.start_s = phases[p].start_s;
    s.end_s = p + 1 < phases.size() ? phases[p + 1].start_s : summary.simulated_s;
    const PhaseAccumulator& a = acc[p];
    if (a.n > 0) {
      s.ee_position_error_max_mm = a.pos_max;
      s.ee_position_error_rms_mm = std::sqrt(a.pos_sq / static_cast<double>(a.n));
      s.ee_orientation_error_max_deg = a.ori_max;
      s.ee_orientation_error_rms_deg = std::sqrt(a.ori_sq / static_cast<double>(a.n));
      s.wrench_norm_max = a.wrench_max;
      s.compliance_switches = a.compliance_switches;
      s.loop_switches = a.loop_switches;
      std::vector<double> slice(micros.begin() + static_cast<std::ptrdiff_t>(a.first_cycle),
                                micros.begin() + static_cast<std::ptrdiff_t>(a.first_cycle + static_cast<std::size_t>(a.n)));
      s.cycle_median_us = percentile(slice, 0.5);
      s.cycle_p999_us = percentile(slice, 0.999);
    }
    summary.phases.push_back(s);
  }
  std::vector<double> all(micros.begin(), micros.begin() + static_cast<std::ptrdiff_t>(k));
  summary.cycle_median_us = percentile(all, 0.5);
  summary.cycle_p99_us = percentile(all, 0.99);
  summary.cycle_p999_us = percentile(all, 0.999);
  summary.cycle_max_us = all.empty() ? 0.0 : *std::max_element(all.begin(), all.end());
  return summary;
}

void print_run_summary(const RunSummary& s, std::ostream& out) {
  char line[400];
  std::snprintf(line, sizeof line,
                "%llu cycles, %.1f s simulated in %.1f s of wall time; controller cycle: median %.1f us, p99 %.1f us, "
                "p99.9 %.1f us, max %.1f us; %llu overruns; %ld held cycles%s\n\n",
                static_cast<unsigned long long>(s.cycles), s.simulated_s, s.wall_s, s.cycle_median_us, s.cycle_p99_us,
                s.cycle_p999_us, s.cycle_max_us, static_cast<unsigned long long>(s.overruns), s.held_cycles,
                s.safe_hold ? (" ; SAFE HOLD: " + s.safe_hold_reason).c_str() : "");
  out << line;
  out << "| phase | from s | to s | EE pos max mm | EE pos RMS mm | EE ori max deg | EE ori RMS deg | wrench max | mode switches | loop switches | cycle median us | cycle p99.9 us |\n";
  out << "|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const PhaseSummary& p : s.phases) {
    std::snprintf(line, sizeof line, "| %s | %.1f | %.1f | %.2f | %.2f | %.2f | %.2f | %.1f | %d | %d | %.1f | %.1f |\n",
                  p.name.c_str(), p.start_s, p.end_s, p.ee_position_error_max_mm, p.ee_position_error_rms_mm,
                  p.ee_orientation_error_max_deg, p.ee_orientation_error_rms_deg, p.wrench_norm_max,
                  p.compliance_switches, p.loop_switches, p.cycle_median_us, p.cycle_p999_us);
    out << line;
  }
}

}  // namespace phri
