// ctest-labels: unit
// phri::run_session, the loop of `phri run`, driven through phri::FakeRobot (a deterministic
// unit-inertia arm, no MuJoCo) with the Gen3 Controller (URDF, actuators.yaml, collision.yaml) and
// the demo's Fsm, in lockstep: it runs ceil(duration / period) cycles, one read and one write each;
// stale, invalid or non-finite joint data are held cycles, counted in the summary; a short spell
// only degrades, a long one is a safe stop reported once (the FSM is told to stop), and so is a
// refused write; the loop ends at the cycle where the FSM has finished; the logger
// gets one row per cycle; phases split the summary at their start times.
//
// The arm starts at the plant's home posture (configs/plant_gen3.yaml), so the FSM's start-up is a
// 2.7 s minimum-jerk joint move in the Position loop; the sessions here stay inside it, where the
// FakeRobot's ideal position servo is the whole plant (no gravity to compensate).
#include <phri/app/fsm.hpp>
#include <phri/app/logger.hpp>
#include <phri/app/run_session.hpp>
#include <phri/config/fsm_settings.hpp>
#include <phri/control/controller.hpp>
#include <phri/control/power_force_limit.hpp>
#include <phri/robot/actuator_table.hpp>
#include <phri/robot/fake_robot.hpp>

#include "temp_dir.hpp"

#include "gen3_settings.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <cstdio>
#include <fstream>
#include <functional>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace {

const std::string kRoot = PHRI_SOURCE_DIR;
const std::string kGen3 = kRoot + "/robots/kinova_gen3/";

// The plant's home posture (configs/plant_gen3.yaml, initial.q_rad), the start-up's starting point.
Eigen::VectorXd plant_home() {
  Eigen::VectorXd q(7);
  q << 0.0, 0.26179939, 3.14159265, -2.26892803, 0.0, 0.95993109, 1.57079633;
  return q;
}

phri::FakeRobotSettings fake_gen3() {
  const phri::ActuatorTable table = phri::ActuatorTable::from_yaml_file(kGen3 + "actuators.yaml");
  phri::FakeRobotSettings s;
  s.dof = 7;
  s.period_s = 1e-3;
  s.initial_q_rad = plant_home();
  s.torque_per_amp_Nm_per_A.resize(7);
  for (int i = 0; i < 7; ++i) s.torque_per_amp_Nm_per_A[i] = table[i].torque_per_amp();
  return s;
}

// Occurrences of `needle` in `text`.
int count(const std::string& text, const std::string& needle) {
  int n = 0;
  for (std::size_t at = text.find(needle); at != std::string::npos; at = text.find(needle, at + needle.size())) ++n;
  return n;
}

// One session: the fake arm, the Gen3 controller, the FSM, and what the loop printed. Every write
// is recorded: its status, its position set-point, the q of the state read in the same cycle, and
// whether the FSM had finished by then.
class Session {
 public:
  explicit Session(phri::FsmSettings fsm_settings = {})
      : controller_(phri::test::gen3_controller_settings()), fsm_(fsm_settings, controller_) {
    robot_.set_write_observer([this](const phri::RobotCommand& command, phri::WriteStatus status) {
      statuses_.push_back(status);
      positions_.push_back(command.q_rad);
      read_q_.push_back(robot_.state().q_rad);
      finished_at_write_.push_back(fsm_.finished());
      if (statuses_.size() == stop_at_write_) stop_requested_.store(true);  // as a signal handler would
    });
  }

  phri::RunSummary run(double duration_s, std::vector<phri::PhaseMark> phases = {}, phri::Logger* logger = nullptr,
                       bool real_time = false) {
    phri::RunOptions options;
    options.duration_s = duration_s;
    options.real_time = real_time;
    options.status_line = false;
    options.phases = std::move(phases);
    options.stop_requested = &stop_requested_;
    return phri::run_session(robot_, controller_, fsm_, nullptr, logger, options, out_);
  }

  phri::FakeRobot robot_{fake_gen3()};
  phri::Controller controller_;
  phri::Fsm fsm_;
  std::ostringstream out_;
  std::vector<phri::WriteStatus> statuses_;
  std::vector<Eigen::VectorXd> positions_;
  std::vector<Eigen::VectorXd> read_q_;
  std::vector<bool> finished_at_write_;
  std::atomic<bool> stop_requested_{false};
  std::size_t stop_at_write_ = 0;  ///< the write at which the stop is asked (0: never)
};

