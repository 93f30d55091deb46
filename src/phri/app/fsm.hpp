#pragma once
// phri::Fsm: the demo's state machine (paper, "Framework overview": the operator switches
// compliance modes, low-level loops and scenarios live). It sits between the estimator and the
// QP (DESIGN.md section 2): each period it turns events into the controller's targets, plain
// data (ControllerTargets) that Controller::step applies; it reads the controller, never changes it.
//
//   phri::Fsm fsm(settings, controller);
//   for (;;) {
//     const phri::RobotState& s = robot.read();
//     for (phri::Event e; gamepad.poll(e);) fsm.post(e);                 // operator events
//     const phri::ControllerTargets& targets = fsm.update(s.time_s, s, controller);  // timeline, state
//     controller.step(s, targets, command);
//     robot.write(command);
//   }
//
// States:
//   startup  Position loop. A minimum-jerk joint move from where the arm is to the home posture
//            (posture task target, end-effector target = its forward kinematics, so the two tasks
//            agree), peak joint speed bounded. Once the move is over and the posture error norm
//            is below `tolerance_rad` (paper: 0.05 rad) — or `timeout_s` later — the low-level
//            loop switches to the torque loop (bumpless, LowLevelController) and the FSM enters
//            the first scenario.
//   static   Minimum-jerk move of the EE target to the static pose (and of the posture target to
//            the static posture), then hold: the FSM no longer writes the EE target, so dual
//            compliance can leave it where the hand put it.
//   dynamic  Streams DynamicTrajectory around the target pose held at entry.
//   stopped  The reference brought to rest and held. After `stop` (not `stop_scenario`),
//            finished() turns true once the arm is at rest.
// Leaving a state whose reference moves (startup's move, static's move, dynamic) goes through a
// brake: the reference decelerates to rest at a bounded rate (PoseBrake, JointBrake) before the
// next state starts from it, so no transition steps the reference velocity.
//
// Events (config/event.hpp) come from post() (the gamepad) and from the timeline (handled when the
// robot time reaches them), and act at once: compliance modes (ControllerTargets::compliance_mode),
// stiffness up/down (x or / stiffness_step, ComplianceController clamps to [0.1, 4]), low-level
// loops (during start-up: the loop to hand over to), scenarios, stops.
//
// update() allocates nothing and never throws; construction checks the settings (ConfigError).
#include <phri/control/controller.hpp>
#include <phri/config/event.hpp>
#include <phri/app/live_channel.hpp>
#include <phri/app/live_gain.hpp>
#include <phri/config/fsm_settings.hpp>
#include <phri/trajectory/joint_move.hpp>
#include <phri/trajectory/pose_move.hpp>
#include <phri/trajectory/quintic.hpp>
#include <phri/core/spsc_ring.hpp>
#include <phri/model/data.hpp>

#include <cstdint>
#include <string_view>
#include <vector>

namespace phri {

enum class FsmState : std::uint8_t { kStartup, kStatic, kDynamic, kStopped };
constexpr std::string_view to_string(FsmState s) {
  switch (s) {
    case FsmState::kStartup: return "startup";
    case FsmState::kStatic: return "static";
    case FsmState::kDynamic: return "dynamic";
    case FsmState::kStopped: return "stopped";
  }
  return "unknown";
}

class Fsm {
public:
  /// `cycle`: the controller this FSM will drive (its model gives the forward kinematics).
  Fsm(const FsmSettings& settings, const Controller& cycle);

  /// Queues an event for the next update (one producer thread; false when the queue is full).
  bool post(Event event) noexcept;
  /// Queues a live gain change (the dashboard's sliders) for the next update, which writes it
  /// into the targets; same thread rule and refusal as post(Event).
  bool post(const GainRequest& request) noexcept;
  /// Queues an end-effector target (the ROS 2 bridge's, checked there); the next update takes the
  /// latest one while the FSM holds a pose (static or stopped, no move or brake running) and
  /// refuses it otherwise (counted): the controller's reference governor then moves the target to
  /// it at a bounded speed. Same thread rule as post(Event).
  bool post(const LiveTarget& target) noexcept;
  std::uint64_t targets_taken() const { return targets_taken_; }
  std::uint64_t targets_refused() const { return targets_refused_; }
  /// Once per period, before controller.step(state, targets, ...). `time_s`: robot time (the
  /// timeline's clock). Returns this period's targets (also targets()).
  const ControllerTargets& update(double time_s, const RobotState& state, const Controller& controller);
  const ControllerTargets& targets() const { return targets_; }

