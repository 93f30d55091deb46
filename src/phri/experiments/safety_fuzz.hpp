#pragma once
// Safety fuzzing on the simulated Gen3 (`phri experiment safety-fuzz`): seeded, reproducible
// hostile testing of phri::Controller and its safety stage.
//
// The arm holds the paper demo's posture [0, 0.58, 3.14, -1.84, 0, 0.85, 1.57] (the plant starts
// there) with the controller's targets fixed; each run starts in the position loop, switches to the
// loop under test after position_phase_s and settles for settle_s (the pushes: and, when the arm
// still moves, until it is still, for at most 2 s more). Then:
//
// 1. Pushes, on every compliance mode (stiff, null_space, full_body, dual) x low-level loop
//    (position, kinova_torque, kinova_torque_high_velocity, custom) pair: `pushes` random pushes
//    split over the 16 pairs (0-200 N on a random moving link, random point of its capsule, random
//    direction into it, step / ramp / half-sine, 0.05-2 s), pushes_per_run per run, the next one
//    starting when the arm is back and settled; plus, per pair, sustained 60 N pushes driving each
//    limited joint toward each of its limits (2 s) and a wrist fold toward the base (3 s).
// 2. Sensor faults (FaultInjectingRobot between the plant and the controller) on an arm at rest:
//    the catalogue of safety_fuzz_cases.hpp, each for 1 and for 100 cycles (a fault with a length of
//    its own, a stall, a one-sample jump, a held offset or a drift, for that), on every loop and on
//    fault_modes; each
//    (mode, loop) has a fault-free reference run with the same plant seed whose path the faulted
//    runs are compared with (the decorator passes the plant's state through bit for bit outside
//    the fault's window, so both runs are identical until it opens).
// 2b. Faults in motion (motion_faults): on every compliance mode x loop pair (kSubset: the
//    fault_modes, three of the faults), one push drawn from the seed (a ramp to 20-80 N lasting
//    1-2 s on a random moving link's capsule; in dual compliance a hand on the tool, below the F/T
//    sensor, so that the dual trigger engages), and every fault of the catalogue starting at a random
//    time 0.1-0.5 s into the push (drawn from the seed and the fault's name), for its length in motion
//    (100 cycles for sustained faults, 1 for spikes and one-sample jumps; a stall is one read of its
//    periods). Each pair has a fault-free reference run with the same push and plant seed (the
//    "motion-reference"; judged itself as a push), whose path the faulted runs are compared with
//    after the fault, indexed by the plant's cycle (a stall skips ahead). And after a loop switch:
//    the run stays in the position loop through the warm-up, the push begins, 0.1-0.5 s into it the
//    controller is switched to the loop under test on the moving arm, and each fault starts 0-50 ms
//    after the sample the reference switched on (a "switch-reference" per pair; no such windows
//    for the position loop).
//    In dual compliance an arm at rest after the hand let go counts as back (it keeps the pose it is
//    pushed to), as for the pushes.
// 3. Every cycle, on the plant's truth: joint limits, |q̇| > 1.05 x its limit, capsule distances,
//    non-finite commands, refused writes (the harness reports each to the controller; one not
//    followed by a safe stop is "unhandled"), exceptions and a diverged plant. After each push or
//    fault: back within 0.05 rad of the reference (the held pose; for dual compliance, which keeps
//    the pose it is pushed to: at rest) within 3 s plus the walk back (d / 0.15 rad/s after a window
//    that took the arm d rad away: ReturnLeash's speed), or in a logged safe stop at rest within 1 s.
//    A window with a violation is operator-possible when its push asked more than the actuators can
//    resist (safety_fuzz_metrics.hpp), a controller failure otherwise. After a safe stop, a window
//    without recovery or a crash, the run goes on with a fresh plant and controller.
//
// Run ids: push/<mode>/<loop>/<n>, targeted/<mode>/<loop>, reference/<mode>/<loop>,
// fault/<mode>/<loop>/<fault>/<cycles> (at rest), motion-reference/<mode>/<loop>,
// motion/<mode>/<loop>/<fault>, switch-reference/<mode>/<loop>, switch/<mode>/<loop>/<fault>.
// Runs are independent, deterministic functions of (seed, run id, pushes, pushes_per_run): they
// run on `jobs` threads (each SimRobot has its own mjModel/mjData; MuJoCo's model compiler is
// serialized) and any one can be replayed alone (`replay`, the ids in the report).
#include <phri/control/compliance_mode.hpp>
#include <phri/experiments/safety_fuzz_cases.hpp>
#include <phri/experiments/safety_fuzz_metrics.hpp>
#include <phri/robot/low_level_mode.hpp>

