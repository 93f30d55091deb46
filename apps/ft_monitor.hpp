#pragma once
// `phri ft-monitor`: the Bota SensONE's wrench and the driver's counters, printed a few times a
// second (the sensor on a serial device, or --emulate: the fake sensor on a pseudo-terminal).
#include <CLI/CLI.hpp>

#include <cstdint>
#include <string>

struct FtMonitorArguments {
  std::string device = "/dev/ttyUSB0";
  bool emulate = false;
  double duration_s = 0.0;  ///< 0: until Ctrl-C
  double print_hz = 4.0;
  std::uint16_t status_mask = 0xFFFF;
};

CLI::App* add_ft_monitor_command(CLI::App& app, FtMonitorArguments& args);
int ft_monitor_command(const FtMonitorArguments& args);
