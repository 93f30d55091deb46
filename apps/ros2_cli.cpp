#include "ros2_cli.hpp"

#include <phri/core/error.hpp>

#ifdef PHRI_HAVE_ROS2
#include <phri/ros2/dds_config.hpp>
#include <phri/ros2/ros2_bridge.hpp>
#endif

#include <ostream>

void add_ros2_options(CLI::App& run, Ros2Arguments& args) {
  auto* ros2 = run.add_flag("--ros2", args.enabled,
                            "publish the run on ROS 2 topics and take /phri/target_pose and /phri/event (DDS, no ROS "
                            "install needed; docs/ros2.md)");
  run.add_option("--ros-domain", args.domain, "ROS 2 domain id (default: the configuration's, else ROS_DOMAIN_ID, else 0)")
      ->check(CLI::Range(0, 232))->needs(ros2);
  run.add_option("--ros-namespace", args.topic_namespace, "namespace of phri's own topics (default /phri)")->needs(ros2);
}

void apply_ros2_arguments(const Ros2Arguments& args, phri::Ros2Settings& settings) {
  if (args.enabled) settings.enabled = true;
  if (args.domain >= 0) settings.domain = args.domain;
  if (!args.topic_namespace.empty()) {
    if (!phri::valid_ros_namespace(args.topic_namespace)) {
      throw phri::ConfigError("--ros-namespace", "", "a ROS 2 namespace such as /phri ('/' then [A-Za-z0-9_] segments), got '" +
                                                     args.topic_namespace + "'");
    }
    settings.topic_namespace = args.topic_namespace;
  }
}

#ifdef PHRI_HAVE_ROS2
struct Ros2Run::Impl {
  phri::Ros2Bridge bridge;
  Impl(const phri::Ros2Settings& s, const phri::Controller& cycle) : bridge(s, cycle.model(), cycle.end_effector_frame()) {}
};

Ros2Run::Ros2Run(const phri::Ros2Settings& settings, const phri::Controller& cycle, phri::RunOptions& options, std::ostream& out)
    : impl_(std::make_unique<Impl>(settings, cycle)) {
  out << "phri ros2: DDS domain " << impl_->bridge.domain() << ", " << settings.discovery << " discovery, /joint_states every "
      << settings.joint_states_decimation << " cycles, the rest every " << settings.decimation << "\n";
  for (const std::string& topic : impl_->bridge.wire_topics()) out << "  " << topic << "\n";
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
      << " events accepted, " << s.refused_total() << " refused";
  for (int r = 1; r < phri::kInputRefusalCount; ++r) {
    if (s.refused[static_cast<std::size_t>(r)] > 0) {
      out << " " << phri::to_string(static_cast<phri::InputRefusal>(r)) << "=" << s.refused[static_cast<std::size_t>(r)];
    }
  }
  out << "\n";
}
#else
struct Ros2Run::Impl {};

Ros2Run::Ros2Run(const phri::Ros2Settings&, const phri::Controller&, phri::RunOptions&, std::ostream&) {
  throw phri::ConfigError("--ros2", "", "this phri was built without the ROS 2 bridge: install cyclonedds-dev and "
                                        "cyclonedds-tools (scripts/setup) and configure again (-DPHRI_BUILD_ROS2=ON)");
}

void Ros2Run::finish(std::ostream&) {}
#endif

Ros2Run::~Ros2Run() = default;