#include <cstdint>
#include <iosfwd>
#include <string>
#include <vector>

namespace phri {

struct SafetyFuzzOptions {
  // ---- files (relative paths are relative to the working directory)
  std::string plant_config_path = "configs/plant_gen3.yaml";
  std::string urdf_path = "robots/kinova_gen3/gen3.urdf";
  std::string end_effector_frame = "end_effector_link";  ///< the URDF's frame the end of arm mounts on
  std::string actuators_path = "robots/kinova_gen3/actuators.yaml";
  std::string collision_path = "robots/kinova_gen3/collision.yaml";
  /// A robot bundle (robots/<robot>) in place of the four files above and of start_q_rad: its
  /// plant (generated from its URDF, or its MJCF), drives, chain, end of arm and collision.yaml
  /// (capsules fitted from its URDF when it has none); the start posture is its home. Empty: the files.
  std::string robot_folder;
  std::string output_dir = "results/safety_fuzz";  ///< empty: no files
  std::string figure_script = "tools/report/safety_fuzz_figure.py";  ///< empty: no figure

  // ---- what to run
  std::uint64_t seed = 1;
  int pushes = 3000;           ///< random pushes, split over the 16 mode x loop pairs
  int pushes_per_run = 8;
  bool targeted_pushes = true; ///< joint-limit pushes and wrist folds on every pair
  FaultSet faults = FaultSet::kAll;
  std::vector<ComplianceMode> fault_modes = {ComplianceMode::kNullSpace, ComplianceMode::kFullBody};
  /// The loops to fuzz; those the robot's drive does not offer (robot.yaml `drive:`) are skipped
  /// (not run, not counted; SafetyFuzzResult::skipped_loops): a Kinova arm runs the first four, a
  /// generic drive position, custom (current) and its plain torque loop.
  std::vector<LowLevelMode> loops = {LowLevelMode::kPosition, LowLevelMode::kKinovaTorque,
                                     LowLevelMode::kKinovaTorqueHighVelocity, LowLevelMode::kCurrent,
                                     LowLevelMode::kTorque};
  std::vector<ComplianceMode> modes = {ComplianceMode::kStiff, ComplianceMode::kNullSpace, ComplianceMode::kFullBody,
                                       ComplianceMode::kDual};
  std::vector<long> fault_cycles = {1, 100};  ///< at rest, for the faults without a length of their own
  bool motion_faults = true;   ///< with faults: the fault-in-motion and loop-switch windows (2b above)
  MotionFaultRanges motion;
  int jobs = 2;
  std::string replay;          ///< run only this run (an id of the report); empty: all
  std::string trace_path;      ///< with replay: every cycle of the replayed run as CSV; empty: none

