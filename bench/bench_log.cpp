// The log writer's work off the control thread: 20,000 rows of the controller benchmarks' closed
// loop (pushed_gen3.hpp; dual compliance: rows as a real run logs them, recorded once before
// timing) written as CSV text (Logger::csv_line, one fwrite per MiB) or as the MCAP log
// (McapLogWriter: CDR encoding, zstd chunks, indexes, summary). Reports rows per second of writer
// time and bytes per row of the file:
//   build/release/bench/phri_bench --benchmark_filter=LogWriter
#include <phri/app/fill_log_row.hpp>
#include <phri/app/logger.hpp>
#include <phri/app/mcap_log.hpp>
#include <phri/config/robot_bundle.hpp>
#include <phri/control/controller.hpp>
#include <phri/sim/sim_robot.hpp>

#include "pushed_gen3.hpp"

#include <benchmark/benchmark.h>

#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

namespace {

const std::vector<phri::LogRow>& recorded_rows() {
  static const std::vector<phri::LogRow> rows = [] {
    const std::string root = PHRI_SOURCE_DIR;
    constexpr int kRows = 20000;
    const phri::SimRobotConfig plant = pushed_gen3_plant(kRows * 1e-3);
    phri::SimRobot robot(plant);
    phri::ControllerSettings settings;
    phri::RobotBundle::from_folder(root + "/robots/kinova_gen3").apply_to(settings);
    settings.initial_compliance = phri::ComplianceMode::kDual;
    phri::Controller cycle(settings);
    phri::RobotCommand command(robot.dof());
    std::vector<phri::LogRow> out(kRows);
    for (phri::LogRow& row : out) {
      const phri::RobotState& s = robot.read();
      cycle.step(s, command);
      phri::fill_log_row(row, s, cycle);
      robot.write(command);
    }
    return out;
  }();
  return rows;
}

void LogWriter(benchmark::State& state) {
  const bool mcap = state.range(0) == 1;
  const std::vector<phri::LogRow>& rows = recorded_rows();
  const std::string path = (std::filesystem::temp_directory_path() / (mcap ? "phri_bench_log.mcap" : "phri_bench_log.csv")).string();
  phri::LoggerSettings settings;
  settings.path = path;
  settings.joint_names = {"joint_1", "joint_2", "joint_3", "joint_4", "joint_5", "joint_6", "joint_7"};
  settings.has_ft_sensor = true;
  std::uintmax_t bytes = 0;
  for (auto _ : state) {
    if (mcap) {
      phri::McapLogWriter writer(settings);
      for (const phri::LogRow& row : rows) writer.write(row);
      writer.close();
    } else {
      std::FILE* file = std::fopen(path.c_str(), "wb");
      std::vector<char> buffer(1 << 20);
      std::size_t used = 0;
      for (const phri::LogRow& row : rows) {
        if (buffer.size() - used < phri::Logger::kMaxCsvLineBytes) {
          std::fwrite(buffer.data(), 1, used, file);
          used = 0;
        }
        char* end = phri::Logger::csv_line(row, settings.dof, buffer.data() + used, buffer.data() + buffer.size());
        *end++ = '\n';
        used = static_cast<std::size_t>(end - buffer.data());
      }
      std::fwrite(buffer.data(), 1, used, file);
      std::fclose(file);
    }
    bytes = std::filesystem::file_size(path);
  }
  std::filesystem::remove(path);
  state.counters["rows_per_s"] = benchmark::Counter(static_cast<double>(rows.size()) * static_cast<double>(state.iterations()),
                                                    benchmark::Counter::kIsRate);
  state.counters["bytes_per_row"] = static_cast<double>(bytes) / static_cast<double>(rows.size());
}
BENCHMARK(LogWriter)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->MinTime(2.0);

}  // namespace