TEST(RunSession, RunsDurationOverPeriodCyclesOneReadAndOneWriteEach) {
  Session session;
  const phri::RunSummary summary = session.run(0.25);
  EXPECT_EQ(summary.cycles, 250u);
  EXPECT_EQ(session.robot_.reads(), 250u);
  EXPECT_EQ(session.robot_.writes(), 250u);
  EXPECT_EQ(session.robot_.refused_writes(), 0u);
  EXPECT_NEAR(summary.simulated_s, 0.25, 1e-12);
  EXPECT_EQ(summary.held_cycles, 0);
  EXPECT_EQ(summary.overruns, 0u);
  EXPECT_FALSE(summary.safe_hold);
  EXPECT_EQ(count(session.out_.str(), "SAFE HOLD"), 0);
  EXPECT_EQ(session.fsm_.state(), phri::FsmState::kStartup);
  EXPECT_FALSE(session.fsm_.finished());
  // The Position loop's reference is what the arm was sent, and the last state shows it reached.
  EXPECT_EQ(session.robot_.last_accepted().mode, phri::LowLevelMode::kPosition);
  EXPECT_EQ(session.robot_.last_accepted().q_rad, session.controller_.low_level().position_reference());
  // A partial period is one more cycle: ceil(0.2505 / 0.001) = 251.
  Session longer;
  EXPECT_EQ(longer.run(0.2505).cycles, 251u);
}

// A stop asked from outside (apps/phri.cpp's SIGINT/SIGTERM handler) during cycle 100 ends the
// run after that cycle, as if its duration had run out: 100 cycles, summarized, said interrupted.
TEST(RunSession, AStopRequestEndsTheRunAfterThatCycle) {
  Session session;
  session.stop_at_write_ = 100;
  const phri::RunSummary summary = session.run(0.5, {{0.0, "startup"}, {0.05, "later"}});
  EXPECT_TRUE(summary.interrupted);
  EXPECT_EQ(summary.cycles, 100u);
  EXPECT_EQ(session.robot_.reads(), 100u);
  EXPECT_EQ(session.robot_.writes(), 100u);
  EXPECT_NEAR(summary.simulated_s, 0.1, 1e-12);
  ASSERT_EQ(summary.phases.size(), 2u);
  EXPECT_NEAR(summary.phases[1].end_s, 0.1, 1e-12);
  EXPECT_FALSE(summary.safe_hold);
  std::ostringstream printed;
  phri::print_run_summary(summary, printed);
  EXPECT_NE(printed.str().find("100 cycles"), std::string::npos) << printed.str();
  EXPECT_NE(printed.str().find("INTERRUPTED"), std::string::npos) << printed.str();
  // Without a stop the same run is whole and not said interrupted.
  Session whole;
  const phri::RunSummary full = whole.run(0.5);
  EXPECT_FALSE(full.interrupted);
  EXPECT_EQ(full.cycles, 500u);
  std::ostringstream full_printed;
  phri::print_run_summary(full, full_printed);
  EXPECT_EQ(full_printed.str().find("INTERRUPTED"), std::string::npos);
}

// The start-up's move, through the loop: after 0.5 s the arm has moved toward the home posture, at
// most the move's 0.3 rad/s peak joint speed (the fake servo's velocity is the reference's).
TEST(RunSession, TheStartupMoveReachesTheArmThroughTheLoop) {
  Session session;
  session.run(0.5);
  Eigen::VectorXd home(7);
  for (int i = 0; i < 7; ++i) home[i] = phri::paper_posture_target()[static_cast<std::size_t>(i)];
  const double start_error = (home - plant_home()).norm();
  const double error = (home - session.robot_.true_q()).norm();
  EXPECT_LT(error, start_error - 0.01) << "the arm moved toward home";
  double peak_speed = 0.0;
  for (std::size_t k = 1; k < session.positions_.size(); ++k) {
    peak_speed = std::max(peak_speed, (session.positions_[k] - session.positions_[k - 1]).cwiseAbs().maxCoeff() / 1e-3);
  }
  EXPECT_GT(peak_speed, 0.01);
  EXPECT_LT(peak_speed, 0.3 * 1.05);
}

