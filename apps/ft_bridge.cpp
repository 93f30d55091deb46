#include "ft_bridge.hpp"

#include <phri/core/error.hpp>
#include <phri/hardware/bota_emulator.hpp>
#include <phri/hardware/bota_sens_one.hpp>

#ifdef PHRI_HAVE_ROS2
#include <phri/config/ros2_settings.hpp>
#include <phri/ros2/wrench_publisher.hpp>
#endif

#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>
#include <thread>

namespace {

volatile std::sig_atomic_t g_ft_bridge_interrupted = 0;

}  // namespace

CLI::App* add_ft_bridge_command(CLI::App& app, FtBridgeArguments& args) {
  auto* bridge = app.add_subcommand("ft-bridge", "Publish the Bota SensONE's wrench on ROS 2 (<namespace>/ft_in) for a "
                                                 "controller on another machine (phri run --ros2 --ros-ft-in)");
  auto* emulate = bridge->add_flag("--emulate", args.emulate, "the fake sensor on a pseudo-terminal (no hardware)");
  bridge->add_option("--device", args.device, "serial device (better /dev/serial/by-id/...)")->capture_default_str()->excludes(emulate);
  bridge->add_option("--duration", args.duration_s, "seconds, 0: until Ctrl-C")->check(CLI::Range(0.0, 86400.0))->capture_default_str();
  bridge->add_option("--ros-domain", args.domain, "ROS 2 domain id (default: ROS_DOMAIN_ID, else 0)")->check(CLI::Range(0, 232));
  bridge->add_option("--ros-namespace", args.topic_namespace, "namespace of the topic")->capture_default_str();
  bridge->add_option("--frame", args.frame_id, "frame_id of the samples (the sensor's frame)")->capture_default_str();
  bridge->add_option("--discovery", args.discovery, "loopback (this machine only, no multicast) or network")
      ->check(CLI::IsMember({"loopback", "network"}))->capture_default_str();
  return bridge;
}

#ifdef PHRI_HAVE_ROS2
namespace {

// The frame's steady-clock read time as wall-clock time (what a ROS 2 stamp is).
std::int64_t wall_stamp_ns(std::int64_t steady_ns) {
  const auto steady_now = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
  const auto wall_now = std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
  return wall_now - (steady_now - steady_ns);
}

}  // namespace

int ft_bridge_command(const FtBridgeArguments& args) {
  phri::Ros2Settings ros;
  ros.domain = args.domain;
  ros.discovery = args.discovery;
  if (!phri::valid_ros_namespace(args.topic_namespace)) {
    throw phri::ConfigError("--ros-namespace", "", "a ROS 2 namespace such as /phri, got '" + args.topic_namespace + "'");
  }
  ros.topic_namespace = args.topic_namespace;
  std::unique_ptr<phri::BotaEmulator> emulator;
  phri::BotaSensOneSettings settings;
  settings.device = args.device;
  settings.decoder.status_error_mask = args.status_mask;
  settings.history_capacity = 4096;  // every sample, not only the newest
  if (args.emulate) {
    emulator = std::make_unique<phri::BotaEmulator>();
    settings.device = emulator->device();
  }
  phri::WrenchPublisher publisher(ros, args.frame_id);
  std::signal(SIGINT, [](int) { g_ft_bridge_interrupted = 1; });
  std::signal(SIGTERM, [](int) { g_ft_bridge_interrupted = 1; });
  std::printf("phri ft-bridge: %s%s -> %s on DDS domain %d (%s discovery) (Ctrl-C ends)\n", settings.device.c_str(),
              args.emulate ? " (the emulated sensor)" : "", publisher.dds_topic().c_str(), publisher.domain(), args.discovery.c_str());
  std::fflush(stdout);
  phri::BotaSensOne sensor(settings);
  const auto start = std::chrono::steady_clock::now();
  auto next_line = start + std::chrono::seconds(1);
  while (g_ft_bridge_interrupted == 0) {
    for (phri::WrenchSample s; sensor.pop_history(s);) {
      if (s.valid) publisher.publish(s.wrench, wall_stamp_ns(s.host_stamp_ns));
    }
    const auto now = std::chrono::steady_clock::now();
    if (now >= next_line) {
      std::printf("phri ft-bridge: %llu samples published, %d subscriber(s)\n", static_cast<unsigned long long>(publisher.published()),
                  publisher.matched());
      std::fflush(stdout);
      next_line += std::chrono::seconds(1);
    }
    if (args.duration_s > 0.0 && std::chrono::duration<double>(now - start).count() >= args.duration_s) break;
    std::this_thread::sleep_for(std::chrono::microseconds(200));
  }
  sensor.stop();
  std::printf("phri ft-bridge: %llu samples published\n", static_cast<unsigned long long>(publisher.published()));
  if (const std::string error = sensor.last_error(); !error.empty()) std::printf("last error: %s\n", error.c_str());
  return publisher.published() > 0 ? 0 : 1;
}
#else
int ft_bridge_command(const FtBridgeArguments&) {
  throw phri::ConfigError("ft-bridge", "", "this phri was built without the ROS 2 bridge: install cyclonedds-dev and "
                                           "cyclonedds-tools (scripts/setup) and configure again (-DPHRI_BUILD_ROS2=ON)");
}
#endif
