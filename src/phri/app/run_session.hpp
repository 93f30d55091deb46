#pragma once
// phri::run_session: the control loop of `phri run` — read -> FSM -> Controller -> write -> log,
// once per period, in lockstep (as fast as possible) or paced by the real-time clock, with the
// same code path. It measures every cycle's compute time, reports a status line (~5 Hz on a
// terminal, plain progress lines otherwise) and, at the end, cycle-time statistics and a table per
// phase (phases are named spans of the run, e.g. the scripted demo's steps).
//
// Safety: every transition of the controller's StateSupervisor is printed with its reason; a
// refused write() is reported to the controller as a fault (safe stop). A safe stop, or two
// consecutive overruns of the real-time period, post a stop to the FSM (brake to rest, hold) and
// are reported once, clearly. Short sensor faults (a spike, a few missing frames) only degrade:
// the controller holds the last good state, then resumes.
#include <phri/control/controller.hpp>
#include <phri/app/fsm.hpp>
#include <phri/app/gamepad.hpp>
#include <phri/app/live_channel.hpp>
#include <phri/app/snapshot_channel.hpp>
#include <phri/app/logger.hpp>
#include <phri/robot/ground_truth.hpp>
#include <phri/robot/push_input.hpp>
#include <phri/robot/robot_interface.hpp>

#include <atomic>
#include <iosfwd>
#include <string>
#include <vector>

namespace phri {

struct PhaseMark {
  double start_s = 0.0;
  std::string name;
};

struct RunOptions {
  double duration_s = 30.0;
  bool real_time = false;           ///< false: lockstep; true: also SCHED_FIFO where allowed (RealTimePriorityScope)
  bool status_line = true;          ///< a refreshed line on a terminal, progress lines otherwise
  std::vector<PhaseMark> phases;    ///< sorted by start; empty: one phase "run"
  /// A live front end (the dashboard), or null. Its commands are taken at the start of each
  /// cycle (events and gains go to the FSM like the gamepad's; pushes to `pushes`), and it is one
  /// of the run's observers (its snapshots). While paused the loop holds between two cycles (the
  /// simulation and the controller stop together) and polls the channel every 1 ms.
  LiveChannel* live = nullptr;
  /// Where the live front end's pushes go (a simulated arm: the backend that built the robot hands
  /// it over), or null: pushes are ignored.
  PushInput* pushes = nullptr;
  /// The plant's true joint positions (a simulated arm), or null. Given, the summary's end-effector
  /// errors are target - the true end effector (forward kinematics of the true link-side joints);
  /// the QP's own task error is kept beside them, labelled as such.
  const GroundTruth* ground_truth = nullptr;
  /// Observers of the run besides the live front end (a recorder, a bridge, a second monitor): each
  /// gets every `decimation`-th cycle's snapshot through its own lock-free ring; a full ring drops
  /// the snapshot, so none can block or slow the cycle. Each must outlive the run.
  std::vector<SnapshotChannel*> observers;
  /// Further sources of commands besides `live` (the ROS 2 bridge): their events and end-effector
  /// targets are taken at the start of each cycle like the live front end's; anything else they
  /// send (pushes, pause) is ignored. Each must outlive the run; feed its snapshots through
  /// `observers`.
  std::vector<LiveChannel*> inputs;
  /// A stop asked from outside the loop (apps/phri.cpp: SIGINT, SIGTERM), or null. Loaded once a
  /// cycle (no wait, no allocation); once true, the run ends after that cycle as if its duration had
  /// run out, with RunSummary::interrupted set.
  const std::atomic<bool>* stop_requested = nullptr;
  /// The body regions each link may meet (Config::body_regions), or null. Given, and the robot has
  /// capsules, every cycle's power-and-force-limiting figures (control/power_force_limit.hpp:
  /// PowerForceLimitMonitor) go into the log's pfl_ columns and the summary, on the ground truth's
  /// state when there is one, else on the measured state.
  const BodyRegionMap* body_regions = nullptr;
};

struct PhaseSummary {
  std::string name;
  double start_s = 0.0, end_s = 0.0;
  double ee_position_error_max_mm = 0.0, ee_position_error_rms_mm = 0.0;
  double ee_orientation_error_max_deg = 0.0, ee_orientation_error_rms_deg = 0.0;
  /// Whether the ee_* errors above are measured from the plant's true state (RunOptions::ground_truth);
  /// false: they are the QP's task error (all a real arm's run has).
  bool ee_error_true = false;
  /// The QP's own end-effector task error (target - the controller's estimate of the pose).
  double qp_task_position_error_max_mm = 0.0, qp_task_position_error_rms_mm = 0.0;
  double wrench_norm_max = 0.0;
  int compliance_switches = 0;   ///< compliance mode changes and dual-compliance touches
  int loop_switches = 0;
  double cycle_median_us = 0.0, cycle_p999_us = 0.0;
};

struct RunSummary {
  std::uint64_t cycles = 0;
  double simulated_s = 0.0, wall_s = 0.0;
  double cycle_median_us = 0.0, cycle_p99_us = 0.0, cycle_p999_us = 0.0, cycle_max_us = 0.0;
  std::uint64_t overruns = 0;
  long held_cycles = 0;
  std::uint64_t refused_writes = 0;
  std::uint64_t safety_transitions = 0;  ///< supervisor state changes
  std::uint64_t degraded_spells = 0;     ///< entries into the degraded state
  bool safe_hold = false;
  std::string safe_hold_reason;
  bool interrupted = false;              ///< ended by RunOptions::stop_requested before its duration
  std::vector<PhaseSummary> phases;
  /// Per link with a capsule (RunOptions::body_regions); empty: no body regions configured.
  std::vector<ContactLinkSummary> contact;
  bool contact_true_state = false;       ///< measured on the plant's true state (a ground truth)
};

/// Runs the loop for options.duration_s of robot time (or until the FSM has stopped and the arm
/// is at rest after a stop event, or options.stop_requested is set). `gamepad` and `logger` may be null.
RunSummary run_session(RobotInterface& robot, Controller& cycle, Fsm& fsm, Gamepad* gamepad, Logger* logger,
                       const RunOptions& options, std::ostream& out);

/// The end-of-run report: cycle statistics, the per-phase table and the power-and-force-limiting
/// table (markdown).
void print_run_summary(const RunSummary& summary, std::ostream& out);
/// The power-and-force-limiting table alone (a line when nothing was measured).
void print_contact_summary(const RunSummary& summary, std::ostream& out);
/// The same of any run's links (ContactRecorder::links()), measured on `state` ("the plant's true
/// state", "the measured state"): the worst link's line and a markdown table.
void print_contact_table(const std::vector<ContactLinkSummary>& links, const char* state, std::ostream& out);

}  // namespace phri