TEST(RunSession, PhasesSplitTheSummaryAtTheirStartTimes) {
  Session session;
  const phri::RunSummary summary = session.run(0.3, {{0.0, "settle"}, {0.1, "move"}, {0.25, "end"}});
  ASSERT_EQ(summary.phases.size(), 3u);
  EXPECT_EQ(summary.phases[0].name, "settle");
  EXPECT_EQ(summary.phases[1].name, "move");
  EXPECT_EQ(summary.phases[2].name, "end");
  EXPECT_DOUBLE_EQ(summary.phases[0].end_s, 0.1);
  EXPECT_DOUBLE_EQ(summary.phases[1].start_s, 0.1);
  EXPECT_DOUBLE_EQ(summary.phases[1].end_s, 0.25);
  EXPECT_NEAR(summary.phases[2].end_s, 0.3, 1e-12);
  // Each phase change announced once (not on a terminal: plain lines).
  EXPECT_EQ(count(session.out_.str(), "phase: move\n"), 1);
  EXPECT_EQ(count(session.out_.str(), "phase: end\n"), 1);
  EXPECT_EQ(count(session.out_.str(), "phase: settle"), 0) << "the first phase is where the run starts";
}

struct BadData {
  std::string name;
  std::function<void(phri::FakeRobot&)> inject;
  long held;
  std::string transition;  // the supervisor's transition into kDegraded, as `phri run` prints it
};

// Short spells of joint data that cannot be used, three ways (shorter than the supervisor's
// 20 ms degraded budget): each bad read is one held cycle in which the previous command is
// written again; the supervisor degrades and recovers, both printed, and the session goes on.
TEST(RunSession, ShortSpellsOfBadJointDataAreHeldCyclesAndTheSessionGoesOn) {
  const std::vector<BadData> cases = {
      {"NaN in q", [](phri::FakeRobot& r) { r.inject_nan({.first = 101, .count = 10}, 3); }, 10,
       "normal -> degraded (not_finite, joint 4) at t = 0.101 s"},
      {"joints.valid false", [](phri::FakeRobot& r) { r.invalidate_joints({.first = 201, .count = 3}); }, 3,
       "normal -> degraded (invalid_signal) at t = 0.201 s"},
      {"frozen joint frames", [](phri::FakeRobot& r) { r.freeze_joints({.first = 151, .count = 5}); }, 5,
       "normal -> degraded (stale_sequence) at t = 0.151 s"},
  };
  for (const BadData& c : cases) {
    SCOPED_TRACE(c.name);
    Session session;
    c.inject(session.robot_);
    const phri::RunSummary summary = session.run(0.5);

    EXPECT_EQ(summary.held_cycles, c.held);
    EXPECT_FALSE(summary.safe_hold) << summary.safe_hold_reason;
    EXPECT_EQ(summary.cycles, 500u);
    EXPECT_EQ(summary.degraded_spells, 1u);
    EXPECT_EQ(summary.safety_transitions, 2u);
    EXPECT_EQ(count(session.out_.str(), "phri: safety: " + c.transition), 1) << session.out_.str();
    EXPECT_EQ(count(session.out_.str(), "degraded -> normal"), 1) << session.out_.str();

    // A write every cycle; during the held cycles, the command of the cycle before, unchanged.
    const std::size_t first = c.transition.find("0.101") != std::string::npos   ? 100
                              : c.transition.find("0.201") != std::string::npos ? 200
                                                                                : 150;
    EXPECT_EQ(session.robot_.writes(), summary.cycles);
    for (std::size_t k = first; k < first + static_cast<std::size_t>(c.held); ++k) {
      EXPECT_EQ(session.positions_[k], session.positions_[first - 1]) << "write " << k + 1;
    }
    EXPECT_NE(session.positions_[first + static_cast<std::size_t>(c.held)], session.positions_[first - 1])
        << "the loop resumes after the bad data";
  }
}

