// phri_record_qps: records the QPs the controller solves in a session (the demo by default) into
// a logged-QP file (bench/data/README.md), which phri_bench's LoggedQpReplay replays:
//   build/release/bench/phri_record_qps [--config configs/demo.yaml] [--stride 10] [--level 19]
//                                       [--out bench/data/demo_qps.bin]
// The session runs as `phri run --config <config> --lockstep` runs it (run_session, the simulated
// plant, the FSM and its scripted events; no log, no gamepad). The recorder sits outside the control
// cycle: it is the robot run_session talks to, wrapped around the plant, and reads the controller's
// QP between read() (the warm-start set, before Controller::step) and write() (the problem as
// solved and its result, after it). Same machine, same build: the same file, byte for byte.
#include "logged_qps.hpp"

#include <phri/app/fsm.hpp>
#include <phri/app/plant_check.hpp>
#include <phri/app/run_session.hpp>
#include <phri/config/config.hpp>
#include <phri/control/controller.hpp>
#include <phri/sim/sim_robot.hpp>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace {

// What the whole session's QPs did, recorded or not.
struct SessionCounts {
  std::uint64_t solves = 0, relaxed_cycles = 0, not_optimal = 0, active_set_changes = 0, ticks_with_changes = 0;
};

// The plant as run_session sees it, reading the controller's QP around each Controller::step.
class QpRecordingRobot final : public phri::RobotInterface {
public:
  QpRecordingRobot(phri::RobotInterface& plant, const phri::WholeBodyQp& qp, phri::LoggedQps& out)
      : plant_(plant), qp_(qp), out_(out), seen_solves_(qp.solve_count()) {}

  int dof() const override { return plant_.dof(); }
  double period_s() const override { return plant_.period_s(); }

  // Before this cycle's step: the active set its solve will warm-start from.
  const phri::RobotState& read() override {
    const phri::QpSolver& solver = qp_.qp_solver();
    warm_rows_.assign(solver.active_rows().begin(), solver.active_rows().end());
    warm_bounds_.assign(solver.active_bounds().begin(), solver.active_bounds().end());
    ++cycles_;
    return plant_.read();
  }

  // After the step (a refused write's second write finds no new solve).
  phri::WriteStatus write(const phri::RobotCommand& command) override {
    if (qp_.solve_count() != seen_solves_) record();
    return plant_.write(command);
  }

  std::uint32_t cycles() const { return cycles_; }
  const SessionCounts& counts() const { return counts_; }

private:
  void record() {
    const phri::QpSolver& solver = qp_.qp_solver();
    const auto solves = qp_.solve_count() - seen_solves_;
    seen_solves_ = qp_.solve_count();
    counts_.relaxed_cycles += solves > 1 ? 1 : 0;
    counts_.not_optimal += solver.status() != phri::QpStatus::kOptimal ? 1 : 0;
    counts_.active_set_changes += static_cast<std::uint64_t>(solver.iterations());
    counts_.ticks_with_changes += solver.iterations() > 0 ? 1 : 0;
    if (counts_.solves++ % out_.stride != 0) return;
    phri::LoggedQpTick& tick = out_.ticks.emplace_back();
    tick.cycle = cycles_ - 1;
    tick.options = qp_.last_solve_options();
    tick.solves = static_cast<std::uint8_t>(std::min<std::uint64_t>(solves, 255));
    tick.status = solver.status();
    tick.iterations = solver.iterations();
    tick.warm_rows = warm_rows_;
    tick.warm_bounds = warm_bounds_;
    tick.final_rows.assign(solver.active_rows().begin(), solver.active_rows().end());
    tick.final_bounds.assign(solver.active_bounds().begin(), solver.active_bounds().end());
    tick.problem = qp_.qp_problem();
    tick.x = solver.x();
  }

