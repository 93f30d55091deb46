#pragma once
// `phri ft-bridge --device DEV | --emulate [--ros-domain N] [--ros-namespace NS] [--duration S]`:
// the F/T machine's role (the paper's NUC as EtherCAT/serial master): reads the Bota SensONE (the
// serial driver, hardware/bota_sens_one.hpp) and publishes every sample on <namespace>/ft_in
// (geometry_msgs/WrenchStamped, the sensor's frame, stamped with the time its bytes were read), at
// the sensor's rate. The controller's machine takes it with `phri run ... --ros2 --ros-ft-in`.
#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

struct FtBridgeArguments {
  std::string device = "/dev/ttyUSB0";
  bool emulate = false;
  double duration_s = 0.0;  ///< 0: until Ctrl-C
  int domain = -1;          ///< -1: ROS_DOMAIN_ID, else 0
  std::string topic_namespace = "/phri";
  std::string frame_id = "ft_sensor";
  std::string discovery = "network";
  std::uint16_t status_mask = 0xFFFF;
};

CLI::App* add_ft_bridge_command(CLI::App& app, FtBridgeArguments& args);
int ft_bridge_command(const FtBridgeArguments& args);
