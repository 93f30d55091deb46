#include <phri/dashboard/dashboard_load.hpp>

#include <phri/config/config.hpp>
#include <phri/app/run_session.hpp>
#include <phri/core/statistics.hpp>
#include <phri/dashboard/dashboard_server.hpp>
#include <phri/dashboard/stream_clients.hpp>
#include <phri/sim/sim_robot.hpp>

#include <cstdio>
#include <memory>
#include <optional>
#include <ostream>
#include <sstream>

namespace phri {
namespace {

DashboardLoadSegment run_segment(const Config& config, const DashboardLoadOptions& o, bool with_dashboard) {
  SimRobot robot(config.plant);
  Controller cycle(config.controller);
  Fsm fsm(config.fsm, cycle);
  RunOptions run;
  run.duration_s = o.segment_s;
  run.real_time = true;
  run.status_line = false;
  LiveChannel live;
  std::unique_ptr<DashboardServer> server;
  std::optional<StreamClients> clients;
  if (with_dashboard) {
    DashboardSettings settings;
    settings.port = 0;
    settings.web_root = o.web_root;
    server = std::make_unique<DashboardServer>(live, cycle, settings);
    run.live = &live;
    run.pushes = &robot;
    StreamClientsSettings crowd;
    crowd.port = server->port();
    crowd.token = server->token();
    crowd.connections = o.clients;
    crowd.spread_s = 0.8 * o.segment_s;
    clients.emplace(crowd);
  }
  std::ostringstream quiet;  // the session's progress lines
  const RunSummary summary = run_session(robot, cycle, fsm, nullptr, nullptr, run, quiet);
  DashboardLoadSegment segment;
  segment.dashboard = with_dashboard;
  segment.cycle_median_us = summary.cycle_median_us;
  segment.cycle_p999_us = summary.cycle_p999_us;
  segment.cycle_max_us = summary.cycle_max_us;
  segment.overruns = summary.overruns;
  if (clients) {
    clients->join();
    segment.clients_served = clients->served();
    segment.clients_failed = clients->failed();
  }
  if (server) server->stop();
  segment.resident_kb = resident_kb();
  return segment;
}

}  // namespace

DashboardLoadResult run_dashboard_load(const DashboardLoadOptions& options, std::ostream& progress) {
  Config config = Config::from_yaml_file(options.config_path);
  DashboardLoadResult result;
  std::vector<double> without, with;
  for (int r = 0; r < options.repeats; ++r) {
    for (bool dashboard : {false, true}) {
      result.segments.push_back(run_segment(config, options, dashboard));
      const DashboardLoadSegment& s = result.segments.back();
      (dashboard ? with : without).push_back(s.cycle_p999_us);
      char line[200];
      std::snprintf(line, sizeof line, "segment %d %-17s p99.9 %6.1f us  median %5.1f us  clients %d/%d  RSS %ld kB\n",
                    r + 1, dashboard ? "with dashboard" : "without dashboard", s.cycle_p999_us, s.cycle_median_us,
                    s.clients_served, s.clients_served + s.clients_failed, s.resident_kb);
      progress << line << std::flush;
    }
  }
  result.p999_without_us = percentile(without, 0.5);
  result.p999_with_us = percentile(with, 0.5);
  result.ratio = result.p999_without_us > 0.0 ? result.p999_with_us / result.p999_without_us : 0.0;
  return result;
}

int run_dashboard_load_command(const DashboardLoadOptions& options, std::ostream& out) {
  out << "dashboard load: " << options.repeats << " x (" << options.segment_s << " s without, " << options.segment_s
      << " s with the dashboard and " << options.clients << " stream clients), real time, " << options.config_path << "\n";
  const DashboardLoadResult r = run_dashboard_load(options, out);
  char line[240];
  std::snprintf(line, sizeof line,
                "loop p99.9 cycle time (median of segments): without %.1f us, with %.1f us; ratio with/without %.3f\n",
                r.p999_without_us, r.p999_with_us, r.ratio);
  out << line;
  return 0;
}

}  // namespace phri
