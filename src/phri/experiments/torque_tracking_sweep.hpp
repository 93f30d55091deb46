#pragma once
// Static torque tracking against the plant's drive-gain error: why the static ratio depends on the
// arm, and how large the error must be for the paper's figure to appear.
//
// At rest the link is in static equilibrium, so the torque sensor reads tau_s = g - tau_ext
// whatever the motor does; the error e = tau_d - tau_s is then fixed by where the joints stopped,
// and a joint stays stopped while the drive's surplus |tau_m - tau_s| is below its static friction
// tau_st. With a drive that delivers k x the torque it is asked for (k = true / nominal K_T G_r):
//   Kinova high-velocity loop (DC gain 1):   tau_m = k (tau_d + e)       -> stuck while |(k - 1) tau_s + 2 k e| <= tau_st
//   custom loop (lambda H + K_I/(s+theta)): tau_m = k (tau_d + 25 e)    -> stuck while |(k - 1) tau_s + 26 k e| <= tau_st
// (DC gain lambda + K_I/theta = 5 + 20). A joint whose gain error pushes (k - 1) tau_s beyond
// tau_st slides until the task's PD raises e to the edge of that band: about tau_st/2 ~ 1 N.m for
// Kinova's loop against tau_st/26 ~ 0.08 N.m for the custom loop. Below that the joint never
// moves and both loops show the same error (model error plus sensor noise).
//
// The sweep runs the static scenario for both loops at drive-gain errors f (each joint's K_T G_r
// off by a uniform draw in [-f, f]) over several mismatch seeds, and reports the high-velocity /
// custom RMS ratio per f (median, min, max over the seeds).
#include <phri/experiments/torque_tracking.hpp>

#include <cstdint>
#include <iosfwd>
#include <vector>

namespace phri {

struct StaticSweepOptions {
  TorqueTrackingOptions tracking;  ///< scenario settings; scenarios/loops/output are set by the sweep
  std::vector<double> torque_constant_errors = {0.0, 0.05, 0.10, 0.15, 0.20, 0.25};
  std::vector<std::uint64_t> mismatch_seeds = {1, 2, 3, 4, 5};
  std::string output_dir = "results/torque_tracking_sweep";
  std::string figure_script = "tools/report/static_sweep_figure.py";
};

struct StaticSweepRow {
  double torque_constant_error = 0.0;
  std::uint64_t mismatch_seed = 0;
  double custom_rms_Nm = 0.0, high_velocity_rms_Nm = 0.0;
  double custom_bias_Nm = 0.0, high_velocity_bias_Nm = 0.0;
  double ratio = 0.0;  ///< high-velocity RMS / custom RMS
};

struct StaticSweepSummary {
  double torque_constant_error = 0.0;
  double median_ratio = 0.0, min_ratio = 0.0, max_ratio = 0.0;
  double median_custom_rms_Nm = 0.0, median_high_velocity_rms_Nm = 0.0;
};

struct StaticSweepResult {
  std::vector<StaticSweepRow> rows;
  std::vector<StaticSweepSummary> summary;  ///< one per error, in the options' order
  double simulated_s = 0.0, wall_s = 0.0;
  std::vector<std::string> files;
};

/// Runs the sweep (progress lines on `progress`, may be null); writes static_sweep.csv (one row per
/// error x seed) and static_sweep.md (the summary table) into output_dir when it is not empty.
/// Throws ConfigError on bad options, and what run_torque_tracking throws.
StaticSweepResult run_static_sweep(const StaticSweepOptions& options, std::ostream* progress = nullptr);

/// The summary table (markdown).
std::string static_sweep_table(const StaticSweepResult& result, const StaticSweepOptions& options);

/// The CLI's `phri experiment torque-tracking --static-sweep`: run, write, draw, print. Returns 0;
/// failures throw (phri::Error, as run_static_sweep).
int run_static_sweep_command(const StaticSweepOptions& options, std::ostream& out);

}  // namespace phri
