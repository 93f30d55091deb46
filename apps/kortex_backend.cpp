#include "kortex_backend.hpp"

#include <phri/app/loop_clock.hpp>
#include <phri/app/plant_check.hpp>
#include <phri/core/error.hpp>
#include <phri/hardware/bota_sens_one.hpp>
#include <phri/hardware/kortex_emulator.hpp>
#include <phri/sim/sim_robot.hpp>
#ifdef PHRI_HAVE_KORTEX_SDK
#include <phri/hardware/kortex_sdk/kortex_sdk_client.hpp>
#endif

#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <ostream>
#include <vector>

namespace {

volatile std::sig_atomic_t g_interrupted = 0;

// The description's settings (actuators, home posture) with the controller's joint limits.
phri::KortexRobotSettings robot_settings(const phri::Config& config, const phri::Model& model, bool dry_run) {
  const phri::RobotDescription& description = config.plant;  // the robot's description (+ the plant's settings)
  if (description.actuators.size() != model.nq()) {
    throw phri::ConfigError(config.source, "robot.actuators", "one actuator per joint for the Kortex backend");
  }
  phri::KortexRobotSettings s = phri::kortex_robot_settings(description, config.controller.period_s);
  s.position_lower_rad = model.lower_limits();
  s.position_upper_rad = model.upper_limits();
  s.dry_run = dry_run;
  return s;
}

std::string health_line(const phri::KortexRobot& robot) {
  const phri::KortexHealth& h = robot.health();
  char line[320];
  std::snprintf(line, sizeof line,
                "kortex: %llu Refresh, %llu failed (longest run %d), %llu mode switches (%llu failed); arm %s%s%s%s",
                static_cast<unsigned long long>(h.refreshes), static_cast<unsigned long long>(h.failed_refreshes),
                h.longest_failure_run, static_cast<unsigned long long>(h.mode_switches),
                static_cast<unsigned long long>(h.failed_mode_switches), std::string(phri::kortex::to_string(h.arm_state)).c_str(),
                h.arm_fault ? ", FAULT" : "", h.link_lost ? ", LINK LOST (position hold)" : "",
                h.link_degraded ? ", LINK DEGRADED (safe stop)" : "");
  return line;
}

// The emulated arm over the simulated plant; the F/T fields come from the plant's sensor.
class EmulatedArm final : public KortexBackend {
public:
  EmulatedArm(const phri::Config& config, const phri::Model& model, const KortexArguments& args)
      : plant_(checked_plant(config)), arm_(plant_, plant_.state()) {
    if (!args.emulate_fault.empty()) arm_.schedule(phri::ScheduledKortexFault::parse(args.emulate_fault, "--emulate-fault"));
    phri::KortexRobotSettings settings = robot_settings(config, model, args.dry_run);
    settings.wrench_source = [this](phri::RobotState& s) {
      s.wrench_sensor = arm_.plant_state().wrench_sensor;
      s.wrench = arm_.plant_state().wrench;
    };
    robot_ = std::make_unique<phri::KortexRobot>(arm_, settings);
  }
  phri::KortexRobot& kortex_robot() override { return *robot_; }
  phri::PushInput* pushes() override { return &plant_; }
  std::string report() const override {
    const phri::KortexEmulator::Counters& c = arm_.counters();
    return health_line(*robot_) + "; emulator: " + std::to_string(c.commands_applied) + " commands applied, " +
           std::to_string(c.lost_packets) + " packets lost, " + std::to_string(c.stalls) + " stalls, " +
           std::to_string(c.watchdog_trips) + " watchdog trips, " + std::to_string(c.following_errors) + " following errors";
  }

private:
  static const phri::SimRobotConfig& checked_plant(const phri::Config& config) {
    phri::check_plant_matches_controller(config.controller, config.plant);
    return config.plant;
  }

  phri::SimRobot plant_;
  phri::KortexEmulator arm_;
  std::unique_ptr<phri::KortexRobot> robot_;
};

#ifdef PHRI_HAVE_KORTEX_SDK
// The real arm through Kinova's SDK; the wrench from the Bota SensONE when a device is given.
class RealArm final : public KortexBackend {
public:
  RealArm(const KortexArguments& args, const phri::Config& config, const phri::Model& model) {
    phri::KortexSdkSettings sdk;
    sdk.ip = args.ip;
    client_ = std::make_unique<phri::KortexSdkClient>(sdk);
    if (!args.ft_serial.empty()) {
      phri::BotaSensOneSettings ft;
      ft.device = args.ft_serial;
      sensor_ = std::make_unique<phri::BotaSensOne>(ft);
    }
    phri::KortexRobotSettings settings = robot_settings(config, model, args.dry_run);
    if (sensor_) {
      settings.wrench_source = [this](phri::RobotState& s) {
        sensor_->read_into(s);
        s.wrench.stamp_s -= robot_->clock_start_s();  // host steady clock (the SDK client's) -> robot time
      };
    }
    robot_ = std::make_unique<phri::KortexRobot>(*client_, settings);
  }
  phri::KortexRobot& kortex_robot() override { return *robot_; }
  std::string report() const override { return health_line(*robot_); }

private:
  std::unique_ptr<phri::KortexSdkClient> client_;
  std::unique_ptr<phri::BotaSensOne> sensor_;
  std::unique_ptr<phri::KortexRobot> robot_;  // last: stopped first
};
#endif

}  // namespace