  FsmState state() const { return state_; }
  /// The reference is being brought to rest before the next state.
  bool braking() const { return motion_ == Motion::kPoseBrake || motion_ == Motion::kJointBrake; }
  /// `stop` was handled and the arm is at rest: the session may end.
  bool finished() const { return finished_; }
  bool stop_requested() const { return stop_requested_; }
  bool startup_complete() const { return startup_complete_; }
  bool startup_timed_out() const { return startup_timed_out_; }
  /// Code of the last event handled by the last update (-1: none), for the log.
  int last_event_code() const { return last_event_; }
  std::uint64_t events_handled() const { return events_handled_; }
  std::uint64_t events_dropped() const { return events_dropped_; }
  /// Time the current state was entered (robot time).
  double state_entry_time() const { return state_entry_time_; }
  /// The torque loop toggle_loop returns to and start-up hands over to.
  LowLevelMode torque_loop() const { return torque_loop_; }
  /// The static scenario's end-effector pose (forward kinematics of its posture).
  const Eigen::Isometry3d& static_pose() const { return static_pose_; }
  const FsmSettings& settings() const { return settings_; }

private:
  enum class Motion { kHold, kJointMove, kPoseMove, kTrajectory, kPoseBrake, kJointBrake };

  void handle(Event event, double t, const RobotState& state, const Controller& cycle);
  void request(FsmState next, double t, const Controller& cycle);
  void enter(FsmState next, double t, const Controller& cycle);
  void enter_startup(double t, const RobotState& state);
  void finish_startup(double t, const Controller& cycle, bool timed_out);
  void run_motion(double t, const Controller& cycle);
  void set_posture_target();
  void hold_when_done(double t, bool done);
  void stream_joint_reference();
  void stream_pose_reference();
  void take_targets();
  double joint_speed(const RobotState& state) const;
  // Targets as the controller will hold them: the posture given so far in this update, else the
  // controller's; the end effector's governed target of the last cycle.
  const Eigen::Isometry3d& pose_target(const Controller& cycle) const;
  const Eigen::VectorXd& posture_target(const Controller& cycle) const;
  LowLevelMode requested_loop(const Controller& cycle) const;
  double stiffness_scale(const Controller& cycle) const;

  FsmSettings settings_;
  const Model& model_;
  Data data_;  // forward kinematics of joint references (start-up)
  int ee_frame_;
  SpscRing<Event> queue_;
  SpscRing<GainRequest> gain_queue_;
  SpscRing<LiveTarget> target_queue_;
  std::uint64_t targets_taken_ = 0;
  std::uint64_t targets_refused_ = 0;
  ControllerTargets targets_;
  std::size_t next_timed_ = 0;

  FsmState state_ = FsmState::kStartup;
  FsmState pending_ = FsmState::kStatic;  // entered when the brake ends
  Scenario after_startup_;
  LowLevelMode torque_loop_;
  LowLevelMode startup_handover_;
  Motion motion_ = Motion::kHold;
  double motion_start_ = 0.0;
  double state_entry_time_ = 0.0;
  bool initialised_ = false;
  bool posture_braking_ = false;  // the posture target brakes with the end effector
  bool startup_complete_ = false;
  bool startup_timed_out_ = false;
  bool stop_requested_ = false;
  bool finished_ = false;
  int last_event_ = -1;
  std::uint64_t events_handled_ = 0;
  std::uint64_t events_dropped_ = 0;

  JointMove joint_move_;
  JointBrake joint_brake_;
  PoseMove pose_move_;
  PoseBrake pose_brake_;
  DynamicTrajectory dynamic_;
  PoseReference pose_ref_;
  Eigen::VectorXd home_q_, static_q_;
  Eigen::VectorXd q_ref_, qd_ref_, qdd_ref_, scratch_;
  Eigen::Isometry3d static_pose_ = Eigen::Isometry3d::Identity();
};

}  // namespace phri
