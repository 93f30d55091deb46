// phri: the command-line entry point.
//   phri run --config FILE [--robot DIR] [--lockstep|--realtime] [--duration S] [--out DIR]
//            [--dashboard [--port P] [--bind ADDR] [--push-max N]]
//            [--backend sim|kortex|kortex-emulator [--ip ADDR] [--ft-serial DEV] [--dry-run]]
//            [--ros2 [--ros-domain N] [--ros-namespace NS]]  (ros2_cli.cpp, docs/ros2.md)
//                                              a session: simulated arm (or the Gen3 through the
//                                              Kortex backend, kortex_backend.cpp), FSM, gamepad,
//                                              log, figure, and the live dashboard in a browser
//   phri info --urdf FILE | --robot DIR        model summary of a robot description (a bundle: with its drives)
//   phri fit-collision --robot DIR [--out FILE] self-collision capsules fitted from the robot's URDF
//   phri identify-friction [options]           the paper's friction identification (simulated arm)
//   phri experiment torque-tracking [options]  the paper's torque-tracking comparison
//   phri experiment safety-fuzz [options]      seeded pushes and sensor faults against the safety stage
//   phri experiment drop-test [options]        30 + 30 drops, torque vs position mode
//   phri experiment dynamic-tracking [options] the dynamic scenario with the four low-level loops
//   phri experiment dual-compliance [options]  guiding the end effector by hand, release, drift
//   phri experiment iso9283 [options]          ISO 9283 pose accuracy and repeatability per loop
//   phri experiment collision [options]        the tool hits a body region: ISO/TS 15066 forces
//   phri evaluate [--out DIR] [--quick]        all five of the paper's evaluations and report.md/.html
//   phri experiment dashboard-load [options]   loop cycle time with vs without the dashboard and its clients
//   phri experiment ros2-load [options]        loop cycle time with vs without the ROS 2 bridge, F/T round trip (ros2_cli.cpp)
//   phri ft-monitor [--device DEV | --emulate] the Bota F/T sensor's wrench and counters (apps/ft_monitor.cpp)
//   phri ft-bridge [--device DEV | --emulate] the Bota F/T sensor published on ROS 2 /phri/ft_in (apps/ft_bridge.cpp)
//   phri log export --csv OUT LOG.mcap        an MCAP log back to its CSV; phri log info LOG: its topics (apps/log_cli.cpp)
// Every bad argument or file, and every failure of a run or an experiment (phri::Error: ConfigError,
// IoError, ExperimentError), gives one line on stderr naming what is wrong and exit status 2.
// `phri run` exits 0, 3 after a safe hold, and 128 + the signal's number (130 SIGINT, 143 SIGTERM)
// when a signal ended it early: the run then stops as if its duration had run out, and the log,
// summary.md and figure are still written (a second signal kills as usual).
#include "exit_status.hpp"
#include "log_cli.hpp"
#include "ft_monitor.hpp"
#include "kortex_backend.hpp"
#include "ros2_cli.hpp"

#include <phri/app/sim_backend.hpp>
#include <phri/app/loop_clock.hpp>
#include <phri/config/config.hpp>
#include <phri/config/config_checks.hpp>
#include <phri/config/robot_bundle.hpp>
#include <phri/model/capsule_fit.hpp>
#include <phri/app/run_session.hpp>
#include <phri/core/error.hpp>
#include <phri/core/format.hpp>
#include <phri/core/process.hpp>
#include <phri/sim/mujoco_handles.hpp>
#include <phri/sim/urdf_plant.hpp>
#include <phri/core/version.hpp>
#include <phri/experiments/collision.hpp>
#include <phri/experiments/drop_test.hpp>
#include <phri/experiments/dual_compliance.hpp>
#include <phri/experiments/evaluation.hpp>
#include <phri/dashboard/dashboard_load.hpp>
#include <phri/dashboard/dashboard_server.hpp>
#include <phri/experiments/experiment_files.hpp>
#include <phri/experiments/friction_identification.hpp>
#include <phri/experiments/iso9283.hpp>
#include <phri/experiments/safety_fuzz.hpp>
#include <phri/experiments/torque_tracking.hpp>
#include <phri/experiments/torque_tracking_sweep.hpp>
#include <phri/model/algorithms.hpp>
#include <phri/model/model.hpp>

#include <CLI/CLI.hpp>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <iostream>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace {

// Prints what the model loaded from a URDF: joints, limits, masses, and a few sanity figures.
int print_model_summary(const std::string& urdf_path, const std::string& tip, const std::string& frame_name) {
  phri::ModelOptions options;
  options.tip_link = tip;
  const phri::Model model = phri::Model::from_urdf_file(urdf_path, options);
  phri::Data data(model);
  std::printf("model '%s' from %s\n", model.name().c_str(), urdf_path.c_str());
  for (const std::string& warning : model.warnings()) std::printf("warning: %s\n", warning.c_str());
  std::printf("chain %s -> %s: %d joints, %d frames, moving mass %.4f kg\n\n", model.base_link().c_str(),
              model.tip_link().c_str(), model.nq(), model.num_frames(), model.total_mass());
  std::printf("%-3s %-10s %-11s %10s %10s %10s %10s %9s\n", "#", "joint", "type", "lower", "upper",
              "vel.lim", "effort", "mass kg");
  for (int i = 0; i < model.nq(); ++i) {
    const phri::Joint& j = model.joint(i);
    const char* type = j.type == phri::JointType::kPrismatic ? "prismatic"
                       : j.type == phri::JointType::kContinuous ? "continuous" : "revolute";
    std::printf("%-3d %-10s %-11s %10.4f %10.4f %10.4f %10.2f %9.4f\n", i + 1, j.name.c_str(), type, j.lower,
                j.upper, j.velocity_limit, j.effort_limit, model.body_inertia(i).mass);
  }
  const int frame = model.frame_id(frame_name.empty() ? model.tip_link() : frame_name);
  const Eigen::VectorXd q0 = Eigen::VectorXd::Zero(model.nq());
  phri::compute_all_terms(model, data, q0, q0);
  const Eigen::Vector3d p = data.frame_placements[static_cast<std::size_t>(frame)].translation();
  std::printf("\nat q = 0: %s at (%.6f, %.6f, %.6f) m; |g(q)| = %.4f N.m; M diagonal:",
              model.frame(frame).name.c_str(), p.x(), p.y(), p.z(), data.gravity_torque.norm());
  for (int i = 0; i < model.nq(); ++i) std::printf(" %.4f", data.mass_matrix(i, i));
  std::printf("\n");
  return 0;
}

