#pragma once
// `phri run --backend kortex | kortex-emulator`: the Kinova Gen3 through the Kortex low-level
// backend (phri::KortexRobot), on the real arm (Kinova's SDK, only when built with
// -DPHRI_KORTEX_API_DIR) or on the in-process emulator over the simulated plant; with
// --ft-serial, the Bota SensONE's wrench; with --dry-run, only reading (no torque ever sent).
#include <phri/config/config.hpp>
#include <phri/app/backend_registry.hpp>
#include <phri/app/live_channel.hpp>
#include <phri/hardware/kortex_robot.hpp>
#include <phri/model/model.hpp>
#include <phri/robot/robot_interface.hpp>

#include <atomic>
#include <iosfwd>
#include <memory>
#include <string>
#include <thread>

struct KortexArguments {
  std::string backend = "sim";  ///< sim | kortex | kortex-emulator
  std::string ip = "192.168.1.10";
  std::string ft_serial;        ///< Bota SensONE device; empty: no F/T sensor on the real arm
  bool dry_run = false;
  std::string emulate_fault;    ///< kortex-emulator: a scheduled link fault (ScheduledKortexFault::parse)
};

/// The arm of a run with its link and sensors, kept alive together; robot() is what the loop drives.
class KortexBackend : public phri::Backend {
public:
  phri::RobotInterface& robot() override { return kortex_robot(); }
  virtual phri::KortexRobot& kortex_robot() = 0;
  bool brake_on_interrupt() const override { return true; }
};

/// Refuses a kortex option without a kortex backend, and --backend kortex without the SDK (one
/// line saying how to build it).
void check_kortex_arguments(const KortexArguments& args);
/// Registers "kortex-emulator" and, when built with Kinova's SDK, "kortex"; `args` must outlive
/// the registry (its factories read it).
void register_kortex_backends(phri::BackendRegistry& registry, const KortexArguments& args);
/// Connects and starts the arm (throws HardwareError with one line when it cannot).
std::unique_ptr<KortexBackend> make_kortex_backend(const KortexArguments& args, const phri::Config& config,
                                                   const phri::Model& model);
/// --dry-run: reads the arm for `duration_s` (paced at its period on the real arm), printing the
/// state once a second; sends nothing but the measured pose in POSITION. Returns the exit status.
int kortex_dry_run(KortexBackend& backend, double duration_s, bool real_time, std::ostream& out);

/// On the arm, Ctrl-C must not just kill the program: while this lives, the first SIGINT posts
/// the FSM's stop through `live` (brake to rest, hold; the run then ends and the exit sequence
/// puts the actuators in POSITION and the arm in single-level servoing); a second one kills as usual.
class InterruptToStop {
public:
  explicit InterruptToStop(phri::LiveChannel& live);
  ~InterruptToStop();
  InterruptToStop(const InterruptToStop&) = delete;
  InterruptToStop& operator=(const InterruptToStop&) = delete;

private:
  phri::LiveChannel& live_;
  std::atomic<bool> done_{false};
  std::thread watcher_;
};