void check_kortex_arguments(const KortexArguments& args) {
  const bool kortex = args.backend == "kortex" || args.backend == "kortex-emulator";
  if (!kortex && args.dry_run) throw phri::ConfigError("--dry-run", "", "needs --backend kortex or kortex-emulator");
  if (args.backend != "kortex" && !args.ft_serial.empty()) throw phri::ConfigError("--ft-serial", "", "needs --backend kortex");
  if (!args.emulate_fault.empty()) {
    if (args.backend != "kortex-emulator") throw phri::ConfigError("--emulate-fault", "", "needs --backend kortex-emulator");
    phri::ScheduledKortexFault::parse(args.emulate_fault, "--emulate-fault");  // a bad spec fails before anything starts
  }
#ifndef PHRI_HAVE_KORTEX_SDK
  if (args.backend == "kortex") {
    throw phri::ConfigError("--backend kortex", "",
                            "this phri was built without Kinova's Kortex API: rebuild with cmake -DPHRI_KORTEX_API_DIR=<the "
                            "unpacked SDK folder> (docs/hardware.md), or run --backend kortex-emulator");
  }
#endif
}

std::unique_ptr<KortexBackend> make_kortex_backend(const KortexArguments& args, const phri::Config& config,
                                                   const phri::Model& model) {
  check_kortex_arguments(args);
  if (args.backend == "kortex-emulator") return std::make_unique<EmulatedArm>(config, model, args);
#ifdef PHRI_HAVE_KORTEX_SDK
  if (args.backend == "kortex") return std::make_unique<RealArm>(args, config, model);
#endif
  throw phri::ConfigError("--backend", args.backend, "not a Kortex backend");
}

void register_kortex_backends(phri::BackendRegistry& registry, const KortexArguments& args) {
  registry.add("kortex-emulator", [&args](const phri::BackendRequest& request) -> std::unique_ptr<phri::Backend> {
    return std::make_unique<EmulatedArm>(request.config, request.model, args);
  });
#ifdef PHRI_HAVE_KORTEX_SDK
  registry.add("kortex", [&args](const phri::BackendRequest& request) -> std::unique_ptr<phri::Backend> {
    return std::make_unique<RealArm>(args, request.config, request.model);
  });
#endif
}

int kortex_dry_run(KortexBackend& backend, double duration_s, bool real_time, std::ostream& out) {
  phri::KortexRobot& robot = backend.kortex_robot();
  phri::LoopClock clock(robot.period_s(), real_time ? phri::LoopClock::Pacing::kRealTime : phri::LoopClock::Pacing::kLockstep);
  const long cycles = std::lround(duration_s / robot.period_s());
  double next_print = 0.0;
  g_interrupted = 0;
  std::signal(SIGINT, [](int) { g_interrupted = 1; });  // Ctrl-C ends the dry run through the exit sequence
  for (long k = 0; k < cycles && !g_interrupted; ++k) {
    const phri::RobotState& s = robot.read();
    if (s.time_s >= next_print) {
      next_print += 1.0;
      char line[400];
      int at = std::snprintf(line, sizeof line, "[%6.3f s] q deg:", s.time_s);
      for (int i = 0; i < s.q_rad.size(); ++i) at += std::snprintf(line + at, sizeof line - static_cast<std::size_t>(at), " %7.2f", s.q_rad[i] * 180.0 / M_PI);
      at += std::snprintf(line + at, sizeof line - static_cast<std::size_t>(at), " | tau N.m:");
      for (int i = 0; i < s.tau_sensor_Nm.size(); ++i) at += std::snprintf(line + at, sizeof line - static_cast<std::size_t>(at), " %6.2f", s.tau_sensor_Nm[i]);
      std::snprintf(line + at, sizeof line - static_cast<std::size_t>(at), "%s", s.fault ? " | FAULT" : "");
      out << line << "\n";
    }
    clock.wait_next();
  }
  std::signal(SIGINT, SIG_DFL);
  out << backend.report() << "\n";
  return robot.health().arm_fault || robot.health().link_lost ? 3 : 0;
}

InterruptToStop::InterruptToStop(phri::LiveChannel& live) : live_(live) {
  g_interrupted = 0;
  std::signal(SIGINT, [](int) {
    g_interrupted = 1;
    std::signal(SIGINT, SIG_DFL);  // a second Ctrl-C kills
  });
  watcher_ = std::thread([this] {
    while (!done_.load()) {
      if (g_interrupted) {
        phri::LiveCommand stop;
        stop.kind = phri::LiveCommand::Kind::kEvent;
        stop.event = phri::Event::kStop;
        live_.send(stop);
        std::fprintf(stderr, "\nphri: interrupted: stopping (brake to rest, position hold, then the exit sequence); Ctrl-C again kills\n");
        return;
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
  });
}

InterruptToStop::~InterruptToStop() {
  done_.store(true);
  watcher_.join();
  std::signal(SIGINT, SIG_DFL);
}