// `phri info --robot DIR`: the bundle's arm as the controller sees it (its chain, payloads, frames),
// its drive and loops, its end of arm and which wrench the touch trigger reads, the actuators.yaml
// defaults in use, the loader's warnings; then the model summary of the chain.
int print_robot_summary(const std::string& folder, const std::string& frame_name) {
  const phri::RobotBundle bundle = phri::RobotBundle::from_folder(folder);
  phri::ControllerSettings settings;
  bundle.apply_to(settings);
  const phri::Model model = phri::Model::from_urdf_file(bundle.urdf_path, phri::Controller::model_options(settings));
  const phri::ActuatorTable drives = phri::ActuatorTable::from_yaml_file(bundle.actuators_path);
  const bool ft = bundle.end_of_arm && bundle.end_of_arm->has_ft_sensor;
  std::printf("robot '%s' from %s\n", bundle.name.c_str(), bundle.source.c_str());
  std::printf("urdf %s, actuators %s\n", bundle.urdf_path.c_str(), bundle.actuators_path.c_str());
  std::string loops;
  for (int m = 0; m < phri::kLowLevelModeCount; ++m) {
    const auto mode = static_cast<phri::LowLevelMode>(m);
    if (settings.offered_loops.contains(mode)) loops += (loops.empty() ? "" : ", ") + std::string(phri::to_string(mode));
  }
  std::printf("drive %s: loops %s\n", std::string(phri::to_string(bundle.drive)).c_str(), loops.c_str());
  std::printf("end of arm: %s; touch trigger: %s\n",
              !bundle.end_of_arm ? "none (bare flange)" : ft ? "F/T sensor and tool" : "tool, no F/T sensor",
              ft ? "F/T sensor wrench" : "end-effector wrench estimated from the observer's tau_ext");
  std::printf("end effector %s, home_q_rad", bundle.end_effector_frame.c_str());
  for (double q : bundle.home_q_rad) std::printf(" %.4f", q);
  std::printf("\n");
  for (const std::string& notice : drives.notices(bundle.actuators_path)) std::printf("default: %s\n", notice.c_str());
  for (const std::string& warning : model.warnings()) std::printf("warning: %s\n", warning.c_str());
  std::printf("chain %s -> %s: %d joints, moving mass %.4f kg (payloads included)\n\n", model.base_link().c_str(),
              model.tip_link().c_str(), model.nq(), model.total_mass());
  std::printf("%-3s %-16s %10s %10s %10s %10s %9s\n", "#", "joint", "lower", "upper", "vel.lim", "torque", "mass kg");
  for (int i = 0; i < model.nq(); ++i) {
    const phri::Joint& j = model.joint(i);
    std::printf("%-3d %-16s %10.4f %10.4f %10.4f %10.2f %9.4f\n", i + 1, j.name.c_str(), j.lower, j.upper,
                drives[i].velocity_limit_rad_s, drives[i].torque_limit_Nm, model.body_inertia(i).mass);
  }
  phri::Data data(model);
  const Eigen::VectorXd home = Eigen::Map<const Eigen::VectorXd>(bundle.home_q_rad.data(), model.nq());
  phri::compute_all_terms(model, data, home, Eigen::VectorXd::Zero(model.nv()));
  const int frame = model.frame_id(frame_name.empty() ? bundle.end_effector_frame : frame_name);
  const Eigen::Vector3d p = data.frame_placements[static_cast<std::size_t>(frame)].translation();
  std::printf("\nat home: %s at (%.6f, %.6f, %.6f) m; |g(q)| = %.4f N.m\n", model.frame(frame).name.c_str(), p.x(), p.y(),
              p.z(), data.gravity_torque.norm());
  return 0;
}

// Files of the experiments are found from the working directory; when run from elsewhere, from
// the source tree the program was built from.
std::string locate(const std::string& relative) {
  if (std::FILE* f = std::fopen(relative.c_str(), "r")) {
    std::fclose(f);
    return relative;
  }
  return std::string(PHRI_SOURCE_DIR) + "/" + relative;
}

// The figure of a run's log (tools/report/demo_figure.py), drawn by the system python through
// run_process: the paths reach the script as arguments, never through a shell. A failure is a warning.
void draw_demo_figure(const std::string& log_path, const std::string& png, const phri::Config& config) {
  const phri::ComplianceSettings& compliance = config.controller.compliance;
  const std::string script = locate("tools/report/demo_figure.py");
  if (!std::filesystem::exists(phri::kSystemPython) || !std::filesystem::exists(script)) {
    std::printf("no figure: %s or %s missing\n", phri::kSystemPython, script.c_str());
    return;
  }
  std::vector<std::string> argv = {phri::kSystemPython, script, log_path, png,
                                         "--touch", phri::format_fixed(compliance.touch_threshold, 6),
                                         "--release", phri::format_fixed(compliance.release_threshold, 6)};
  argv.insert(argv.end(), {"--arm", config.robot_name});
  if (!config.plant.ft_sensor_present()) argv.push_back("--no-ft");
  try {
    if (phri::run_process(argv) != 0) std::fprintf(stderr, "phri: warning: the figure script failed\n");
  } catch (const phri::IoError& e) {
    std::fprintf(stderr, "phri: warning: the figure script failed: %s\n", e.what());
  }
}

// The plant friction's form (friction_model_form.hpp), on both spellings of the command.
void add_plant_friction_options(CLI::App& command, phri::FrictionIdentificationOptions& friction) {
  phri::StribeckRippleSettings& s = friction.stribeck_ripple;
  command
      .add_option_function<std::string>(
          "--plant-friction",
          [&friction](const std::string& form) {
            friction.plant_friction =
                form == "stribeck-ripple" ? phri::PlantFrictionForm::kStribeckRipple : phri::PlantFrictionForm::kModelForm;
          },
          "plant friction's form: model (the identified model's, default) or stribeck-ripple (Stribeck curve + ripple)")
      ->check(CLI::IsMember({"model", "stribeck-ripple"}));
  command.add_option("--stribeck-velocity", s.stribeck_velocity_rad_s, "stribeck-ripple: v_s [rad/s]")
      ->check(CLI::Range(1e-4, 1.0))
      ->capture_default_str();
  command.add_option("--static-ratio", s.static_to_coulomb, "stribeck-ripple: plant static / Coulomb")
      ->check(CLI::Range(1.0, 3.0))
      ->capture_default_str();
  command.add_option("--ripple-fraction", s.ripple_fraction, "stribeck-ripple: ripple amplitude, fraction of Coulomb")
      ->check(CLI::Range(0.0, 0.5))
      ->capture_default_str();
  command.add_option("--stribeck-sweep", s.stribeck_velocity_sweep, "stribeck-ripple: v_s values of the sweep [rad/s]")
      ->check(CLI::Range(1e-4, 1.0))
      ->capture_default_str();
  command.add_option("--ripple-sweep", s.ripple_fraction_sweep, "stribeck-ripple: ripple amplitudes of the sweep (of Coulomb)")
      ->check(CLI::Range(0.0, 0.5))
      ->capture_default_str();
  command.add_option("--sweep-joints", s.sweep_joints, "stribeck-ripple: joints of the sweep (1-based)")
      ->check(CLI::Range(1, 7))
      ->capture_default_str();
}

// `phri experiment friction-identification`: the same as `phri identify-friction`.
CLI::App* add_friction_alias(CLI::App& experiment, phri::FrictionIdentificationOptions& friction) {
  auto* alias = experiment.add_subcommand("friction-identification", "Same as 'phri identify-friction'");
  alias->add_option("--out", friction.output_dir, "output folder");
  alias->add_option("--seed", friction.seed, "seed");
  add_plant_friction_options(*alias, friction);
  return alias;
}

// The figure of the run's log; an MCAP log is exported to a CSV beside it for the script, then removed.
void draw_run_figure(const std::string& log_path, const std::string& png, const phri::Config& config) {
  if (config.logging.format == phri::LogFormat::kCsv) return draw_demo_figure(log_path, png, config);
  const std::string csv = std::filesystem::path(log_path).replace_extension(".figure.csv").string();
  try {
    phri::export_mcap_log_csv(log_path, csv, false);
    draw_demo_figure(csv, png, config);
  } catch (const phri::Error& e) {
    std::fprintf(stderr, "phri: warning: no figure: %s\n", e.what());
  }
  std::error_code ignored;
  std::filesystem::remove(csv, ignored);
}

// Where the dashboard's page is: --web-root, else web/ here, else the installed copy beside the
// program (cmake --install), else the source tree's (scripts/setup put the npm packages there).
std::string dashboard_web_root(const std::string& given) {
  if (!given.empty()) return given;
  std::vector<std::filesystem::path> candidates = {"web"};
  std::error_code ec;
  const std::filesystem::path exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (!ec) candidates.push_back(exe.parent_path().parent_path() / PHRI_INSTALL_DATADIR / "phri" / "web");
  candidates.push_back(std::filesystem::path(PHRI_SOURCE_DIR) / "web");
  for (const auto& dir : candidates) {
    if (std::filesystem::exists(dir / "index.html") && std::filesystem::exists(dir / "node_modules")) return dir.string();
  }
  return candidates.back().string();
}

