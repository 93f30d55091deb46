#include <phri/app/run_session.hpp>

#include <phri/app/fill_log_row.hpp>
#include <phri/app/loop_clock.hpp>
#include <phri/core/statistics.hpp>
#include <phri/model/algorithms.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <optional>
#include <ostream>
#include <string>
#include <string_view>
#include <thread>
#include <utility>
#include <vector>

#include <unistd.h>

namespace phri {
namespace {

constexpr std::uint64_t kMaxPrintedTransitions = 20;
constexpr int kMaxSteps = 1 << 30;  // single steps asked and not yet run (they add up)

// The sums of one phase, for its row of the summary table.
struct PhaseAccumulator {
  double pos_max = 0, pos_sq = 0, ori_max = 0, ori_sq = 0, wrench_max = 0, qp_pos_max = 0, qp_pos_sq = 0;
  long n = 0;
  int compliance_switches = 0, loop_switches = 0;
  std::size_t first_cycle = 0;

  void add(double pos, double ori, double wrench, double qp_pos) {
    qp_pos_max = std::max(qp_pos_max, qp_pos);
    qp_pos_sq += qp_pos * qp_pos;
    pos_max = std::max(pos_max, pos);
    pos_sq += pos * pos;
    ori_max = std::max(ori_max, ori);
    ori_sq += ori * ori;
    wrench_max = std::max(wrench_max, wrench);
    ++n;
  }
};

// One run of the loop: its state between cycles, one method per job of a cycle. Everything the
// loop touches is sized in the constructor: a cycle allocates nothing (but a safe-hold message).
class Session {
public:
  Session(RobotInterface& robot, Controller& cycle, Fsm& fsm, Gamepad* gamepad, Logger* logger, const RunOptions& options,
          std::ostream& out)
      : robot_(robot),
        cycle_(cycle),
        fsm_(fsm),
        gamepad_(gamepad),
        logger_(logger),
        options_(options),
        out_(out),
        period_(robot.period_s()),
        max_cycles_(static_cast<std::size_t>(std::ceil(options.duration_s / period_))),
        micros_(max_cycles_, 0.0),
        phases_(options.phases.empty() ? std::vector<PhaseMark>{{0.0, "run"}} : options.phases),
        acc_(phases_.size()),
        tty_(options.status_line && isatty(fileno(stdout))),
        command_(robot.dof()),
        clock_(period_, options.real_time ? LoopClock::Pacing::kRealTime : LoopClock::Pacing::kLockstep),
        last_mode_(cycle.compliance().mode()),
        last_touches_(cycle.compliance().touch_count()),
        last_loop_switches_(cycle.low_level().switch_count()),
        live_(options.live),
        pushes_(options.pushes),
        ground_truth_(options.ground_truth),
        truth_data_(cycle.model()),
        observers_(options.observers) {
    if (live_) observers_.push_back(&live_->snapshots());
    if (live_ && pushes_) push_targets_ = push_targets(cycle.model(), *pushes_);
    if (options.body_regions != nullptr && cycle.collision() != nullptr) {
      Eigen::VectorXd rotor(cycle.model().nv());
      for (int i = 0; i < rotor.size(); ++i) rotor[i] = cycle.actuators()[i].reflected_inertia_kgm2;
      contact_.emplace(cycle.model(), *cycle.collision(), rotor, *options.body_regions);
      summary_.contact_true_state = has_true_state();
    }
  }