  phri::RobotInterface& plant_;
  const phri::WholeBodyQp& qp_;
  phri::LoggedQps& out_;
  std::uint64_t seen_solves_;
  std::uint32_t cycles_ = 0;
  std::vector<phri::QpActiveSide> warm_rows_, warm_bounds_;
  SessionCounts counts_;
};

struct Arguments {
  std::string config = std::string(PHRI_SOURCE_DIR) + "/configs/demo.yaml";
  std::string out = std::string(PHRI_SOURCE_DIR) + "/bench/data/demo_qps.bin";
  std::uint32_t stride = 10;
  int level = 19;
};

Arguments parse_arguments(int argc, char** argv) {
  Arguments args;
  for (int i = 1; i < argc; ++i) {
    const std::string_view key = argv[i];
    if (i + 1 >= argc) throw std::invalid_argument("usage: phri_record_qps [--config F] [--out F] [--stride N] [--level L]");
    const std::string value = argv[++i];
    if (key == "--config") {
      args.config = value;
    } else if (key == "--out") {
      args.out = value;
    } else if (key == "--stride") {
      args.stride = static_cast<std::uint32_t>(std::stoul(value));
    } else if (key == "--level") {
      args.level = std::stoi(value);
    } else {
      throw std::invalid_argument("unknown option " + std::string(key));
    }
  }
  if (args.stride == 0) throw std::invalid_argument("--stride must be >= 1");
  return args;
}

int record(const Arguments& args) {
  phri::Config config = phri::Config::from_yaml_file(args.config);
  phri::check_plant_matches_controller(config.controller, config.plant);
  phri::Controller cycle(config.controller);
  phri::Fsm fsm(config.fsm, cycle);
  phri::SimRobot plant(config.plant);

  phri::LoggedQps qps;
  const phri::QpSolver& solver = cycle.qp().qp_solver();
  qps.n = solver.num_variables();
  qps.m_eq = solver.num_equalities();
  qps.m_in = solver.num_inequalities();
  qps.settings = solver.settings();
  qps.stride = args.stride;
  QpRecordingRobot robot(plant, cycle.qp(), qps);

  phri::RunOptions options;
  options.duration_s = config.run.duration_s;
  options.real_time = false;
  options.status_line = false;
  std::ostringstream session_output;  // the loop's own notes; its summary is printed below
  const phri::RunSummary summary = phri::run_session(robot, cycle, fsm, nullptr, nullptr, options, session_output);
  qps.session_cycles = robot.cycles();
  const SessionCounts& counts = robot.counts();
  qps.session_solves = static_cast<std::uint32_t>(counts.solves);
  std::filesystem::create_directories(std::filesystem::absolute(args.out).parent_path());
  phri::write_logged_qps(args.out, qps, args.level);

  std::printf("%s: %llu cycles (%.2f s), %llu QPs solved (%llu relaxed, %llu not optimal), %llu active-set changes in %llu of them\n",
              args.config.c_str(), static_cast<unsigned long long>(summary.cycles), summary.simulated_s,
              static_cast<unsigned long long>(counts.solves), static_cast<unsigned long long>(counts.relaxed_cycles),
              static_cast<unsigned long long>(counts.not_optimal), static_cast<unsigned long long>(counts.active_set_changes),
              static_cast<unsigned long long>(counts.ticks_with_changes));
  std::printf("wrote %s: %zu ticks (1 QP in %u), n %lld, m_eq %lld, m_in %lld, %llu bytes\n", args.out.c_str(),
              qps.ticks.size(), qps.stride, static_cast<long long>(qps.n), static_cast<long long>(qps.m_eq),
              static_cast<long long>(qps.m_in), static_cast<unsigned long long>(std::filesystem::file_size(args.out)));
  return summary.safe_hold ? 1 : 0;
}

}  // namespace

int main(int argc, char** argv) {
  try {
    return record(parse_arguments(argc, argv));
  } catch (const std::exception& e) {
    std::fprintf(stderr, "phri_record_qps: %s\n", e.what());
    return 2;
  }
}
