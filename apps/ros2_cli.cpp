#include "ros2_cli.hpp"

#include <phri/core/error.hpp>

#ifdef PHRI_HAVE_ROS2
#include <phri/ros2/dds_config.hpp>
#include <phri/ros2/ft_in_robot.hpp>
#include <phri/ros2/ros2_bridge.hpp>
#include <phri/ros2/ros2_load.hpp>
#endif

#include <algorithm>
#include <filesystem>
#include <iostream>
#include <ostream>
#include <vector>

void add_ros2_options(CLI::App& run, Ros2Arguments& args) {
  auto* ros2 = run.add_flag("--ros2", args.enabled,
                            "publish the run on ROS 2 topics and take /phri/target_pose and /phri/event (DDS, no ROS "
                            "install needed; docs/ros2.md)");
  run.add_option("--ros-domain", args.domain, "ROS 2 domain id (default: the configuration's, else ROS_DOMAIN_ID, else 0)")
      ->check(CLI::Range(0, 232))->needs(ros2);
  run.add_option("--ros-namespace", args.topic_namespace, "namespace of phri's own topics (default /phri)")->needs(ros2);
  run.add_option("--ros-discovery", args.discovery, "loopback (this machine, unicast, no multicast) or network (Cyclone's "
                 "defaults, or the file CYCLONEDDS_URI names; docs/ros2.md); default: the configuration's, else loopback")
      ->check(CLI::IsMember({"loopback", "network"}))->needs(ros2);
  run.add_flag("--ros-ft-in", args.ft_in, "the F/T sensor from <namespace>/ft_in (another machine's `phri ft-bridge`), "
               "checked like the arm's own; needs --realtime")->needs(ros2);
}

Ros2Commands::Ros2Commands(CLI::App& app, CLI::App& experiment)
    : ft_bridge_(add_ft_bridge_command(app, ft_bridge_args_)), load_(add_ros2_load_command(experiment, load_args_)) {}

void apply_ros2_arguments(const Ros2Arguments& args, phri::Ros2Settings& settings, bool lockstep) {
  if (args.enabled) settings.enabled = true;
  if (args.domain >= 0) settings.domain = args.domain;
  if (args.ft_in) settings.ft_in = true;
  if (!args.discovery.empty()) settings.discovery = args.discovery;
  if (!args.topic_namespace.empty()) {
    if (!phri::valid_ros_namespace(args.topic_namespace)) {
      throw phri::ConfigError("--ros-namespace", "", "a ROS 2 namespace such as /phri ('/' then [A-Za-z0-9_] segments), got '" +
                                                     args.topic_namespace + "'");
    }
    settings.topic_namespace = args.topic_namespace;
  }
  if (settings.enabled && settings.ft_in && lockstep) {
    throw phri::ConfigError("ros2.ft_in", "", "the F/T sensor from " + settings.topic_namespace + "/ft_in needs real-time "
                                              "pacing (--realtime): in lockstep robot time outruns its samples");
  }
}

CLI::App* add_ros2_load_command(CLI::App& experiment, Ros2LoadArguments& args) {
  auto* load = experiment.add_subcommand("ros2-load", "The loop's p99.9 cycle time without and with the ROS 2 bridge (same run), "
                                                      "and the age of remote F/T samples at the cycle");
  load->add_option("--config", args.config_path, "run configuration")->check(CLI::ExistingFile)->capture_default_str();
  load->add_option("--segment-s", args.segment_s, "robot time of each segment [s]")->check(CLI::Range(2.0, 600.0))->capture_default_str();
  load->add_option("--repeats", args.repeats, "segment pairs (without, with), interleaved")->check(CLI::Range(1, 50))->capture_default_str();
  load->add_option("--ros-domain", args.domain, "DDS domain of the measurement")->check(CLI::Range(0, 232))->capture_default_str();
  load->add_flag("!--no-ft", args.ft, "without the F/T peer (phri ft-bridge --emulate)");
  return load;
}

#ifdef PHRI_HAVE_ROS2
int ros2_load_command(const Ros2LoadArguments& args) {
  phri::Ros2LoadOptions o;
  o.config_path = args.config_path;
  o.segment_s = args.segment_s;
  o.repeats = args.repeats;
  o.domain = args.domain;
  if (args.ft) {
    std::error_code ec;
    o.phri_program = std::filesystem::read_symlink("/proc/self/exe", ec).string();
  }
  return phri::run_ros2_load_command(o, std::cout);
}