  RunSummary run() {
    const RealTimePriorityScope priority(options_.real_time);
    if (options_.real_time && !priority.granted()) {
      out_ << "phri: note: no real-time scheduling priority (SCHED_FIFO) for the loop; a busy machine may make it overrun\n";
    }
    const auto wall_start = std::chrono::steady_clock::now();
    std::size_t k = 0;
    for (; k < max_cycles_; ++k) {
      if (live_) take_live_commands();
      for (LiveChannel* input : options_.inputs) take_input_commands(*input);
      const RobotState& state = robot_.read();
      const double t = state.time_s;
      enter_phases(t, k);
      const CycleStatus status = control_cycle(state, k);
      const double pos = accumulate_phase();
      check_safety(status);
      check_overruns(clock_.wait_next(), t);
      print_status(t, pos, micros_[k]);
      if (!observers_.empty()) publish_to_observers(k);
      if (fsm_.finished()) {
        ++k;
        break;
      }
      if (stop_requested()) {
        summary_.interrupted = true;
        ++k;
        break;
      }
    }
    if (tty_) out_ << "\n";
    summary_.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    summarize(k);
    if (contact_) summary_.contact = contact_->links();
    return summary_;
  }

private:
  bool stop_requested() const {
    return options_.stop_requested != nullptr && options_.stop_requested->load(std::memory_order_relaxed);
  }

  // Moves to the phases that have started by t; without a status line, says so.
  void enter_phases(double t, std::size_t k) {
    while (phase_ + 1 < phases_.size() && t >= phases_[phase_ + 1].start_s) {
      ++phase_;
      acc_[phase_].first_cycle = k;
      if (!tty_) out_ << "[" << t << " s] phase: " << phases_[phase_].name << "\n";
    }
  }

  // Gamepad -> FSM -> Controller -> robot and log; the compute time is cycle k's entry of micros_.
  CycleStatus control_cycle(const RobotState& state, std::size_t k) {
    const auto start = std::chrono::steady_clock::now();
    if (gamepad_) {
      Event event;
      while (gamepad_->poll(event)) fsm_.post(event);
    }
    const CycleStatus status = cycle_.step(state, fsm_.update(state.time_s, state, cycle_), command_);
    const double us = std::chrono::duration<double, std::micro>(std::chrono::steady_clock::now() - start).count();
    micros_[k] = us;
    // A refused command leaves the robot on its previous one (a stale torque, a set-point it may
    // not reach): a fault the controller answers in this cycle (its safe stop, a hold re-targeted).
    if (robot_.write(command_) != WriteStatus::kOk) {
      ++summary_.refused_writes;
      if (cycle_.answer_refused_write(state, command_) && robot_.write(command_) != WriteStatus::kOk) {
        ++summary_.refused_writes;
      }
    }
    monitor_contact(state);
    if (logger_ || !observers_.empty()) {
      fill_log_row(row_, state, cycle_, fsm_);
      row_.cycle_time_s = 1e-6 * us;
      // The live push acts from the read after its request until its hold runs out unrenewed.
      row_.live_push_N = push_.body >= 0 && row_.time_s > push_start_s_ && row_.time_s <= push_end_s_ ? push_.force_world.norm() : 0.0;
      fill_contact_columns();
    }
    if (logger_) logger_->push(row_);
    return status;
  }

  // The push target of each model body (by link name), found before the loop.
  static std::vector<int> push_targets(const Model& model, const PushInput& pushes) {
    std::vector<int> bodies(static_cast<std::size_t>(model.num_bodies()), -1);
    for (const Frame& f : model.frames()) {
      if (f.type == FrameType::kLink && f.body >= 0 && f.placement.isApprox(Eigen::Isometry3d::Identity()) &&
          bodies[static_cast<std::size_t>(f.body)] < 0) {
        bodies[static_cast<std::size_t>(f.body)] = pushes.push_target(f.name);
      }
    }
    return bodies;
  }

  // Takes the front end's commands; while paused, waits here (between two cycles) until it runs
  // again or asks for steps. The wait restarts the real-time schedule: a pause is no overrun.
  void take_live_commands() {
    for (LiveCommand c; live_->receive(c);) handle_live(c);
    if (!paused_) return;
    bool waited = false, shown = row_.time_s <= 0.0;
    while (paused_ && steps_ == 0 && !stop_requested()) {
      // The page learns it is paused, and sees the last cycle (retried: the queue may be full
      // of the snapshots of a burst of steps).
      if (!shown) shown = live_->publish(fill_snapshot());
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      for (LiveCommand c; live_->receive(c);) handle_live(c);
      waited = true;
    }
    if (steps_ > 0) --steps_;
    if (waited) clock_.start();
  }