struct DashboardArguments {
  bool enabled = false;
  int port = 8080;
  std::string bind = "127.0.0.1";
  double push_max_N = 100.0;
  std::string web_root;
};

// Binds the server (an address in use fails here, before the run) and prints the page's address.
std::unique_ptr<phri::DashboardServer> start_dashboard(const DashboardArguments& args, const phri::Config& config,
                                                       const phri::Controller& cycle, phri::LiveChannel& live) {
  phri::DashboardSettings settings;
  settings.bind_address = args.bind;
  settings.port = args.port;
  settings.push_max_N = args.push_max_N;
  settings.web_root = dashboard_web_root(args.web_root);
  if (config.logging_enabled) settings.log_path = config.logging.path;
  settings.body_regions = config.body_regions;
  if (args.bind != "127.0.0.1" && args.bind != "localhost") {
    std::fprintf(stderr, "phri: warning: the dashboard listens on %s, not only on this machine: whoever reaches it with "
                 "the token moves the arm\n", args.bind.c_str());
  }
  auto server = std::make_unique<phri::DashboardServer>(live, cycle, settings);
  std::printf("phri dashboard: %s\n", server->url().c_str());
  std::fflush(stdout);
  return server;
}

// SIGINT and SIGTERM during `phri run`: the handler only stores lock-free atomics; the loop polls
// the flag once a cycle (RunOptions::stop_requested). SA_RESETHAND: a second signal kills.
std::atomic<bool> g_stop_requested{false};
std::atomic<int> g_stop_signal{0};
static_assert(std::atomic<bool>::is_always_lock_free && std::atomic<int>::is_always_lock_free);

extern "C" void request_stop(int signal) {
  g_stop_signal.store(signal);
  g_stop_requested.store(true);
}