// Bad data for longer than the degraded budget (20 ms): a latched safe stop. In the position loop
// of the start-up, the robot's hold of the controller's last reference (within the following
// error of the last good pose; braking, were it moving) at once; reported once; the FSM stops and
// the loop ends with the arm at rest.
TEST(RunSession, BadJointDataBeyondTheDegradedBudgetEndInOneSafeStopHoldingTheLastGoodPose) {
  Session session;
  session.robot_.inject_nan({.first = 101, .count = 100}, 1);
  const phri::RunSummary summary = session.run(3.0);
  ASSERT_TRUE(summary.safe_hold);
  EXPECT_NE(summary.safe_hold_reason.find("degraded -> safe_stop (not_finite, joint 2) at t = 0.12"), std::string::npos)
      << summary.safe_hold_reason;
  EXPECT_EQ(count(session.out_.str(), "SAFE HOLD"), 1) << session.out_.str();
  EXPECT_EQ(session.controller_.status(), phri::CycleStatus::kSafeStop);
  EXPECT_TRUE(session.controller_.holding());
  // From the safe stop on, every command holds the reference of the last good cycle (write 100),
  // at the pose of the last good read (read 100) up to the servo's following error.
  const Eigen::VectorXd& last_good = session.read_q_[99];
  EXPECT_LE((session.positions_[99] - last_good).cwiseAbs().maxCoeff(), 1e-3);
  for (std::size_t k = 125; k < session.positions_.size(); ++k) {
    ASSERT_EQ(session.positions_[k], session.positions_[99]) << "write " << k + 1;
  }
  EXPECT_TRUE(session.fsm_.finished());
  EXPECT_LT(summary.cycles, 3000u);
  EXPECT_LT(session.robot_.true_qd().cwiseAbs().maxCoeff(), 0.01);
}

// A refused write leaves the robot on its previous command, which the controller no longer
// controls: it is a fault, answered in the same cycle. The loop hands it to the controller, whose
// safe stop sends a second command at once (here the arm is at rest: the hold where the robot says
// it is); while the robot refuses, each cycle's hold is re-targeted at the pose it reports, and a
// hold refused for more than max_hold_refusals cycles is the stop's own fault. Once the robot
// accepts again, the last hold stays.
TEST(RunSession, ARefusedWriteIsAFaultTheLoopAnswersInTheSameCycle) {
  Session session;
  session.robot_.refuse_writes({.first = 100, .count = 50}, phri::WriteStatus::kFault);
  const phri::RunSummary summary = session.run(0.3);
  EXPECT_EQ(summary.refused_writes, 50u);
  EXPECT_EQ(session.robot_.state().rejected_writes, 50u);
  ASSERT_TRUE(summary.safe_hold);
  EXPECT_NE(summary.safe_hold_reason.find("normal -> safe_stop (write_refused) at t = 0.100 s"), std::string::npos)
      << summary.safe_hold_reason;
  EXPECT_EQ(session.controller_.supervisor().escalation().reason, phri::SafetyFault::kHoldRefused);
  EXPECT_NE(session.out_.str().find("the stop failed: hold_refused"), std::string::npos) << session.out_.str();
  // Two writes per cycle while refused: writes 100..149 are 25 cycles, the answer the second of each.
  ASSERT_GT(session.positions_.size(), 160u);
  for (std::size_t k = 99; k < 149; ++k) {
    EXPECT_EQ(session.statuses_[k], phri::WriteStatus::kFault) << "write " << k + 1;
    EXPECT_LE((session.positions_[k] - session.read_q_[k]).cwiseAbs().maxCoeff(), 1e-3) << "write " << k + 1;
  }
  for (std::size_t k = 149; k < session.positions_.size(); ++k) {
    ASSERT_EQ(session.statuses_[k], phri::WriteStatus::kOk) << "write " << k + 1;
    ASSERT_EQ(session.positions_[k], session.positions_[149]) << "write " << k + 1;
  }
  EXPECT_EQ(session.robot_.state().q_rad, session.positions_[149]);
}