  // Events and targets of a further source (RunOptions::inputs); the rest is not theirs to ask.
  void take_input_commands(LiveChannel& input) {
    for (LiveCommand c; input.receive(c);) {
      if (c.kind == LiveCommand::Kind::kEvent) fsm_.post(c.event);
      if (c.kind == LiveCommand::Kind::kTarget) fsm_.post(c.target);
    }
  }

  void handle_live(const LiveCommand& c) {
    switch (c.kind) {
      case LiveCommand::Kind::kEvent: fsm_.post(c.event); break;
      case LiveCommand::Kind::kTarget: fsm_.post(c.target); break;
      case LiveCommand::Kind::kGain: fsm_.post(c.gain); break;
      case LiveCommand::Kind::kPush: start_push(c.push); break;
      case LiveCommand::Kind::kRelease: end_push(); break;
      case LiveCommand::Kind::kRun: paused_ = false; steps_ = 0; break;
      case LiveCommand::Kind::kPause: paused_ = true; steps_ = 0; break;
      case LiveCommand::Kind::kStep: paused_ = true; steps_ = std::min(steps_ + std::max(1, c.steps), kMaxSteps); break;
    }
  }

  // A push on the arm from the next read() on, for push_hold_s unless renewed.
  void start_push(const LivePush& push) {
    if (!pushes_ || push.body < 0 || push.body >= static_cast<int>(push_targets_.size()) ||
        push_targets_[static_cast<std::size_t>(push.body)] < 0) {
      return;
    }
    const double hold_s = live_->settings().push_hold_s;
    pushes_->push(push_targets_[static_cast<std::size_t>(push.body)], push.point_local, push.force_world, hold_s);
    push_start_s_ = row_.time_s;  // the latest state's time, where the push's hold starts
    push_end_s_ = push_start_s_ + hold_s;
    push_ = push;
  }

  void end_push() {
    if (pushes_) pushes_->push(-1, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero(), 0.0);
    push_.body = -1;
  }

  // Every observer whose cycle it is gets this cycle's snapshot (all of them while paused).
  void publish_to_observers(std::size_t k) {
    bool filled = false;
    for (SnapshotChannel* observer : observers_) {
      if (!paused_ && !observer->due(k)) continue;
      if (!filled) fill_snapshot();
      filled = true;
      observer->publish(snapshot_);
    }
  }

  // The last cycle's row and what the loop knows beside it.
  const LiveSnapshot& fill_snapshot() {
    if (push_.body >= 0 && (row_.time_s < push_start_s_ || row_.time_s >= push_end_s_)) push_.body = -1;  // ran out unrenewed
    snapshot_.row = row_;
    snapshot_.dof = robot_.dof();
    snapshot_.push = push_;
    snapshot_.paused = paused_;
    const ComplianceController& compliance = cycle_.compliance();
    snapshot_.ee_gamma_override = compliance.ee_gamma_override();
    snapshot_.posture_gamma_override = compliance.posture_gamma_override();
    snapshot_.posture_stiffness = compliance.posture_stiffness();
    snapshot_.overruns = clock_.overruns();
    snapshot_.contact_links = contact_ ? std::min(contact_->monitor().num_links(), kLiveMaxContactLinks) : 0;
    for (int i = 0; i < snapshot_.contact_links; ++i) {
      snapshot_.contact_ratio[static_cast<std::size_t>(i)] = contact_->monitor().link(i).ratio();
    }
    return snapshot_;
  }

