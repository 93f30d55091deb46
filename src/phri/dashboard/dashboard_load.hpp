#pragma once
// phri::run_dashboard_load: what the dashboard costs the control loop. One process runs the
// same session (configuration, seed, real-time pacing) in segments, alternately without the
// dashboard and with it serving a crowd of stream clients that connect, read a few frames and
// leave (StreamClients), and compares the loop's p99.9 compute time per cycle. Each segment is
// a fresh robot, controller and FSM, so both conditions replay the same robot time; the figure
// of a condition is the median of its segments' p99.9.
//
//   phri experiment dashboard-load [--config configs/dashboard.yaml] [--segment-s 10] [--repeats 3] [--clients 100]
#include <iosfwd>
#include <string>
#include <vector>

namespace phri {

struct DashboardLoadOptions {
  std::string config_path = "configs/dashboard.yaml";
  double segment_s = 10.0;  ///< robot time of a segment (real-time pacing: as long in wall time)
  int repeats = 3;          ///< pairs of segments (without, with)
  int clients = 100;        ///< stream connections during each segment with the dashboard
  std::string web_root = "web";
};

struct DashboardLoadSegment {
  bool dashboard = false;
  double cycle_median_us = 0.0, cycle_p999_us = 0.0, cycle_max_us = 0.0;
  unsigned long long overruns = 0;
  int clients_served = 0, clients_failed = 0;
  long resident_kb = 0;  ///< after the segment
};

struct DashboardLoadResult {
  std::vector<DashboardLoadSegment> segments;
  double p999_without_us = 0.0, p999_with_us = 0.0;
  double ratio = 0.0;  ///< with / without
};

DashboardLoadResult run_dashboard_load(const DashboardLoadOptions& options, std::ostream& progress);
/// Runs it and prints a table and the ratio; 0 unless a segment failed to run.
int run_dashboard_load_command(const DashboardLoadOptions& options, std::ostream& out);

}  // namespace phri
