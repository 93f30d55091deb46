#pragma once
// phri::BackendRegistry: the robots a run can drive, by name (`phri run --backend NAME`). Each
// backend registers a factory that builds its robot from the run's configuration (config.plant
// is the robot's description plus the simulator's settings) and the controller's model; the run
// then drives Backend::robot() through the robot interface alone, and hands Backend::pushes() to
// the loop (RunOptions::pushes).
//
//   phri::BackendRegistry backends;
//   phri::register_sim_backend(backends);            // "sim" (app/sim_backend.hpp)
//   register_kortex_backends(backends, arguments);   // "kortex", "kortex-emulator" (apps/)
//   std::unique_ptr<phri::Backend> backend = backends.make(name, {config, cycle.model()});
//
// An unknown name is one phri::ConfigError naming it and the known ones.
#include <phri/config/config.hpp>
#include <phri/model/model.hpp>
#include <phri/robot/ground_truth.hpp>
#include <phri/robot/push_input.hpp>
#include <phri/robot/robot_interface.hpp>

#include <functional>
#include <map>
#include <memory>
#include <string>
#include <vector>

namespace phri {

/// A robot of a run with what keeps it alive (a plant, a link, sensors).
class Backend {
public:
  virtual ~Backend() = default;
  virtual RobotInterface& robot() = 0;
  /// Where the live front end's pushes go (a simulated arm), or null.
  virtual PushInput* pushes() { return nullptr; }
  /// The plant's true state for the run's error measurements (a simulated arm), or null.
  virtual const GroundTruth* ground_truth() const { return nullptr; }
  /// Ctrl-C must brake the arm to rest through the FSM before the run ends (an arm behind a link).
  virtual bool brake_on_interrupt() const { return false; }
  /// One line on the link and the arm after the run; '' when there is nothing to say.
  virtual std::string report() const { return ""; }
};

struct BackendRequest {
  const Config& config;
  const Model& model;  ///< the controller's
};

using BackendFactory = std::function<std::unique_ptr<Backend>(const BackendRequest&)>;

class BackendRegistry {
public:
  /// Registers (or replaces) the backend `name`.
  void add(const std::string& name, BackendFactory factory);
  bool has(const std::string& name) const { return factories_.count(name) > 0; }
  /// The names, sorted.
  std::vector<std::string> names() const;
  /// Refuses an unknown name: ConfigError("--backend", name, "unknown backend (known: ...)").
  void require(const std::string& name) const;
  /// Builds the backend `name` (an unknown name refused as by require()); the factory's own errors pass through.
  std::unique_ptr<Backend> make(const std::string& name, const BackendRequest& request) const;

private:
  std::map<std::string, BackendFactory> factories_;
};

}  // namespace phri