  bool has_true_state() const {
    const auto n = static_cast<Eigen::Index>(cycle_.model().nq());
    return ground_truth_ != nullptr && ground_truth_->true_joint_positions().size() == n &&
           ground_truth_->true_joint_velocities().size() == n;
  }

  // The power-and-force-limiting figures of every monitored link this cycle, on the plant's true
  // state when known (the state a person would meet), into the run's per-link maxima.
  void monitor_contact(const RobotState& state) {
    if (!contact_) return;
    const bool truth = has_true_state();
    contact_->record(cycle_.model(), truth ? ground_truth_->true_joint_positions() : state.q_rad,
                     truth ? ground_truth_->true_joint_velocities() : state.qd_rad_s, period_);
  }

  void fill_contact_columns() {
    const int worst = contact_ ? contact_->monitor().worst_link() : -1;
    row_.pfl_link = worst;
    const ContactPointState none;
    const ContactPointState& p = worst >= 0 ? contact_->monitor().link(worst) : none;
    row_.pfl_ratio = p.ratio();
    row_.pfl_speed_m_s = p.speed_m_s;
    row_.pfl_reflected_mass_kg = p.reflected_mass_kg;
    row_.pfl_permissible_speed_m_s = p.permissible_speed_m_s;
    row_.pfl_energy_j = p.energy_J;
  }

  // Target - the true end effector (forward kinematics of the plant's link-side joints) [mm, deg];
  // false without a ground truth.
  bool true_ee_error(double& pos_mm, double& ori_deg) {
    if (ground_truth_ == nullptr || ground_truth_->true_joint_positions().size() != static_cast<Eigen::Index>(cycle_.model().nq())) return false;
    forward_kinematics(cycle_.model(), truth_data_, ground_truth_->true_joint_positions());
    update_frame_placements(cycle_.model(), truth_data_);
    const auto& target = cycle_.qp().end_effector().target_pose();
    const auto& pose = truth_data_.frame_placements[static_cast<std::size_t>(cycle_.end_effector_frame())];
    pos_mm = 1e3 * (target.translation() - pose.translation()).norm();
    const Eigen::Matrix3d r = target.linear() * pose.linear().transpose();
    ori_deg = Eigen::AngleAxisd(r).angle() * 180.0 / std::numbers::pi;
    return true;
  }

  // The operator's wrench at the end effector as the touch trigger reads it: the F/T sensor's, or,
  // without one, the estimate from the observer's tau_ext.
  double operator_wrench_norm() const {
    return cycle_.touch_source() == Controller::TouchSource::kForceTorque ? cycle_.wrench().norm()
                                                                           : cycle_.estimated_wrench().norm();
  }

  // Adds the cycle to its phase's sums; returns the end-effector position error [mm] (the true one
  // when the run has a ground truth, else the QP's task error).
  double accumulate_phase() {
    PhaseAccumulator& a = acc_[phase_];
    const Vector6d& error = cycle_.qp().end_effector().error();
    const double qp_pos = 1e3 * error.head<3>().norm();
    double pos = qp_pos, ori = error.tail<3>().norm() * 180.0 / std::numbers::pi;
    true_ee_error(pos, ori);
    a.add(pos, ori, operator_wrench_norm(), qp_pos);
    const ComplianceController& compliance = cycle_.compliance();
    if (compliance.mode() != last_mode_ || compliance.touch_count() != last_touches_) ++a.compliance_switches;
    if (cycle_.low_level().switch_count() != last_loop_switches_) ++a.loop_switches;
    last_mode_ = compliance.mode();
    last_touches_ = compliance.touch_count();
    last_loop_switches_ = cycle_.low_level().switch_count();
    return pos;
  }