class StopOnSignals {
public:
  StopOnSignals() {
    struct sigaction action {};
    action.sa_handler = request_stop;
    action.sa_flags = SA_RESETHAND;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
  }
  ~StopOnSignals() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  StopOnSignals(const StopOnSignals&) = delete;
  StopOnSignals& operator=(const StopOnSignals&) = delete;

private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

// 128 + the signal's number when one ended the run (said on stderr), 3 after a safe hold, else 0.
int run_exit_status(const phri::RunSummary& summary, double duration_s) {
  if (!summary.interrupted) return summary.safe_hold ? phri::cli::kSafetyStop : phri::cli::kOk;
  const int signal = g_stop_signal.load();
  std::fprintf(stderr, "phri: interrupted by %s after %.3f s of the %.1f s run; it ended there, its files written\n",
               signal == SIGINT ? "SIGINT" : "SIGTERM", summary.simulated_s, duration_s);
  return phri::cli::kSignalBase + signal;
}

struct RunArguments {
  DashboardArguments dashboard;
  std::string config_path;
  std::string robot_folder;  ///< robots/<robot>: replaces the configuration's robot
  bool lockstep = false;
  bool real_time = false;
  double duration_s = -1.0;
  std::string out_dir = "out";
  bool figure = true;
  std::string log_format;  ///< --log csv|mcap (empty: the configuration's logging.format)
  KortexArguments kortex;
  Ros2Arguments ros2;
};

// The generated plant's warnings (none for a hand-written MJCF).
std::vector<std::string> generated_plant_warnings(const phri::SimRobotConfig& plant) {
  if (plant.urdf_path.empty()) return {};
  phri::UrdfPlantOptions options;
  options.urdf_path = plant.urdf_path;
  options.locked_joints = plant.locked_joints;
  options.balance_inertia = plant.balance_inertia;
  return phri::UrdfPlant::generate(options).warnings;
}

// The robots `phri run --backend` drives: the simulation, the Kortex backends (kortex_backend.cpp).
phri::BackendRegistry run_backends(const KortexArguments& kortex) {
  phri::BackendRegistry registry;
  phri::register_sim_backend(registry);
  register_kortex_backends(registry, kortex);
  return registry;
}

void print_run_line(const RunArguments& args, const phri::Config& config) {
  std::printf("phri run: %s, %.1f s, %s%s%s\n", args.config_path.c_str(), config.run.duration_s,
              config.run.pacing == phri::LoopClock::Pacing::kLockstep ? "lockstep" : "real time",
              args.kortex.backend == "sim" ? "" : (", backend " + args.kortex.backend).c_str(), args.kortex.dry_run ? ", dry run" : "");
  // Which wrench drives dual compliance's touch trigger (Controller::touch_source()).
  std::printf("touch trigger: %s\n", config.plant.ft_sensor_present()
                                         ? "F/T sensor wrench"
                                         : "end-effector wrench estimated from the observer's tau_ext (no F/T sensor; least squares through J_ee)");
}

// The run's log, when enabled; its legend names the links of the power-and-force-limiting columns.
void open_run_log(phri::Config& config, const phri::Controller& cycle, std::optional<phri::Logger>& logger) {
  if (!config.logging_enabled) return;
  if (config.body_regions && cycle.collision() != nullptr) {
    config.logging.pfl_links = phri::PowerForceLimitMonitor::monitored_links(*cycle.collision());
  }
  for (const phri::Joint& j : cycle.model().joints()) config.logging.joint_names.push_back(j.name);
  config.logging.has_ft_sensor = config.plant.ft_sensor_present();
  config.logging.topic_namespace = config.ros2.topic_namespace;
  logger.emplace(config.logging);
}

// The summary on stdout and in <out>/summary.md.
void write_run_summary(const phri::RunSummary& summary, const std::string& config_path, const std::filesystem::path& out) {
  phri::print_run_summary(summary, std::cout);
  std::ostringstream md;
  md << "# phri run: " << config_path << "\n\n";
  phri::print_run_summary(summary, md);
  phri::write_text_file((out / "summary.md").string(), md.str());
  std::printf("\nwrote %s\n", (out / "summary.md").c_str());
}

// --log over logging.format; then the format is settled (auto: by the run's final duration).
void apply_log_format(const std::string& log_format, phri::Config& config) {
  if (!log_format.empty()) {
    config.log_format_auto = false;
    config.logging.format = log_format == "mcap" ? phri::LogFormat::kMcap : phri::LogFormat::kCsv;
  }
  phri::resolve_log_format(config);
}

// `phri run`: loads the configuration, runs the session, writes the log, summary and figure.
int run_command(const RunArguments& args) {
  phri::Config config = phri::Config::from_yaml_file(args.config_path, args.robot_folder);
  if (args.lockstep) config.run.pacing = phri::LoopClock::Pacing::kLockstep;
  if (args.real_time) config.run.pacing = phri::LoopClock::Pacing::kRealTime;
  if (args.duration_s > 0.0) config.run.duration_s = args.duration_s;
  apply_log_format(args.log_format, config);
  apply_ros2_arguments(args.ros2, config.ros2, config.run.pacing == phri::LoopClock::Pacing::kLockstep);
  phri::ensure_output_directory(args.out_dir);
  const std::filesystem::path out(args.out_dir);
  config.logging.path = (out / std::filesystem::path(config.logging.path).filename()).string();

  // Everything that can refuse the configuration is built before the first line of output.
  check_kortex_arguments(args.kortex);
  const phri::BackendRegistry backends = run_backends(args.kortex);
  backends.require(args.kortex.backend);
  const bool real_arm = args.kortex.backend == "kortex";
  if (real_arm && args.lockstep) throw phri::ConfigError("--lockstep", "", "the real arm runs in real time (--backend kortex)");
  if (real_arm) config.run.pacing = phri::LoopClock::Pacing::kRealTime;
  phri::Controller cycle(config.controller);
  // What the URDF loader and the plant generator accepted but the user should know (one line each,
  // naming the link): odd inertias, a base inertial ignored, inertias MuJoCo balanced.
  for (const std::string& warning : cycle.model().warnings()) std::fprintf(stderr, "phri: warning: %s\n", warning.c_str());
  for (const std::string& warning : generated_plant_warnings(config.plant)) std::fprintf(stderr, "phri: warning: %s\n", warning.c_str());
  for (const std::string& warning : phri::config_warnings(config)) std::fprintf(stderr, "phri: warning: %s\n", warning.c_str());
  phri::Fsm fsm(config.fsm, cycle);
  if (args.kortex.dry_run) {  // a Kortex backend (check_kortex_arguments), only read
    const std::unique_ptr<KortexBackend> kortex = make_kortex_backend(args.kortex, config, cycle.model());
    print_run_line(args, config);
    return kortex_dry_run(*kortex, config.run.duration_s, config.run.pacing == phri::LoopClock::Pacing::kRealTime, std::cout);
  }
  // The backend last: a real arm connects and starts then (a refusal is one line, the arm put back).
  const std::unique_ptr<phri::Backend> backend = backends.make(args.kortex.backend, {config, cycle.model()});
  phri::RobotInterface& robot = backend->robot();
  print_run_line(args, config);
  std::unique_ptr<phri::Gamepad> gamepad;
  if (config.gamepad.enabled) {
    gamepad = std::make_unique<phri::Gamepad>(config.gamepad);
    gamepad->start();
  }
  std::optional<phri::Logger> logger;
  open_run_log(config, cycle, logger);
  phri::LiveChannel live;
  std::unique_ptr<phri::DashboardServer> dashboard;
  if (args.dashboard.enabled) dashboard = start_dashboard(args.dashboard, config, cycle, live);

  phri::RunOptions options;
  if (dashboard || backend->brake_on_interrupt()) options.live = &live;
  options.pushes = backend->pushes();
  options.ground_truth = backend->ground_truth();
  if (config.body_regions) options.body_regions = &*config.body_regions;
  // Until the files are written. On the arm, Ctrl-C brakes to rest first (InterruptToStop replaces
  // the SIGINT handler); SIGTERM ends the loop there too, then the backend's exit sequence.
  const StopOnSignals stop_on_signals;
  options.stop_requested = &g_stop_requested;
  std::optional<InterruptToStop> interrupt;
  if (backend->brake_on_interrupt()) interrupt.emplace(live);
  options.duration_s = config.run.duration_s;
  options.real_time = config.run.pacing == phri::LoopClock::Pacing::kRealTime;
  options.phases.push_back({0.0, "startup"});
  for (const phri::TimedEvent& e : config.fsm.timeline) options.phases.push_back({e.time_s, std::string(phri::to_string(e.event))});
  const std::unique_ptr<Ros2Run> ros2 = Ros2Run::start_if_enabled(config.ros2, cycle, options, std::cout);
  phri::RobotInterface& driven = ros2 ? ros2->robot(robot) : robot;
  const phri::RunSummary summary = phri::run_session(driven, cycle, fsm, gamepad.get(), logger ? &*logger : nullptr, options, std::cout);
  if (gamepad) gamepad->stop();
  if (dashboard) dashboard->stop();
  std::printf("\n");
  if (ros2) ros2->finish(std::cout);
  if (const std::string report = backend->report(); !report.empty()) std::printf("%s\n", report.c_str());
  write_run_summary(summary, args.config_path, out);
  if (logger) {
    const phri::LoggerStats stats = logger->close();
    std::printf("%s\n", logger->summary().c_str());
    if (stats.dropped > 0 || stats.write_error) std::fprintf(stderr, "phri: warning: log incomplete\n");
    if (args.figure) draw_run_figure(logger->path(), (out / "demo.png").string(), config);
  }
  return run_exit_status(summary, config.run.duration_s);
}

// `--duration`: a finite number of seconds (CLI::Range lets NaN through: every comparison with it
// is false) in [0.001, RunSettings::kMaxDuration_s], the configuration's own cap on run.duration_s.
CLI::Validator duration_seconds() {
  return CLI::Validator(
      [](std::string& text) -> std::string {
        const std::optional<double> number = phri::parse_number(text);
        if (!number) return "expected a number of seconds, got '" + text + "'";
        const double value = *number;
        if (!std::isfinite(value)) return "must be a finite number of seconds, got '" + text + "'";
        if (value < 0.001) return "must be at least 0.001 s, got " + text;
        if (value > phri::RunSettings::kMaxDuration_s) {
          return "at most 3600 s (the run keeps one cycle time per period), got " + text;
        }
        return std::string();
      },
      "SECONDS");
}

// Checks every command's options share, added after the commands are built: an empty --out would
// write into the working directory; CLI11 reads a seed with strtoull, which wraps "-1" to 2^64 - 1.
void add_shared_checks(CLI::App& app) {
  const CLI::Validator non_empty(
      [](std::string& text) { return text.empty() ? std::string("must not be empty") : std::string(); }, "PATH");
  const CLI::Validator seed(
      [](std::string& text) {
        const bool digits = !text.empty() && text.find_first_not_of("0123456789") == std::string::npos;
        return digits ? std::string() : "a seed is a whole number from 0 to 2^64 - 1, got '" + text + "'";
      },
      "SEED");
  for (CLI::Option* option : app.get_options()) {
    for (const std::string& name : option->get_lnames()) {
      if (name == "out") option->check(non_empty);
      if (name.find("seed") != std::string::npos) option->check(seed);
    }
  }
  for (CLI::App* command : app.get_subcommands([](CLI::App*) { return true; })) add_shared_checks(*command);
}

CLI::App* add_run_command(CLI::App& app, RunArguments& args) {
  auto* run = app.add_subcommand("run", "Run a session on the simulated arm from one configuration file");
  run->add_option("--config", args.config_path, "configuration YAML (e.g. configs/demo.yaml)")
      ->required()
      ->check(CLI::ExistingFile);
  run->add_option("--robot", args.robot_folder, "robot bundle folder with its robot.yaml (e.g. robots/kinova_gen3), "
                  "in place of the configuration's robot")
      ->check(CLI::ExistingDirectory);
  auto* lockstep = run->add_flag("--lockstep", args.lockstep, "as fast as possible (same code path)");
  run->add_flag("--realtime", args.real_time, "paced by the 1 ms real-time clock")->excludes(lockstep);
  run->add_option("--duration", args.duration_s, "robot time to run [s], at most 3600")
      ->check(duration_seconds());
  run->add_option("--out", args.out_dir, "output folder (log, summary, figure)")->capture_default_str();
  run->add_flag("!--no-figure", args.figure, "skip the figure");
  run->add_option("--log", args.log_format, "log format: csv (text) or mcap (ROS 2 messages, zstd; read by ros2 bag, "
                  "Foxglove, PlotJuggler, `phri log export --csv`); default: the configuration's logging.format "
                  "(auto: mcap for runs over 60 s)")
      ->check(CLI::IsMember({"csv", "mcap"}));
  run->add_option("--backend", args.kortex.backend,
                  "the arm: sim (the simulated Gen3), kortex (the real Gen3 through Kinova's Kortex API; needs a build with "
                  "-DPHRI_KORTEX_API_DIR) or kortex-emulator (the Kortex backend on an emulated arm over the simulation)")
      ->capture_default_str();
  run->add_option("--ip", args.kortex.ip, "the arm's address (--backend kortex; TCP 10000, UDP 10001)")->capture_default_str();
  run->add_option("--ft-serial", args.kortex.ft_serial, "the Bota SensONE's serial device (--backend kortex)");
  run->add_option("--emulate-fault", args.kortex.emulate_fault,
                  "--backend kortex-emulator: a link fault the emulated arm injects at robot time T: packet-loss:P@T, "
                  "stall:MS@T or drop-session@T (e.g. packet-loss:0.01@3.5)");
  run->add_flag("--dry-run", args.kortex.dry_run, "connect and read the arm, print its state; no torque is ever sent "
                "(the actuators hold the measured pose in position mode)");
  auto* dashboard = run->add_flag("--dashboard", args.dashboard.enabled,
                                  "serve the live dashboard (3-D view, plots, buttons, sliders, drag-to-push) on "
                                  "127.0.0.1; its address, with a random token, is printed at start");
  run->add_option("--port", args.dashboard.port, "dashboard port (0: any free one)")
      ->check(CLI::Range(0, 65535))->needs(dashboard)->capture_default_str();
  run->add_option("--bind", args.dashboard.bind, "dashboard address to listen on (another than 127.0.0.1: a warning)")
      ->needs(dashboard)->capture_default_str();
  run->add_option("--push-max", args.dashboard.push_max_N, "drag-to-push force cap [N]")
      ->check(CLI::Range(1.0, 1000.0))->needs(dashboard)->capture_default_str();
  run->add_option("--web-root", args.dashboard.web_root, "folder of the dashboard's page (default: web/)")
      ->needs(dashboard)->check(CLI::ExistingDirectory);
  add_ros2_options(*run, args.ros2);
  return run;
}

struct InfoArguments {
  std::string urdf_path, robot_folder, tip, frame;
};

int info_command(const InfoArguments& args) {
  if (args.urdf_path.empty() && args.robot_folder.empty()) {
    throw phri::ConfigError("phri info", "--urdf", "required: a URDF file (--urdf) or a robot bundle (--robot)");
  }
  if (!args.robot_folder.empty()) return print_robot_summary(args.robot_folder, args.frame);
  return print_model_summary(args.urdf_path, args.tip, args.frame);
}

CLI::App* add_info_command(CLI::App& app, InfoArguments& args) {
  auto* info = app.add_subcommand("info", "Load a robot description and print a summary of its model");
  auto* urdf = info->add_option("--urdf", args.urdf_path, "URDF file");
  auto* robot = info->add_option("--robot", args.robot_folder, "robot bundle (robots/<robot>): its chain, drives and end of arm")
                    ->check(CLI::ExistingDirectory);
  urdf->excludes(robot);
  info->add_option("--tip", args.tip, "tip link of the chain (default: end of the movable chain)");
  info->add_option("--frame", args.frame, "frame whose position is printed (default: the tip)");
  return info;
}

struct FitCollisionArguments {
  std::string robot_folder, out_path;
  phri::CapsuleFitOptions options;
};

CLI::App* add_fit_collision_command(CLI::App& app, FitCollisionArguments& args) {
  auto* fit = app.add_subcommand("fit-collision", "Fit self-collision capsules from a robot bundle's URDF (a collision.yaml)");
  fit->add_option("--robot", args.robot_folder, "robot bundle folder (robots/<robot>)")->required()->check(CLI::ExistingDirectory);
  fit->add_option("--out", args.out_path, "collision.yaml to write (default: standard output)");
  fit->add_option("--radius", args.options.link_frame_radius_m, "capsule radius of links without collision geometry [m]")
      ->check(CLI::Range(0.001, 0.5))->capture_default_str();
  fit->add_option("--clearance", args.options.clearance_m, "pairs closer at the home posture are left out [m]")
      ->check(CLI::Range(0.0, 0.5))->capture_default_str();
  return fit;
}

// `phri fit-collision`: the bundle's model at its home posture; notes on stderr, the YAML out.
int fit_collision_command(const FitCollisionArguments& args) {
  const phri::RobotBundle robot = phri::RobotBundle::from_folder(args.robot_folder);
  phri::ControllerSettings settings;
  robot.apply_to(settings);
  settings.payloads.clear();
  const phri::Model model = phri::Model::from_urdf_file(robot.urdf_path, phri::Controller::model_options(settings));
  std::ifstream file(robot.urdf_path);
  std::stringstream urdf;
  urdf << file.rdbuf();
  const Eigen::VectorXd home = Eigen::Map<const Eigen::VectorXd>(robot.home_q_rad.data(), model.nq());
  const phri::CapsuleFit fit = phri::fit_capsules(urdf.str(), model, home, args.options);
  for (const std::string& note : fit.notes) std::fprintf(stderr, "phri fit-collision: %s\n", note.c_str());
  if (args.out_path.empty()) {
    std::cout << fit.yaml;
    return 0;
  }
  std::ofstream out(args.out_path);
  out << fit.yaml;
  if (!out) throw phri::IoError(args.out_path, "cannot write");
  std::printf("phri fit-collision: %d capsules, %d pairs -> %s\n", fit.capsules, fit.pairs, args.out_path.c_str());
  return 0;
}

CLI::App* add_identify_command(CLI::App& app, phri::FrictionIdentificationOptions& friction) {
  auto* identify = app.add_subcommand("identify-friction",
                                      "Identify joint friction on the simulated arm (paper: friction identification)");
  identify->add_option("--out", friction.output_dir, "output folder")->capture_default_str();
  identify->add_option("--seed", friction.seed, "seed of the plant's friction perturbation and noise")->capture_default_str();
  identify->add_option("--perturbation", friction.friction_perturbation,
                       "plant friction off actuators.yaml by up to this fraction")
      ->check(CLI::Range(0.0, 0.9))
      ->capture_default_str();
  identify->add_option("--joints", friction.joints, "joints to identify (1-based)")->check(CLI::Range(1, 7));
  identify->add_option("--plant", friction.plant_config_path, "plant configuration")->check(CLI::ExistingFile);
  add_plant_friction_options(*identify, friction);
  return identify;
}

struct TrackingArguments {
  phri::TorqueTrackingOptions torque;
  bool static_ft = false;
  std::uint64_t mismatch_seed = 0;
  CLI::Option* mismatch_seed_option = nullptr;  // given or not: the plant file's seed otherwise
  CLI::Option* out_option = nullptr;            // given or not: the sweep has its own default folder
  bool static_sweep = false;
  phri::StaticSweepOptions sweep;
};

CLI::App* add_torque_tracking_command(CLI::App& experiment, TrackingArguments& args) {
  auto* tracking = experiment.add_subcommand("torque-tracking", "Custom vs Kinova high-velocity torque loop");
  phri::TorqueTrackingOptions& torque = args.torque;
  args.out_option = tracking->add_option("--out", torque.output_dir, "output folder")->capture_default_str();
  tracking->add_option("--seed", torque.seed, "seed of the plant's noise")->capture_default_str();
  tracking->add_option("--static-s", torque.static_duration_s, "static scenario duration")->check(CLI::Range(1.0, 600.0));
  tracking->add_option("--dynamic-s", torque.dynamic_duration_s, "dynamic scenario duration")->check(CLI::Range(1.0, 600.0));
  tracking->add_option("--plant", torque.plant_config_path, "plant configuration")->check(CLI::ExistingFile);
  tracking->add_flag("--elastic", torque.elastic,
                     "on the plant `phri evaluate` uses: elastic joints (plant.elasticity) and the paper's open-loop "
                     "position mode; writes each run's elastic_modes_<scenario>_<loop>.csv");
  tracking->add_flag("--static-ft", args.static_ft,
                     "static scenario as in the paper: the weight is hung after the switch and compensated through the "
                     "F/T sensor (J^T F), not the joint-torque observer");
  tracking->add_option("--torque-constant-error", torque.torque_constant_error,
                       "plant drive gain error: each joint's true K_T G_r off the nominal by up to this fraction "
                       "(default: the plant file's mismatch.torque_constant_fraction)")
      ->check(CLI::Range(0.0, 0.5));
  args.mismatch_seed_option =
      tracking->add_option("--mismatch-seed", args.mismatch_seed, "seed of the plant's inertial and drive-gain mismatch "
                                                                  "(default: the plant file's mismatch.seed)");
  tracking->add_flag("--static-sweep", args.static_sweep,
                     "instead: the static scenario at several drive gain errors x mismatch seeds (why the static "
                     "ratio depends on the arm; see src/phri/experiments/torque_tracking_sweep.hpp)");
  tracking->add_option("--sweep-errors", args.sweep.torque_constant_errors, "drive gain errors of the sweep")
      ->check(CLI::Range(0.0, 0.5))
      ->capture_default_str();
  tracking->add_option("--sweep-seeds", args.sweep.mismatch_seeds, "mismatch seeds of the sweep")->capture_default_str();
  return tracking;
}

struct SafetyFuzzArguments {
  phri::SafetyFuzzOptions fuzz;
  std::string faults = "all";
  bool no_targeted = false;
  bool no_motion_faults = false;
  bool fail_on_violation = false;
};

CLI::App* add_safety_fuzz_command(CLI::App& experiment, SafetyFuzzArguments& args) {
  auto* fuzz = experiment.add_subcommand("safety-fuzz", "Seeded random pushes and sensor faults against the safety stage");
  phri::SafetyFuzzOptions& o = args.fuzz;
  fuzz->add_option("--pushes", o.pushes, "random pushes, split over the 16 mode x loop pairs")
      ->check(CLI::Range(0, 1000000))
      ->capture_default_str();
  fuzz->add_option("--seed", o.seed, "seed of the pushes, faults and plants")->capture_default_str();
  fuzz->add_option("--out", o.output_dir, "output folder")->capture_default_str();
  fuzz->add_option("--jobs", o.jobs, "threads")->check(CLI::Range(1, 64))->capture_default_str();
  fuzz->add_option("--faults", args.faults, "sensor faults: all, subset or none")
      ->check(CLI::IsMember({"all", "subset", "none"}))
      ->capture_default_str();
  fuzz->add_option("--pushes-per-run", o.pushes_per_run, "pushes on one plant + controller")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  fuzz->add_flag("--no-targeted", args.no_targeted, "leave out the pushes toward the joint limits and the wrist folds");
  fuzz->add_flag("--no-motion-faults", args.no_motion_faults,
                 "inject the faults only into an arm at rest (not during a push, nor after a loop switch)");
  fuzz->add_option("--replay", o.replay, "run only this run (an id from report.md)");
  fuzz->add_option("--trace", o.trace_path, "with --replay: the run's every cycle as CSV (plant truth, command, push)")
      ->needs("--replay");
  fuzz->add_option("--plant", o.plant_config_path, "plant configuration")->check(CLI::ExistingFile);
  fuzz->add_option("--robot", o.robot_folder, "robot bundle (robots/<robot>) in place of the Gen3's files")
      ->check(CLI::ExistingDirectory);
  fuzz->add_flag("--fail-on-violation", args.fail_on_violation, "exit with status 1 when a controller failure was found");
  return fuzz;
}

CLI::App* add_dashboard_load_command(CLI::App& experiment, phri::DashboardLoadOptions& o) {
  auto* load = experiment.add_subcommand(
      "dashboard-load", "The loop's p99.9 cycle time without and with the dashboard serving many clients (same run)");
  load->add_option("--config", o.config_path, "run configuration")->check(CLI::ExistingFile)->capture_default_str();
  load->add_option("--segment-s", o.segment_s, "robot time of each segment [s]")->check(CLI::Range(2.0, 600.0))->capture_default_str();
  load->add_option("--repeats", o.repeats, "segment pairs (without, with), interleaved")->check(CLI::Range(1, 50))->capture_default_str();
  load->add_option("--clients", o.clients, "stream clients connecting and leaving in each segment with the dashboard")
      ->check(CLI::Range(0, 10000))->capture_default_str();
  load->add_option("--web-root", o.web_root, "folder of the dashboard's page (default: web/)")->check(CLI::ExistingDirectory);
  return load;
}

int safety_fuzz_command(SafetyFuzzArguments& args) {
  phri::SafetyFuzzOptions& o = args.fuzz;
  o.faults = args.faults == "none" ? phri::FaultSet::kNone : args.faults == "subset" ? phri::FaultSet::kSubset : phri::FaultSet::kAll;
  o.targeted_pushes = !args.no_targeted;
  o.motion_faults = !args.no_motion_faults;
  for (std::string* path : {&o.plant_config_path, &o.urdf_path, &o.actuators_path, &o.collision_path, &o.figure_script}) {
    *path = locate(*path);
  }
  return phri::run_safety_fuzz_command(o, args.fail_on_violation, std::cout);
}

struct DropArguments {
  phri::DropTestOptions drop;
  std::string source = "fused";
  double cable_damping = -1.0;  // < 0: the plant file's
};

CLI::App* add_drop_test_command(CLI::App& experiment, DropArguments& args) {
  auto* drop = experiment.add_subcommand("drop-test", "The paper's drop test: torque vs position mode, metrics per drop");
  phri::DropTestOptions& o = args.drop;
  drop->add_option("--drops", o.drops, "drops per mode")->check(CLI::Range(1, 1000))->capture_default_str();
  drop->add_option("--jobs", o.jobs, "threads (drops are independent)")->check(CLI::Range(1, 64))->capture_default_str();
  drop->add_option("--out", o.output_dir, "output folder")->capture_default_str();
  drop->add_option("--seed", o.first_seed, "noise seed of the first drop (mismatch: + 1000)")->capture_default_str();
  drop->add_option("--source", args.source, "external torque of the torque mode: observer, ft or fused")
      ->check(CLI::IsMember({"observer", "ft", "fused"}))
      ->capture_default_str();
  drop->add_option("--observer-gain", o.observer_gain, "K_O [1/s]")->check(CLI::Range(0.1, 999.0))->capture_default_str();
  drop->add_option("--release", o.release_s, "release time [s]")->check(CLI::Range(1.0, 100.0))->capture_default_str();
  drop->add_option("--cable-damping", args.cable_damping, "cable damping [N.s/m] (default: the plant file's)")
      ->check(CLI::Range(0.0, 1e4));
  return drop;
}

int drop_test_command(DropArguments& args) {
  phri::DropTestOptions& o = args.drop;
  o.external_torque_source = *phri::external_torque_source_from_string(args.source);
  if (args.cable_damping >= 0.0) o.cable_damping_Ns_per_m = args.cable_damping;
  for (std::string* path : {&o.plant_config_path, &o.urdf_path, &o.actuators_path, &o.collision_path, &o.figure_script}) {
    *path = locate(*path);
  }
  phri::ensure_output_directory(o.output_dir);
  return phri::run_drop_test_command(o, std::cout);
}

int dynamic_tracking_command(phri::TorqueTrackingOptions t) {
  for (std::string* path : {&t.plant_config_path, &t.urdf_path, &t.actuators_path, &t.collision_path}) *path = locate(*path);
  phri::ensure_output_directory(t.output_dir);
  return phri::run_torque_tracking_command(t, std::cout);
}

int dual_compliance_command(phri::DualComplianceOptions d) {
  for (std::string* path : {&d.plant_config_path, &d.urdf_path, &d.actuators_path, &d.collision_path}) *path = locate(*path);
  phri::ensure_output_directory(d.output_dir);
  return phri::run_dual_compliance_command(d, std::cout);
}

const CLI::App* add_dynamic_tracking_command(CLI::App& experiment, phri::TorqueTrackingOptions& options) {
  auto* dynamic = experiment.add_subcommand("dynamic-tracking", "The dynamic scenario: position, custom, Kinova torque loops");
  dynamic->add_option("--out", options.output_dir, "output folder")->capture_default_str();
  dynamic->add_option("--duration", options.dynamic_duration_s, "after the switch [s]")
      ->check(CLI::Range(1.0, 600.0))
      ->capture_default_str();
  return dynamic;
}

const CLI::App* add_dual_compliance_command(CLI::App& experiment, phri::DualComplianceOptions& options) {
  auto* dual = experiment.add_subcommand("dual-compliance", "Guide the end effector by hand in dual compliance, release");
  dual->add_option("--out", options.output_dir, "output folder")->capture_default_str();
  return dual;
}

struct Iso9283Arguments {
  phri::Iso9283Options options;
  std::vector<std::string> loops;
};

const CLI::App* add_iso9283_command(CLI::App& experiment, Iso9283Arguments& args) {
  auto* iso = experiment.add_subcommand("iso9283", "ISO 9283 pose accuracy and repeatability (AP, RP) per low-level loop");
  iso->add_option("--out", args.options.output_dir, "output folder")->capture_default_str();
  iso->add_option("--cycles", args.options.cycles, "cycles through the five poses (the standard: 30)")
      ->check(CLI::Range(2, 1000))
      ->capture_default_str();
  iso->add_option("--loops", args.loops, "loops to measure (default: position custom kinova_torque_high_velocity kinova_torque)")
      ->check(CLI::IsMember({"position", "custom", "kinova_torque", "kinova_torque_high_velocity"}));
  iso->add_option("--dwell", args.options.dwell_s, "wait at each pose before it is taken [s]")
      ->check(CLI::Range(0.2, 10.0))
      ->capture_default_str();
  iso->add_option("--speed", args.options.max_speed_m_s, "peak speed of the moves [m/s]")
      ->check(CLI::Range(0.01, 1.0))
      ->capture_default_str();
  iso->add_option("--bands", args.options.bands_mm, "the tight and the coarse stabilisation band [mm]")
      ->check(CLI::Range(0.001, 10.0))
      ->capture_default_str();
  iso->add_option("--seed", args.options.seed, "plant seed (model mismatch, noise)")->capture_default_str();
  iso->add_option("--jobs", args.options.jobs, "threads (one loop each)")->check(CLI::Range(1, 64))->capture_default_str();
  return iso;
}

int iso9283_command(Iso9283Arguments args) {
  phri::Iso9283Options& o = args.options;
  for (std::string* path : {&o.plant_config_path, &o.urdf_path, &o.actuators_path, &o.collision_path, &o.figure_script}) {
    *path = locate(*path);
  }
  if (!args.loops.empty()) {
    o.loops.clear();
    for (const std::string& name : args.loops) o.loops.push_back(*phri::low_level_mode_from_string(name));
  }
  phri::ensure_output_directory(o.output_dir);
  return phri::run_iso9283_command(o, std::cout);
}

struct CollisionArguments {
  phri::CollisionOptions options;
  std::vector<std::string> loops, modes;
};

const CLI::App* add_collision_command(CLI::App& experiment, CollisionArguments& args) {
  auto* collision = experiment.add_subcommand("collision", "The tool hits a body region: peak and clamping forces (ISO/TS 15066)");
  phri::CollisionOptions& o = args.options;
  collision->add_option("--out", o.output_dir, "output folder")->capture_default_str();
  collision->add_option("--regions", o.regions, "body regions met, by name in the regions file")->capture_default_str();
  collision->add_option("--regions-file", o.regions_file, "the body regions (k, m_H, F_QS)")->capture_default_str();
  collision->add_option("--speeds", o.speeds_m_s, "point-to-point peak speeds [m/s]")
      ->check(CLI::Range(0.01, 3.0))
      ->capture_default_str();
  collision->add_flag("!--no-dynamic", o.dynamic, "leave out the dynamic scenario");
  collision->add_option("--modes", args.modes, "compliance modes (default: null_space full_body dual)")
      ->check(CLI::IsMember({"stiff", "null_space", "full_body", "dual"}));
  collision->add_option("--loops", args.loops, "low-level loops (default: position custom kinova_torque_high_velocity)")
      ->check(CLI::IsMember({"position", "custom", "kinova_torque", "kinova_torque_high_velocity"}));
  collision->add_option("--window", o.contact_window_s, "measured after the first touch [s]")
      ->check(CLI::Range(0.3, 10.0))
      ->capture_default_str();
  collision->add_option("--seed", o.seed, "plant seed (model mismatch, noise)")->capture_default_str();
  collision->add_option("--jobs", o.jobs, "threads")->check(CLI::Range(1, 64))->capture_default_str();
  return collision;
}

int collision_command(CollisionArguments args) {
  phri::CollisionOptions& o = args.options;
  for (std::string* path : {&o.plant_config_path, &o.urdf_path, &o.actuators_path, &o.collision_path, &o.regions_file,
                            &o.figure_script}) {
    *path = locate(*path);
  }
  if (!args.loops.empty()) {
    o.loops.clear();
    for (const std::string& name : args.loops) o.loops.push_back(*phri::low_level_mode_from_string(name));
  }
  if (!args.modes.empty()) {
    o.modes.clear();
    for (const std::string& name : args.modes) o.modes.push_back(*phri::compliance_mode_from_string(name));
  }
  phri::collision_regions(o);  // refused before the output folder is made
  phri::ensure_output_directory(o.output_dir);
  return phri::run_collision_command(o, std::cout);
}

const CLI::App* add_evaluate_command(CLI::App& app, phri::EvaluationOptions& evaluation) {
  auto* evaluate = app.add_subcommand("evaluate", "The paper's five evaluations and a report (report.md, report.html)");
  evaluate->add_option("--out", evaluation.output_dir, "output folder")->capture_default_str();
  evaluate->add_flag("--quick", evaluation.quick, "short protocols (a smoke test; not the paper's numbers)");
  evaluate->add_option("--jobs", evaluation.jobs, "threads for the drops")->check(CLI::Range(1, 64))->capture_default_str();
  return evaluate;
}

// `phri evaluate`: the files are found from the working directory, else from the source tree.
int evaluate_command(phri::EvaluationOptions e) {
  const std::string probe = locate("configs/plant_gen3.yaml");
  e.root = probe == "configs/plant_gen3.yaml" ? "." : std::string(PHRI_SOURCE_DIR);
  return phri::run_evaluation_command(e, std::cout);
}

// `phri identify-friction`: the experiment with its files found (see locate).
int friction_identification_command(phri::FrictionIdentificationOptions friction) {
  for (std::string* path : {&friction.plant_config_path, &friction.urdf_path, &friction.figure_script}) *path = locate(*path);
  phri::ensure_output_directory(friction.output_dir);  // before the work: an unwritable folder fails now
  return phri::run_friction_identification_command(friction, std::cout);
}

// `phri experiment torque-tracking [--static-sweep]`: the options completed from the flags, the
// files found (see locate).
int torque_tracking_command(TrackingArguments& args) {
  phri::TorqueTrackingOptions& torque = args.torque;
  if (args.static_ft) {
    torque.static_external_torque = phri::ExternalTorqueSource::kForceTorqueSensor;
    torque.payload_mode = phri::PayloadMode::kHungAfterSwitch;
  }
  if (args.mismatch_seed_option->count() > 0) torque.mismatch_seed = args.mismatch_seed;
  if (torque.elastic) phri::use_evaluation_plant(torque);
  for (std::string* path : {&torque.plant_config_path, &torque.urdf_path, &torque.actuators_path, &torque.collision_path,
                            &torque.figure_script, &args.sweep.figure_script}) {
    *path = locate(*path);
  }
  if (!args.static_sweep) {
    phri::ensure_output_directory(torque.output_dir);  // before the work: an unwritable folder fails now
    return phri::run_torque_tracking_command(torque, std::cout);
  }
  args.sweep.tracking = torque;
  if (args.out_option->count() > 0) args.sweep.output_dir = torque.output_dir;
  phri::ensure_output_directory(args.sweep.output_dir);
  return phri::run_static_sweep_command(args.sweep, std::cout);
}

// The command words of a command line (`phri bogus`, `phri experiment bogus`, `phri`): CLI11 only
// says "A subcommand is required"; this names the word and the commands there are. Empty when the
// words are commands (options and the leaf command's own arguments are left to CLI11).
std::string command_word_error(CLI::App& app, int argc, char** argv) {
  CLI::App* level = &app;
  std::string words;
  for (int i = 1;; ++i) {
    const std::vector<CLI::App*> commands = level->get_subcommands([](CLI::App*) { return true; });
    if (commands.empty()) return "";
    std::string names;
    for (const CLI::App* c : commands) names += (names.empty() ? "" : ", ") + c->get_name();
    const std::string where = words.empty() ? "commands" : "'" + words + "' commands";
    if (i >= argc) {
      return words.empty() ? "a command is required (commands: " + names + ")"
                           : "'" + words + "' needs a command (" + where + ": " + names + ")";
    }
    const std::string word = argv[i];
    if (!word.empty() && word[0] == '-') {
      // Before the first command only phri's own options (--help, --version) may come. CLI11 prints
      // the version and ignores whatever follows --version.
      const std::string name = word.substr(0, word.find('='));
      if (level == &app && name == "--version" && i + 1 < argc) {
        return "--version takes nothing after it, got '" + std::string(argv[i + 1]) + "'";
      }
      if (level != &app || app.get_option_no_throw(name) != nullptr || name == "-h" || name == "--help") return "";
      return "unknown option '" + name + "' before the command (commands: " + names + ")";
    }
    words += (words.empty() ? "" : " ") + word;
    const auto named = std::find_if(commands.begin(), commands.end(), [&](CLI::App* c) { return c->check_name(word); });
    if (named == commands.end()) return "unknown command '" + words + "' (" + where + ": " + names + ")";
    level = *named;
  }
}

// One line whatever the message: a library's multi-line text (every phri error is one line
// already) is joined with "; ".
int print_error(const char* what, int status = phri::cli::kBadInput) {
  std::string line;
  for (const char* c = what; *c != '\0'; ++c) {
    if (*c != '\n' && *c != '\r') {
      line += *c;
    } else if (!line.empty() && c[1] != '\0' && c[1] != '\n' && line.back() != ' ') {
      line += "; ";
    }
  }
  std::fprintf(stderr, "phri: error: %s\n", line.c_str());
  return status;
}

// Progress lines reach a pipe as they are printed, not at exit (std::cout writes through stdout:
// sync_with_stdio stays on); MuJoCo's own messages become phri lines on stderr.
void set_up_output() {
  std::setvbuf(stdout, nullptr, _IOLBF, 0);
  phri::route_mujoco_messages_to_stderr();
}

}  // namespace