  // ---- plant and protocol
  bool model_mismatch = true;  ///< plant link inertials ±5 % from the controller's URDF
  std::vector<double> start_q_rad = {0.0, 0.58, 3.14, -1.84, 0.0, 0.85, 1.57};
  double position_phase_s = 0.4;  ///< position loop before the switch (F/T bias)
  double settle_s = 0.6;          ///< after the switch, before the first push or fault
  double min_pause_s = 0.2;       ///< after a push, at least this before the next
  double fault_observation_s = 1.0;  ///< after a fault, at least this (the arm must stay back)
  RandomPushRanges push_ranges;
  double targeted_force_N = 60.0;
  double limit_push_s = 2.0;
  double wrist_fold_s = 3.0;
  SafetyFuzzThresholds thresholds;
};

enum class FuzzCaseKind : std::uint8_t { kRandomPush = 0, kLimitPush, kWristFold, kFault, kReference, kStartup };

constexpr std::string_view to_string(FuzzCaseKind k) {
  switch (k) {
    case FuzzCaseKind::kRandomPush: return "push";
    case FuzzCaseKind::kLimitPush: return "limit_push";
    case FuzzCaseKind::kWristFold: return "wrist_fold";
    case FuzzCaseKind::kFault: return "fault";
    case FuzzCaseKind::kReference: return "reference";
    case FuzzCaseKind::kStartup: return "startup";
  }
  return "unknown";
}

/// One push or fault window (or a reference run, or a start-up that failed) and its verdict.
struct FuzzRecord {
  std::string run_id;     ///< replay id of the run it belongs to
  int index = 0;          ///< in the run
  FuzzCaseKind kind = FuzzCaseKind::kRandomPush;
  ComplianceMode mode = ComplianceMode::kStiff;
  LowLevelMode loop = LowLevelMode::kPosition;
  std::uint64_t plant_seed = 0;
  double start_s = 0.0;   ///< plant time the push or fault began
  // push
  std::string target;     ///< push: link; fault: catalogue name
  int joint = -1;         ///< fault or limit push: joint (0-based)
  double force_N = 0.0;
  std::string profile;
  double duration_s = 0.0;
  // fault
  long fault_cycles = 0;
  std::string fault_kind;    ///< the decorator's FaultKind (to_string)
  std::string context;       ///< fault or its reference: "rest", "motion" or "switch"; pushes: empty
  std::string push_link;     ///< motion / switch: the link (or tool) the push lands on
  double fault_offset_s = 0.0;  ///< motion: after the push began; switch: after the sample the switch took effect on
  WindowMetrics metrics;
  FuzzVerdict verdict;
  std::string safe_stop_reason;
  std::string error;      ///< crash: what happened
};

struct SafetyFuzzResult {
  std::vector<FuzzRecord> records;
  int runs = 0;           ///< plant + controller constructions
  double simulated_s = 0.0;
  double wall_s = 0.0;
  std::vector<std::string> files;
  /// Loops of the options the drive does not offer: their mode x loop rows were not run.
  std::vector<LowLevelMode> skipped_loops;
  int skipped_rows = 0;  ///< mode x loop pairs not run (modes x skipped_loops)

  long controller_failures() const;
  long invalid_windows() const;  ///< windows whose loop or mode under test did not run (never passes)
  long held_command_windows() const;  ///< overspeeds on a held command (FuzzVerdict::held_command)
  long passes() const;           ///< valid windows without a violation
  long pushes() const;    ///< push windows (random and targeted)
  long faults() const;    ///< fault windows, at rest, in motion and after a loop switch
  long faults_in(std::string_view context) const;  ///< "rest", "motion" or "switch"
};

/// Runs everything the options ask for; progress lines on `progress` (may be null). Writes the
/// CSV (safety_fuzz.csv) and the report (report.md) into options.output_dir when set. Throws
/// ConfigError on bad options or input files (a replay id that names no run), IoError when an output
/// cannot be written; a run that throws is recorded (crash), not rethrown.
SafetyFuzzResult run_safety_fuzz(const SafetyFuzzOptions& options, std::ostream* progress = nullptr);

/// The CSV: one row per record.
std::string safety_fuzz_csv(const SafetyFuzzResult& result);
/// The Markdown report: counts per mode x loop, worst margins, controller failures with replay commands.
std::string safety_fuzz_report(const SafetyFuzzResult& result, const SafetyFuzzOptions& options);

/// `phri experiment safety-fuzz`: run, write the files, draw the figure, print the summary.
/// Returns 1 when fail_on_violation and there were controller failures, else 0.
int run_safety_fuzz_command(const SafetyFuzzOptions& options, bool fail_on_violation, std::ostream& out);

}  // namespace phri