// A scripted stop: the FSM brakes the start-up move, holds, and the loop stops at the cycle where
// the arm is at rest, long before the 5 s asked.
TEST(RunSession, TheLoopStopsAtTheCycleWhereTheFsmHasFinished) {
  phri::FsmSettings settings;
  settings.timeline = {{0.3, phri::Event::kStop}};
  Session session(settings);
  const phri::RunSummary summary = session.run(5.0);
  ASSERT_TRUE(session.fsm_.finished());
  EXPECT_FALSE(summary.safe_hold);
  EXPECT_EQ(summary.held_cycles, 0);
  // The stop at 0.3 s brakes the move (joint speeds ~0.05 rad/s then) for max(0.2 s, speed / 1 rad/s^2)
  // = 0.2 s: stopped, and at rest, at 0.5 s.
  EXPECT_NEAR(static_cast<double>(summary.cycles), 500.0, 1.0);
  // finished() turned true in the last cycle (its update precedes the write), never before it.
  ASSERT_EQ(session.finished_at_write_.size(), summary.cycles);
  for (std::size_t k = 0; k + 1 < summary.cycles; ++k) ASSERT_FALSE(session.finished_at_write_[k]) << k + 1;
  EXPECT_TRUE(session.finished_at_write_.back());
  EXPECT_EQ(session.robot_.reads(), summary.cycles);
  EXPECT_NEAR(summary.simulated_s, 1e-3 * static_cast<double>(summary.cycles), 1e-12);
  EXPECT_LT(session.robot_.true_qd().cwiseAbs().maxCoeff(), settings.rest_speed_rad_s);
}

TEST(RunSession, TheLoggerGetsOneRowPerCycle) {
  Session session;
  phri::LoggerSettings log;
  log.path = phri::test::temp_path("phri_test_run_session", "run.csv");
  log.write_legend = false;
  phri::Logger logger(log);
  const phri::RunSummary summary = session.run(0.2, {}, &logger);
  const phri::LoggerStats stats = logger.close();
  EXPECT_EQ(stats.written, summary.cycles);
  EXPECT_EQ(stats.dropped, 0u);
  std::ifstream in(log.path);
  std::string line;
  std::getline(in, line);  // header
  ASSERT_EQ(line.rfind("time_s,", 0), 0u) << line;
  long rows = 0;
  double last_time = 0.0;
  while (std::getline(in, line)) {
    ++rows;
    last_time = std::stod(line.substr(0, line.find(',')));
    ASSERT_NEAR(last_time, 1e-3 * static_cast<double>(rows), 1e-12) << rows;
  }
  EXPECT_EQ(rows, 200);
}

// Paced by the real-time clock: the same cycles, and never ahead of the wall clock (a late cycle
// is counted, not caught up, so the run can only take longer).
TEST(RunSession, RealTimePacingRunsTheSameCyclesNoFasterThanTheClock) {
  Session session;
  const phri::RunSummary summary = session.run(0.05, {}, nullptr, true);
  EXPECT_EQ(summary.cycles, 50u);
  EXPECT_GE(summary.wall_s, 0.049);
}

}  // namespace