  // Every supervisor transition is shown (the first kMaxPrintedTransitions; all are counted and
  // logged); a safe stop also stops the FSM (its references brake to rest) and ends the run.
  void check_safety(CycleStatus status) {
    const StateSupervisor& supervisor = cycle_.supervisor();
    if (supervisor.transition_count() != summary_.safety_transitions) {
      summary_.safety_transitions = supervisor.transition_count();
      if (supervisor.state() == SupervisorState::kDegraded) ++summary_.degraded_spells;
      if (summary_.safety_transitions <= kMaxPrintedTransitions) {
        out_ << "phri: safety: " << describe(supervisor.last_transition()) << "\n";
        if (summary_.safety_transitions == kMaxPrintedTransitions) out_ << "phri: safety: further transitions are only logged\n";
      }
    }
    if (supervisor.escalation().reason != SafetyFault::kNone && !escalation_shown_) {
      escalation_shown_ = true;
      out_ << "phri: safety: the stop failed: " << to_string(supervisor.escalation().reason) << " at t = "
           << supervisor.escalation().time_s << " s\n";
    }
    if (summary_.safe_hold || status != CycleStatus::kSafeStop) return;
    safe_hold("safety: " + describe(supervisor.safe_stop_transition()));
  }

  static std::string describe(const SafetyTransition& tr) {
    std::string text = std::string(to_string(tr.from)) + " -> " + std::string(to_string(tr.to));
    if (tr.reason != SafetyFault::kNone) {
      text += " (" + std::string(to_string(tr.reason));
      if (tr.joint >= 0) text += ", joint " + std::to_string(tr.joint + 1);
      text += ")";
    }
    char at[48];
    std::snprintf(at, sizeof at, " at t = %.3f s", tr.time_s);
    return text + at;
  }

  // Two overruns of the period in a row (`late` > 0: this cycle overran): brake to rest and hold.
  void check_overruns(double late, double t) {
    consecutive_overruns_ = late > 0.0 ? consecutive_overruns_ + 1 : 0;
    if (consecutive_overruns_ < 2 || summary_.safe_hold) return;
    safe_hold("two consecutive overruns of the " + std::to_string(1e3 * period_) + " ms period at t = " + std::to_string(t) +
              " s");
  }

  void safe_hold(std::string reason) {
    summary_.safe_hold = true;
    summary_.safe_hold_reason = std::move(reason);
    fsm_.post(Event::kStop);
    out_ << "phri: SAFE HOLD: " << summary_.safe_hold_reason << "; braking to rest, then the robot's position hold\n";
  }

  // ~5 Hz on a terminal (one refreshed line), every 5 s otherwise.
  void print_status(double t, double pos, double us) {
    if (!options_.status_line || t < next_status_) return;
    next_status_ = t + (tty_ ? 0.2 : 5.0);
    char line[200];  // string_views printed with %.*s: no allocation in the loop
    const std::string_view mode = to_string(cycle_.compliance().mode());
    const std::string_view loop = to_string(cycle_.low_level().loop());
    std::snprintf(line, sizeof line, "t %6.2f s | %-10.*s | loop %-27.*s | EE error %6.2f mm | wrench %5.1f | cycle %5.1f us",
                  t, static_cast<int>(mode.size()), mode.data(), static_cast<int>(loop.size()), loop.data(), pos,
                  operator_wrench_norm(), us);
    if (tty_) {
      out_ << "\r" << line << std::flush;
    } else {
      out_ << line << "\n";
    }
  }

  // The cycle-time statistics and the per-phase table of the `cycles` cycles run.
  void summarize(std::size_t cycles) {
    summary_.cycles = cycles;
    summary_.simulated_s = static_cast<double>(cycles) * period_;
    summary_.overruns = clock_.overruns();
    summary_.held_cycles = cycle_.held_cycles();
    // Phases the run never reached (it ended or stopped first) are left out of the table.
    for (std::size_t p = 0; p <= phase_; ++p) summary_.phases.push_back(phase_summary(p));
    const std::vector<double> all(micros_.begin(), micros_.begin() + static_cast<std::ptrdiff_t>(cycles));
    summary_.cycle_median_us = percentile(all, 0.5);
    summary_.cycle_p99_us = percentile(all, 0.99);
    summary_.cycle_p999_us = percentile(all, 0.999);
    summary_.cycle_max_us = all.empty() ? 0.0 : *std::max_element(all.begin(), all.end());
  }

