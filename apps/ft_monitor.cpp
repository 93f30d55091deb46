#include "ft_monitor.hpp"

#include "exit_status.hpp"

#include <phri/hardware/bota_emulator.hpp>
#include <phri/hardware/bota_sens_one.hpp>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <memory>
#include <string>
#include <utility>
#include <thread>

namespace {

volatile std::sig_atomic_t g_interrupted = 0;

void print_reading(double t_s, phri::BotaSensOne& sensor) {
  const phri::WrenchSample s = sensor.latest();
  const std::int64_t now_ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(phri::BotaSensOne::Clock::now().time_since_epoch()).count();
  const phri::BotaSensOneCounters c = sensor.counters();
  const auto& d = c.decoder;
  std::printf("%7.2f s  F [%8.3f %8.3f %8.3f] N  M [%7.4f %7.4f %7.4f] N.m  %5.1f C  status 0x%04x  ", t_s,
              s.wrench[0], s.wrench[1], s.wrench[2], s.wrench[3], s.wrench[4], s.wrench[5],
              static_cast<double>(s.temperature), static_cast<unsigned>(s.status));
  if (!s.connected) {
    std::printf("disconnected");
  } else if (!s.valid) {
    std::printf("no data yet");
  } else {
    std::printf("age %5.1f ms  seq %u", 1e3 * s.age_s(now_ns), s.sequence);
  }
  std::printf("  | ok %llu crc %llu status %llu invalid %llu skipped %llu\n",
              static_cast<unsigned long long>(d.frames_ok), static_cast<unsigned long long>(d.crc_errors),
              static_cast<unsigned long long>(d.status_errors), static_cast<unsigned long long>(d.invalid_values),
              static_cast<unsigned long long>(d.bytes_skipped));
  std::fflush(stdout);
}

void print_summary(const phri::BotaSensOne& sensor) {
  const phri::BotaSensOneCounters c = sensor.counters();
  const auto& d = c.decoder;
  std::printf("phri ft-monitor: frames ok %llu, crc errors %llu, status errors %llu, invalid values %llu, "
              "unconfirmed %llu, resyncs %llu, bytes skipped %llu of %llu; connections %llu, disconnections %llu, "
              "open failures %llu, handshake failures %llu\n",
              static_cast<unsigned long long>(d.frames_ok), static_cast<unsigned long long>(d.crc_errors),
              static_cast<unsigned long long>(d.status_errors), static_cast<unsigned long long>(d.invalid_values),
              static_cast<unsigned long long>(d.unconfirmed), static_cast<unsigned long long>(d.resyncs),
              static_cast<unsigned long long>(d.bytes_skipped), static_cast<unsigned long long>(d.bytes),
              static_cast<unsigned long long>(c.connections), static_cast<unsigned long long>(c.disconnections),
              static_cast<unsigned long long>(c.open_failures), static_cast<unsigned long long>(c.handshake_failures));
  if (const std::string error = sensor.last_error(); !error.empty()) std::printf("last error: %s\n", error.c_str());
}

}  // namespace

CLI::App* add_ft_monitor_command(CLI::App& app, FtMonitorArguments& args) {
  auto* monitor = app.add_subcommand("ft-monitor", "Print the Bota SensONE's wrench and the driver's counters");
  auto* emulate = monitor->add_flag("--emulate", args.emulate, "monitor a fake sensor on a pseudo-terminal (no hardware)");
  monitor->add_option("--device", args.device, "serial device (better /dev/serial/by-id/...)")
      ->capture_default_str()
      ->excludes(emulate);  // the emulator makes its own device
  monitor->add_option("--duration", args.duration_s, "seconds, 0: until Ctrl-C")->check(CLI::Range(0.0, 86400.0))
      ->capture_default_str();
  monitor->add_option("--print-hz", args.print_hz, "lines per second")->check(CLI::Range(0.1, 100.0))->capture_default_str();
  monitor->add_option("--status-mask", args.status_mask, "status bits that reject a frame (e.g. 0xFFFF: any)")
      ->capture_default_str();
  return monitor;
}

int ft_monitor_command(const FtMonitorArguments& args) {
  std::unique_ptr<phri::BotaEmulator> emulator;
  phri::BotaSensOneSettings settings;
  settings.device = args.device;
  settings.decoder.status_error_mask = args.status_mask;
  if (args.emulate) {
    emulator = std::make_unique<phri::BotaEmulator>();
    settings.device = emulator->device();
  }
  std::signal(SIGINT, [](int) { g_interrupted = 1; });
  std::printf("phri ft-monitor: %s at %d baud%s (Ctrl-C ends)\n", settings.device.c_str(), phri::kBotaBaudRate,
              args.emulate ? ", the emulated sensor" : "");
  phri::BotaSensOne sensor(settings);
  const auto start = phri::BotaSensOne::Clock::now();
  const auto period = std::chrono::duration<double>(1.0 / args.print_hz);
  std::string shown_error;
  for (auto next = start + period; g_interrupted == 0; next += std::chrono::duration_cast<phri::BotaSensOne::Clock::duration>(period)) {
    std::this_thread::sleep_until(next);
    const double t_s = std::chrono::duration<double>(phri::BotaSensOne::Clock::now() - start).count();
    print_reading(t_s, sensor);
    if (std::string error = sensor.last_error(); error != shown_error) {  // each new error once
      if (!error.empty()) std::printf("phri ft-monitor: %s\n", error.c_str());
      shown_error = std::move(error);
    }
    if (args.duration_s > 0.0 && t_s >= args.duration_s) break;
  }
  sensor.stop();
  print_summary(sensor);
  // A monitor that never heard the sensor has not monitored it: say so in the exit status too.
  if (sensor.counters().decoder.frames_ok == 0) {
    std::printf("phri ft-monitor: no valid frame from %s\n", settings.device.c_str());
    return phri::cli::kChecksFailed;
  }
  return phri::cli::kOk;
}