// With body regions, every cycle's power-and-force-limiting figures: the log's pfl_ columns name
// the link closest to its permissible speed, the summary keeps each link's worst and its time above
// 1; the start-up's motion moves every link but the first at least a little.
TEST(RunSession, BodyRegionsGiveEachLinksPowerAndForceLimitingFiguresInTheLogAndTheSummary) {
  phri::LoggerSettings log_settings;
  log_settings.path = phri::test::temp_path("phri_test_run_session", "pfl.csv");
  log_settings.dof = 7;
  log_settings.pfl_links = phri::PowerForceLimitMonitor::monitored_links(*Session().controller_.collision());
  phri::BodyRegionMap regions;
  regions.region = {"test_slow", 75000.0, 0.6, 2.0, 2.0};  // v_max of a few cm/s: the start-up exceeds it
  regions.links.emplace_back("end_effector_link", phri::BodyRegion{"hand_fingers", 75000.0, 0.6, 140.0, 2.0});
  Session session;
  phri::Logger logger(log_settings);
  phri::RunOptions options;
  options.duration_s = 1.0;
  options.status_line = false;
  options.body_regions = &regions;
  const phri::RunSummary s =
      phri::run_session(session.robot_, session.controller_, session.fsm_, nullptr, &logger, options, session.out_);
  logger.close();
  ASSERT_EQ(s.contact.size(), log_settings.pfl_links.size());
  EXPECT_FALSE(s.contact_true_state) << "a fake robot has no ground truth";
  double worst = 0.0;
  for (std::size_t i = 0; i < s.contact.size(); ++i) {
    const phri::ContactLinkSummary& c = s.contact[i];
    EXPECT_EQ(c.link, log_settings.pfl_links[i]);
    EXPECT_EQ(c.region, c.link == "end_effector_link" ? "hand_fingers" : "test_slow");
    EXPECT_GE(c.max_speed_m_s, c.speed_at_max_m_s);
    if (c.max_ratio > 0.0) {
      EXPECT_NEAR(c.max_ratio, c.speed_at_max_m_s / c.permissible_speed_at_max_m_s, 1e-12);
    }
    EXPECT_LE(c.time_above_s, s.simulated_s + 1e-9);
    worst = std::max(worst, c.max_ratio);
  }
  EXPECT_GT(worst, 1.0) << "the test region's v_max is below the start-up's speeds";
  std::ostringstream text;
  phri::print_run_summary(s, text);
  EXPECT_NE(text.str().find("Power and force limiting (ISO/TS 15066 transient contact, the measured state): worst v / v_max"),
            std::string::npos)
      << text.str();
  // The log: the worst link each cycle, its ratio as speed / v_max; the legend names the links.
  std::ifstream in(log_settings.path);
  std::string header;
  std::getline(in, header);
  EXPECT_NE(header.find(",pfl_ratio,pfl_link,pfl_speed_m_s,pfl_reflected_mass_kg,pfl_permissible_speed_m_s,pfl_energy_j,"),
            std::string::npos);
  std::ifstream legend(phri::Logger::legend_path_for(log_settings.path));
  const std::string legend_text((std::istreambuf_iterator<char>(legend)), std::istreambuf_iterator<char>());
  EXPECT_NE(legend_text.find("pfl_link:\n  -1: none\n  0: " + log_settings.pfl_links[0] + "\n"), std::string::npos) << legend_text;
}

// With a ground truth (a simulated arm's true link-side joints), the summary's EE errors are
// target - the true end effector and the QP's own task error stays beside them, labelled. Here the
// "truth" is the fake arm's q with joint 2 off by 0.01 rad, an error the QP (on the measured q)
// cannot see: the true error must show it, the QP's task error must not.
TEST(RunSession, AGroundTruthMeasuresTheTrueEndEffectorBesideTheQpTaskError) {
  struct OffsetTruth final : phri::GroundTruth {
    explicit OffsetTruth(const phri::FakeRobot& r) : robot(r), q(7) {}
    const Eigen::VectorXd& true_joint_positions() const override {
      q = robot.state().q_rad;
      q[1] += 0.01;
      return q;
    }
    const Eigen::VectorXd& true_joint_velocities() const override { return robot.state().qd_rad_s; }
    const phri::FakeRobot& robot;
    mutable Eigen::VectorXd q;
  };
  Session session;
  const OffsetTruth truth(session.robot_);
  phri::RunOptions options;
  options.duration_s = 0.2;
  options.status_line = false;
  options.ground_truth = &truth;
  const phri::RunSummary s =
      phri::run_session(session.robot_, session.controller_, session.fsm_, nullptr, nullptr, options, session.out_);
  ASSERT_EQ(s.phases.size(), 1u);
  const phri::PhaseSummary& p = s.phases[0];
  EXPECT_TRUE(p.ee_error_true);
  EXPECT_GT(p.ee_position_error_rms_mm, p.qp_task_position_error_rms_mm + 2.0);
  std::ostringstream printed;
  phri::print_run_summary(s, printed);
  EXPECT_NE(printed.str().find("target - the true end effector"), std::string::npos) << printed.str();
  EXPECT_NE(printed.str().find("QP task pos RMS mm"), std::string::npos);
  // Without one, the EE errors are the QP's task error, and the summary says so.
  Session plain;
  const phri::RunSummary q = plain.run(0.2);
  EXPECT_FALSE(q.phases[0].ee_error_true);
  EXPECT_DOUBLE_EQ(q.phases[0].ee_position_error_rms_mm, q.phases[0].qp_task_position_error_rms_mm);
}