  PhaseSummary phase_summary(std::size_t p) const {
    PhaseSummary s;
    s.name = phases_[p].name;
    s.start_s = phases_[p].start_s;
    s.end_s = p + 1 < phases_.size() ? std::min(phases_[p + 1].start_s, summary_.simulated_s) : summary_.simulated_s;
    const PhaseAccumulator& a = acc_[p];
    if (a.n == 0) return s;
    s.ee_position_error_max_mm = a.pos_max;
    s.ee_position_error_rms_mm = std::sqrt(a.pos_sq / static_cast<double>(a.n));
    s.ee_orientation_error_max_deg = a.ori_max;
    s.ee_orientation_error_rms_deg = std::sqrt(a.ori_sq / static_cast<double>(a.n));
    s.ee_error_true = ground_truth_ != nullptr && ground_truth_->true_joint_positions().size() == static_cast<Eigen::Index>(cycle_.model().nq());
    s.qp_task_position_error_max_mm = a.qp_pos_max;
    s.qp_task_position_error_rms_mm = std::sqrt(a.qp_pos_sq / static_cast<double>(a.n));
    s.wrench_norm_max = a.wrench_max;
    s.compliance_switches = a.compliance_switches;
    s.loop_switches = a.loop_switches;
    const auto first = micros_.begin() + static_cast<std::ptrdiff_t>(a.first_cycle);
    const std::vector<double> slice(first, first + static_cast<std::ptrdiff_t>(a.n));
    s.cycle_median_us = percentile(slice, 0.5);
    s.cycle_p999_us = percentile(slice, 0.999);
    return s;
  }