struct Ros2Run::Impl {
  phri::Ros2Bridge bridge;
  std::unique_ptr<phri::FtInRobot> ft_robot;
  Impl(const phri::Ros2Settings& s, const phri::Controller& cycle) : bridge(s, cycle.model(), cycle.end_effector_frame()) {}
};

phri::RobotInterface& Ros2Run::robot(phri::RobotInterface& robot) {
  if (!impl_->bridge.settings().ft_in) return robot;
  impl_->ft_robot = std::make_unique<phri::FtInRobot>(robot, impl_->bridge.ft_in());
  return *impl_->ft_robot;
}

namespace {

// The F/T round trip: a sample's age when the cycle first read it (bridge take -> controller).
void print_ft_ages(const phri::FtInRobot& robot, std::ostream& out) {
  std::vector<double> ages = robot.ages_s();
  out << "ros2 ft_in: " << robot.samples_seen() << " new samples read by the cycle";
  if (ages.empty()) {
    out << "\n";
    return;
  }
  std::sort(ages.begin(), ages.end());
  const auto at = [&](double p) { return 1e3 * ages[static_cast<std::size_t>(p * static_cast<double>(ages.size() - 1))]; };
  out << "; age at the cycle p50 " << at(0.5) << " ms, p99 " << at(0.99) << " ms, max " << 1e3 * ages.back() << " ms\n";
}

}  // namespace

Ros2Run::Ros2Run(const phri::Ros2Settings& settings, const phri::Controller& cycle, phri::RunOptions& options, std::ostream& out)
    : impl_(std::make_unique<Impl>(settings, cycle)) {
  out << "phri ros2: DDS domain " << impl_->bridge.domain() << ", " << settings.discovery << " discovery, /joint_states every "
      << settings.joint_states_decimation << " cycles, the rest every " << settings.decimation << "\n";
  for (const std::string& topic : impl_->bridge.wire_topics()) out << "  " << topic << "\n";
  if (settings.subscribe) {
    out << "phri ros2: targets within " << impl_->bridge.input_limits().max_reach_m << " m of the base, inputs at most "
        << settings.max_input_rate_hz << " per second and topic\n";
  }
  options.observers.push_back(&impl_->bridge.observer());
  if (settings.subscribe) options.inputs.push_back(&impl_->bridge.input());
  impl_->bridge.start();
}

void Ros2Run::finish(std::ostream& out) {
  impl_->bridge.stop();
  const phri::Ros2BridgeStats s = impl_->bridge.stats();
  out << "ros2: " << s.snapshots << " snapshots (" << s.snapshots_dropped << " dropped); published joint_states "
      << s.published[0] << ", status " << s.published[static_cast<std::size_t>(phri::Ros2Topic::kStatus)] << ", tf "
      << s.published[static_cast<std::size_t>(phri::Ros2Topic::kTf)] << "; inputs: " << s.targets << " targets, " << s.events
      << " events, " << s.wrenches << " wrenches accepted, " << s.refused_total() << " refused";
  for (int r = 1; r < phri::kInputRefusalCount; ++r) {
    if (s.refused[static_cast<std::size_t>(r)] > 0) {
      out << " " << phri::to_string(static_cast<phri::InputRefusal>(r)) << "=" << s.refused[static_cast<std::size_t>(r)];
    }
  }
  out << "\n";
  if (impl_->ft_robot) print_ft_ages(*impl_->ft_robot, out);
}
#else
struct Ros2Run::Impl {};

Ros2Run::Ros2Run(const phri::Ros2Settings&, const phri::Controller&, phri::RunOptions&, std::ostream&) {
  throw phri::ConfigError("--ros2", "", "this phri was built without the ROS 2 bridge: install cyclonedds-dev and "
                                        "cyclonedds-tools (scripts/setup) and configure again (-DPHRI_BUILD_ROS2=ON)");
}

phri::RobotInterface& Ros2Run::robot(phri::RobotInterface& robot) { return robot; }
void Ros2Run::finish(std::ostream&) {}

int ros2_load_command(const Ros2LoadArguments&) {
  throw phri::ConfigError("experiment ros2-load", "", "this phri was built without the ROS 2 bridge (-DPHRI_BUILD_ROS2=ON)");
}
#endif

Ros2Run::~Ros2Run() = default;