int main(int argc, char** argv) {
  set_up_output();
  CLI::App app{"phri: control framework for physical human-robot interaction"};
  app.set_version_flag("--version", std::string("phri ") + phri::version());
  app.require_subcommand(1);
  // One line per error, naming what is wrong.
  app.failure_message([](const CLI::App*, const CLI::Error& e) { return std::string("phri: error: ") + e.what() + "\n"; });

  RunArguments run_args;
  InfoArguments info_args;
  phri::FrictionIdentificationOptions friction;
  TrackingArguments tracking_args;
  SafetyFuzzArguments fuzz_args;
  DropArguments drop_args;
  phri::TorqueTrackingOptions dynamic_options = phri::dynamic_tracking_options();
  phri::DualComplianceOptions dual_options;
  phri::EvaluationOptions evaluation;
  phri::DashboardLoadOptions load_args;
  const CLI::App* run = add_run_command(app, run_args);
  const CLI::App* info = add_info_command(app, info_args);
  const CLI::App* identify = add_identify_command(app, friction);
  auto* experiment = app.add_subcommand("experiment", "Run one of the paper's experiments on the simulated arm");
  experiment->require_subcommand(1);
  const CLI::App* tracking = add_torque_tracking_command(*experiment, tracking_args);
  const CLI::App* fuzz = add_safety_fuzz_command(*experiment, fuzz_args);
  const CLI::App* load = add_dashboard_load_command(*experiment, load_args);
  Ros2Commands ros2_commands(app, *experiment);  // ft-bridge, experiment ros2-load
  const CLI::App* friction_alias = add_friction_alias(*experiment, friction);
  const CLI::App* drop = add_drop_test_command(*experiment, drop_args);
  const CLI::App* dynamic = add_dynamic_tracking_command(*experiment, dynamic_options);
  const CLI::App* dual = add_dual_compliance_command(*experiment, dual_options);
  Iso9283Arguments iso_args;
  const CLI::App* iso = add_iso9283_command(*experiment, iso_args);
  CollisionArguments collision_args;
  const CLI::App* collision = add_collision_command(*experiment, collision_args);
  const CLI::App* evaluate = add_evaluate_command(app, evaluation);
  FitCollisionArguments fit_args;
  const CLI::App* fit_collision = add_fit_collision_command(app, fit_args);
  FtMonitorArguments ft_args;
  const CLI::App* ft_monitor = add_ft_monitor_command(app, ft_args);
  const LogCommands log_commands(app);

  add_shared_checks(app);
  if (const std::string error = command_word_error(app, argc, argv); !error.empty()) return print_error(error.c_str());
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    // --help and --version exit 0; every refusal 2, as phri's own (CLI11 has a code per kind).
    return app.exit(e) == 0 ? phri::cli::kOk : phri::cli::kBadInput;
  }
  try {
    if (run->parsed()) return run_command(run_args);
    if (info->parsed()) return info_command(info_args);
    if (fit_collision->parsed()) return fit_collision_command(fit_args);
    if (ft_monitor->parsed()) return ft_monitor_command(ft_args);
    if (log_commands.parsed()) return log_commands.run();
    if (ros2_commands.parsed()) return ros2_commands.run();
    if (identify->parsed() || friction_alias->parsed()) return friction_identification_command(friction);
    if (tracking->parsed()) return torque_tracking_command(tracking_args);
    if (fuzz->parsed()) return safety_fuzz_command(fuzz_args);
    if (drop->parsed()) return drop_test_command(drop_args);
    if (dynamic->parsed()) return dynamic_tracking_command(dynamic_options);
    if (dual->parsed()) return dual_compliance_command(dual_options);
    if (iso->parsed()) return iso9283_command(iso_args);
    if (collision->parsed()) return collision_command(collision_args);
    if (evaluate->parsed()) return evaluate_command(evaluation);
    if (load->parsed()) {
      load_args.config_path = locate(load_args.config_path);
      load_args.web_root = dashboard_web_root(load_args.web_root);
      return phri::run_dashboard_load_command(load_args, std::cout);
    }
  } catch (const phri::SubjectError& e) {  // IoError, ExperimentError: the system refused
    return print_error(e.what(), phri::cli::kSystemError);
  } catch (const phri::Error& e) {  // ConfigError, ArgumentError: the input
    return print_error(e.what());
  } catch (const std::exception& e) {  // from a library below (yaml-cpp, the standard library)
    return print_error(e.what(), phri::cli::kSystemError);
  }
  return 0;
}
