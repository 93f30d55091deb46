#pragma once
// `phri run --ros2 [--ros-domain N] [--ros-namespace NS]`: the ROS 2 bridge (src/phri/ros2/,
// docs/ros2.md) as one observer and one input of the run, when phri is built with it
// (PHRI_BUILD_ROS2, on when Cyclone DDS is found).
#include <phri/app/run_session.hpp>
#include <phri/config/ros2_settings.hpp>
#include <phri/control/controller.hpp>
#include <phri/robot/robot_interface.hpp>

#include "ft_bridge.hpp"

#include <CLI/CLI.hpp>

#include <iosfwd>
#include <memory>
#include <string>

struct Ros2Arguments {
  bool enabled = false;
  int domain = -1;              ///< -1: the configuration's (else ROS_DOMAIN_ID, else 0)
  std::string topic_namespace;  ///< empty: the configuration's
  bool ft_in = false;           ///< the F/T sensor from <namespace>/ft_in
  std::string discovery;        ///< loopback | network; empty: the configuration's
};

void add_ros2_options(CLI::App& run, Ros2Arguments& args);
/// The command line over the run YAML's `ros2:` (phri::ConfigError: a bad namespace, or the F/T
/// from /ft_in in a `lockstep` run, whose robot time outruns the samples).
void apply_ros2_arguments(const Ros2Arguments& args, phri::Ros2Settings& settings, bool lockstep);

/// `phri experiment ros2-load` (phri/ros2/ros2_load.hpp).
struct Ros2LoadArguments {
  std::string config_path = "configs/dashboard.yaml";
  double segment_s = 5.0;
  int repeats = 3;
  int domain = 47;
  bool ft = true;
};
CLI::App* add_ros2_load_command(CLI::App& experiment, Ros2LoadArguments& args);
int ros2_load_command(const Ros2LoadArguments& args);

/// The ROS 2 commands besides `run --ros2`: `phri ft-bridge` and `phri experiment ros2-load`.
class Ros2Commands {
public:
  Ros2Commands(CLI::App& app, CLI::App& experiment);
  bool parsed() const { return ft_bridge_->parsed() || load_->parsed(); }
  int run() const { return ft_bridge_->parsed() ? ft_bridge_command(ft_bridge_args_) : ros2_load_command(load_args_); }

private:
  FtBridgeArguments ft_bridge_args_;
  Ros2LoadArguments load_args_;
  CLI::App* ft_bridge_ = nullptr;
  CLI::App* load_ = nullptr;
};

/// The bridge of one run: started here (its topics printed), its observer and input added to
/// `options`; finish() stops it and prints what it published and refused.
class Ros2Run {
public:
  /// A started bridge when settings.enabled, else null.
  static std::unique_ptr<Ros2Run> start_if_enabled(const phri::Ros2Settings& settings, const phri::Controller& cycle,
                                                   phri::RunOptions& options, std::ostream& out) {
    return settings.enabled ? std::make_unique<Ros2Run>(settings, cycle, options, out) : nullptr;
  }
  Ros2Run(const phri::Ros2Settings& settings, const phri::Controller& cycle, phri::RunOptions& options, std::ostream& out);
  ~Ros2Run();
  Ros2Run(const Ros2Run&) = delete;
  Ros2Run& operator=(const Ros2Run&) = delete;
  /// The robot the loop drives: `robot` itself, or with --ros-ft-in its state's F/T wrench from
  /// /phri/ft_in (phri::FtInRobot). Valid while this lives.
  phri::RobotInterface& robot(phri::RobotInterface& robot);
  void finish(std::ostream& out);

private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};