  RobotInterface& robot_;
  Controller& cycle_;
  Fsm& fsm_;
  Gamepad* gamepad_;
  Logger* logger_;
  const RunOptions& options_;
  std::ostream& out_;
  const double period_;
  const std::size_t max_cycles_;
  std::vector<double> micros_;  // every cycle's compute time, sized before the loop
  const std::vector<PhaseMark> phases_;
  std::vector<PhaseAccumulator> acc_;
  std::size_t phase_ = 0;
  const bool tty_;
  RobotCommand command_;
  LogRow row_;
  LoopClock clock_;
  int consecutive_overruns_ = 0;
  double next_status_ = 0.0;
  ComplianceMode last_mode_;
  int last_touches_;
  int last_loop_switches_;
  RunSummary summary_;
  // live front end
  LiveChannel* live_;
  PushInput* pushes_;
  const GroundTruth* ground_truth_;
  Data truth_data_;  // forward kinematics of the true joints, sized once
  std::optional<ContactRecorder> contact_;  // the power-and-force-limiting figures (true or measured state)
  std::vector<SnapshotChannel*> observers_;  // options.observers and the live front end's; sized before the loop
  std::vector<int> push_targets_;
  double push_start_s_ = 0.0, push_end_s_ = 0.0;
  LivePush push_;
  LiveSnapshot snapshot_;
  bool paused_ = false;
  bool escalation_shown_ = false;  // the stop's own fault (a refused hold) was printed
  int steps_ = 0;
};

}  // namespace

RunSummary run_session(RobotInterface& robot, Controller& cycle, Fsm& fsm, Gamepad* gamepad, Logger* logger,
                       const RunOptions& options, std::ostream& out) {
  return Session(robot, cycle, fsm, gamepad, logger, options, out).run();
}

void print_run_summary(const RunSummary& s, std::ostream& out) {
  char line[700];
  std::snprintf(line, sizeof line,
                "%llu cycles, %.1f s simulated in %.1f s of wall time; controller cycle: median %.1f us, p99 %.1f us, "
                "p99.9 %.1f us, max %.1f us; %llu overruns; %ld held cycles; %llu degraded spells; %llu refused writes%s%s\n\n",
                static_cast<unsigned long long>(s.cycles), s.simulated_s, s.wall_s, s.cycle_median_us, s.cycle_p99_us,
                s.cycle_p999_us, s.cycle_max_us, static_cast<unsigned long long>(s.overruns), s.held_cycles, static_cast<unsigned long long>(s.degraded_spells),
                static_cast<unsigned long long>(s.refused_writes),
                s.safe_hold ? (" ; SAFE HOLD: " + s.safe_hold_reason).c_str() : "",
                s.interrupted ? " ; INTERRUPTED before the end of its duration" : "");
  out << line;
  const bool truth = !s.phases.empty() && s.phases.front().ee_error_true;
  out << (truth ? "EE errors: target - the true end effector (the simulator's link-side joints); QP task error: the "
                  "QP's own (target - its estimate of the pose)\n"
                : "EE errors: the QP's task error (target - its estimate of the pose; no ground truth on this robot)\n");
  out << "| phase | from s | to s | EE pos max mm | EE pos RMS mm | EE ori max deg | EE ori RMS deg | QP task pos max mm | "
         "QP task pos RMS mm | wrench max | mode switches | loop switches | cycle median us | cycle p99.9 us |\n";
  out << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const PhaseSummary& p : s.phases) {
    std::snprintf(line, sizeof line,
                  "| %s | %.1f | %.1f | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | %.1f | %d | %d | %.1f | %.1f |\n",
                  p.name.c_str(), p.start_s, p.end_s, p.ee_position_error_max_mm, p.ee_position_error_rms_mm,
                  p.ee_orientation_error_max_deg, p.ee_orientation_error_rms_deg, p.qp_task_position_error_max_mm,
                  p.qp_task_position_error_rms_mm, p.wrench_norm_max, p.compliance_switches, p.loop_switches,
                  p.cycle_median_us, p.cycle_p999_us);
    out << line;
  }
  print_contact_summary(s, out);
}

void print_contact_summary(const RunSummary& s, std::ostream& out) {
  if (s.contact.empty()) {
    out << "\nPower and force limiting (ISO/TS 15066): not measured (no body_regions in the configuration, or no capsules)\n";
    return;
  }
  print_contact_table(s.contact, s.contact_true_state ? "the plant's true state" : "the measured state", out);
}

void print_contact_table(const std::vector<ContactLinkSummary>& links, const char* state, std::ostream& out) {
  if (links.empty()) return;
  const auto worst = std::max_element(links.begin(), links.end(),
                                      [](const ContactLinkSummary& a, const ContactLinkSummary& b) { return a.max_ratio < b.max_ratio; });
  char line[400];
  std::snprintf(line, sizeof line,
                "\nPower and force limiting (ISO/TS 15066 transient contact, %s): worst v / v_max %.2f on %s (%s), %.3f s above 1 "
                "on that link\n",
                state, worst->max_ratio, worst->link.c_str(), worst->region.c_str(), worst->time_above_s);
  out << line;
  out << "| link | region | max v / v_max | speed there m/s | reflected mass there kg | v_max there m/s | max speed m/s | "
         "max energy J | time above 1 s |\n";
  out << "|---|---|---|---|---|---|---|---|---|\n";
  for (const ContactLinkSummary& c : links) {
    std::snprintf(line, sizeof line, "| %s | %s | %.3f | %.3f | %.2f | %.3f | %.3f | %.4f | %.3f |\n", c.link.c_str(),
                  c.region.c_str(), c.max_ratio, c.speed_at_max_m_s, c.reflected_mass_at_max_kg, c.permissible_speed_at_max_m_s,
                  c.max_speed_m_s, c.max_energy_J, c.time_above_s);
    out << line;
  }
}

}  // namespace phri
