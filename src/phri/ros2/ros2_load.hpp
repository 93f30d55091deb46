#pragma once
// phri::run_ros2_load: what the ROS 2 bridge costs the control loop, and how old a remote F/T sample
// is when the controller uses it. One process runs the same session (configuration, real-time
// pacing) in segments, alternately without the bridge and with it: publishing every topic (the
// configuration's decimations), a subscriber of all of them (a second participant), and the F/T
// sensor from /phri/ft_in published by a separate process, `phri ft-bridge --emulate` (the Bota
// emulator on a pseudo-terminal -> the serial driver -> DDS over loopback UDP -> the bridge ->
// the cycle). Each segment is a fresh robot, controller and FSM. Figures: the loop's p99.9 compute
// time per cycle (median of the segments of each condition), and the F/T round trip: a sample's age
// at the first cycle that reads it (bridge take -> controller), p50 / p99 over all segments with
// the bridge, plus the publisher-to-cycle latency from the samples' stamps.
//
//   phri experiment ros2-load [--config configs/dashboard.yaml] [--segment-s 5] [--repeats 3] [--ros-domain N]
#include <iosfwd>
#include <string>
#include <vector>

namespace phri {

struct Ros2LoadOptions {
  std::string config_path = "configs/dashboard.yaml";
  std::string phri_program;  ///< the phri executable (for `phri ft-bridge --emulate`); empty: no F/T peer
  double segment_s = 5.0;
  int repeats = 3;
  int domain = 47;
};

struct Ros2LoadSegment {
  bool bridge = false;
  double cycle_median_us = 0.0, cycle_p999_us = 0.0, cycle_max_us = 0.0;
  unsigned long long overruns = 0, snapshots = 0, snapshots_dropped = 0, received = 0, ft_samples = 0;
};

struct Ros2LoadResult {
  std::vector<Ros2LoadSegment> segments;
  double p999_without_us = 0.0, p999_with_us = 0.0, ratio = 0.0;
  std::vector<double> ft_ages_s;  ///< every F/T sample's age at the cycle, all segments with the bridge
  double ft_age_p50_ms = 0.0, ft_age_p99_ms = 0.0;
  std::vector<double> ft_stamp_ages_s;  ///< the same from the publisher's stamps (sensor read -> cycle)
  double ft_stamp_age_p50_ms = 0.0, ft_stamp_age_p99_ms = 0.0;
};

Ros2LoadResult run_ros2_load(const Ros2LoadOptions& options, std::ostream& progress);
/// Runs it and prints the segments and the figures; 0 unless it could not run.
int run_ros2_load_command(const Ros2LoadOptions& options, std::ostream& out);

}  // namespace phri
