#pragma once
// `phri evaluate`: the paper's five evaluations in one run on the simulated Gen3, each into its own
// folder of `output_dir`, then one report (tools/report/evaluation_report.py: report.md and a
// self-contained report.html, figures inline, each table beside the paper's numbers):
//   friction_identification/  friction identification (identify_friction)
//   torque_tracking/          torque tracking, static and dynamic, custom vs Kinova high-velocity,
//                             with each run's elastic modes (elastic_modes.hpp)
//   torque_tracking_rigid/    the same on rigid joints, a labelled sensitivity row (not with `quick`)
//   drop_test/                30 + 30 drops, torque vs position mode (run_drop_test)
//   dynamic_tracking/         the dynamic scenario with position, custom, Kinova torque and
//                             Kinova high-velocity loops: y and z position and velocity errors
//   dual_compliance/          guiding the end effector by hand, release, drift
//   sensitivity/<variant>/    the drop test with one setting changed (not with `quick`);
//                             sensitivity/variants.csv: each row's parameter, setting and source
// Every evaluation runs the same plant (use_evaluation_plant): elastic joints, the paper's open-loop
// position mode; every run is checked (run_validity.hpp) and an invalid one is flagged and excluded.
// `quick` shortens every protocol (the ctest of the report; numbers are then not the paper's protocol).
#include <phri/experiments/torque_tracking.hpp>

#include <iosfwd>
#include <string>

namespace phri {

struct EvaluationOptions {
  std::string output_dir = "results/evaluation";
  bool quick = false;
  int jobs = 2;
  int drops = 30;          ///< per mode (quick: 4)
  int sensitivity_drops = 6;  ///< per mode and variant
  /// Torque tracking's runs per loop and scenario, on independent plants (not with quick): the main
  /// run and tracking_runs - 1 more, so that the report can test the loops' difference.
  int tracking_runs = 6;
  /// Files, relative to the working directory (the CLI resolves them against the source tree).
  std::string root = ".";
  std::string report_script = "tools/report/evaluation_report.py";
};

/// Issue 39: one plant for every evaluation, the drop test's: elastic joints (the torque sensors measure
/// the springs, the Kinova loops run on them as on the Gen3) and the paper's open-loop position mode.
void use_evaluation_plant(TorqueTrackingOptions& options);

/// `phri experiment dynamic-tracking`: the torque-tracking experiment's dynamic scenario with the
/// four low-level loops of the paper's Fig. dynamic-comparison (position, custom, Kinova torque,
/// Kinova high-velocity), into results/dynamic_tracking, on the evaluation's plant; the y/z errors
/// are in its summary CSV.
TorqueTrackingOptions dynamic_tracking_options();

/// Runs everything, prints progress on `out`, writes the report; returns 0, or 1 when the report
/// script failed (the experiments' files are written either way). Throws phri::Error.
int run_evaluation_command(const EvaluationOptions& options, std::ostream& out);

}  // namespace phri
