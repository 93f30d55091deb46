// ctest-labels: unit
// phri::Logger and phri::SpscRing: every row pushed reaches the CSV intact and in order while the
// writer thread drains concurrently; push never allocates; a full ring drops (and counts) instead
// of blocking; the header is a list of unique, plain column names that pandas and PlotJuggler
// accept, and every row has as many fields.
#include <phri/config/log_row.hpp>
#include <phri/app/logger.hpp>
#include <phri/core/spsc_ring.hpp>
#include <phri/core/error.hpp>

#include "allocation_counter.hpp"
#include "config_error.hpp"

#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <charconv>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <unistd.h>
#include <vector>

namespace {

std::string temp_path(const std::string& name) { return phri::test::temp_path("phri_test_logger", name); }


std::vector<std::string> split(const std::string& line) {
  std::vector<std::string> out;
  std::string field;
  std::stringstream s(line);
  while (std::getline(s, field, ',')) out.push_back(field);
  if (!line.empty() && line.back() == ',') out.emplace_back();
  return out;
}

double to_double(const std::string& text) {
  double v = 0.0;
  const auto result = std::from_chars(text.data(), text.data() + text.size(), v);
  EXPECT_EQ(result.ec, std::errc()) << text;
  EXPECT_EQ(result.ptr, text.data() + text.size()) << text;
  return v;
}

// A row whose every column is a distinct function of k, so a lost, repeated, reordered or torn row
// shows up when read back.
phri::LogRow make_row(long k) {
  phri::LogRow r;
  r.time_s = static_cast<double>(k) * 1e-3;
  r.cycle = k;
  for (int i = 0; i < phri::kLogMaxJoints; ++i) {
    r.q[static_cast<std::size_t>(i)] = static_cast<double>(k) + 0.1 * i;
    r.tau_d[static_cast<std::size_t>(i)] = -0.5 * static_cast<double>(k) + i;
    r.current[static_cast<std::size_t>(i)] = 1.0 / (static_cast<double>(k) + 1.0 + i);
  }
  r.ee_position = {0.75, static_cast<double>(k) * 1e-6, 0.4};
  r.wrench_norm = static_cast<double>(k % 97);
  r.compliance_mode = static_cast<std::int32_t>(k % 4);
  r.event = static_cast<std::int32_t>(k % 17) - 1;
  r.cycle_time_s = 1e-6 * static_cast<double>(k % 1000);
  return r;
}

struct Csv {
  std::vector<std::string> header;
  std::vector<std::vector<std::string>> rows;
  int column(const std::string& name) const {
    for (std::size_t i = 0; i < header.size(); ++i) {
      if (header[i] == name) return static_cast<int>(i);
    }
    ADD_FAILURE() << "no column " << name;
    return 0;
  }
};

Csv read_csv(const std::string& path) {
  std::ifstream in(path);
  Csv csv;
  std::string line;
  std::getline(in, line);
  csv.header = split(line);
  while (std::getline(in, line)) csv.rows.push_back(split(line));
  return csv;
}

TEST(SpscRing, FifoAcrossThreads) {
  phri::SpscRing<long> ring(1000);
  EXPECT_EQ(ring.capacity(), 1024u);
  constexpr long kCount = 2'000'000;
  std::thread consumer([&] {
    long expected = 0, value = 0;
    while (expected < kCount) {
      if (ring.try_pop(value)) {
        ASSERT_EQ(value, expected);
        ++expected;
      }
    }
  });
  for (long k = 0; k < kCount; ++k) {
    while (!ring.try_push(k)) std::this_thread::yield();
  }
  consumer.join();
  EXPECT_EQ(ring.size_approx(), 0u);
}

TEST(Logger, HeaderNamesEveryColumnOnce) {
  const std::string header = phri::Logger::header(7);
  const auto names = split(header);
  std::set<std::string> unique(names.begin(), names.end());
  EXPECT_EQ(unique.size(), names.size()) << header;
  EXPECT_EQ(names.front(), "time_s");
  for (const std::string& n : names) {
    ASSERT_FALSE(n.empty());
    for (char c : n) EXPECT_TRUE((c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_') << n;
    EXPECT_FALSE(n[0] >= '0' && n[0] <= '9') << n;
  }
  for (const char* expected : {"q_1", "q_7", "qd_7", "tau_d_1", "tau_s_4", "tau_ext_7", "current_1", "ee_qw",
                               "target_z", "err_pos_m", "err_ori_rad", "ee_vy", "target_vz", "wrench_fx", "wrench_norm", "compliance_mode",
                               "touched", "low_level_loop", "event", "cycle_status", "qp_status", "cycle_time_s"}) {
    EXPECT_EQ(unique.count(expected), 1u) << expected;
  }
  EXPECT_EQ(unique.count("q_8"), 0u);
  EXPECT_EQ(split(phri::Logger::header(6)).size(), names.size() - 7 * 1);  // 7 groups of joints
  std::printf("header: %zu columns for 7 joints\n", names.size());
}

TEST(Logger, LegendNamesTheCodes) {
  const std::string legend = phri::Logger::legend_yaml();
  for (const char* expected : {"compliance_mode:", "1: null_space", "low_level_loop:", "3: custom", "event:",
                               "-1: none", "3: dual_compliance", "cycle_status:", "qp_status:"}) {
    EXPECT_NE(legend.find(expected), std::string::npos) << expected;
  }
  EXPECT_EQ(phri::Logger::legend_path_for("a/run.csv"), "a/run.legend.yaml");
  EXPECT_EQ(phri::Logger::legend_path_for("run.log"), "run.log.legend.yaml");
}

TEST(Logger, PushDoesNotAllocate) {
  phri::LoggerSettings settings;
  settings.path = temp_path("alloc.csv");
  phri::Logger logger(settings);
  const phri::LogRow row = make_row(3);
  std::size_t allocations = 0;
  {
    phri::test::NoMallocScope no_malloc;
    phri::test::AllocationCounter count;
    for (int k = 0; k < 5000; ++k) logger.push(row);
    allocations = count.allocations();
  }
  EXPECT_EQ(allocations, 0u);
  const phri::LoggerStats stats = logger.close();
  EXPECT_EQ(stats.written, 5000u);
  EXPECT_EQ(stats.dropped, 0u);
}

// 60 s of a 1 kHz run, 60,000 rows, pushed as fast as the writer takes them: the producer only
// waits while the ring is full to the brim (so the writer drains at its full speed the whole
// time); nothing may be dropped, and the file must hold every row, in order, value for value.
TEST(Logger, SixtySecondsAtOneKilohertzAllRowsReadBack) {
  constexpr long kRows = 60'000;
  phri::LoggerSettings settings;
  settings.path = temp_path("complete.csv");
  phri::Logger logger(settings);
  long waits = 0;
  const auto start = std::chrono::steady_clock::now();
  for (long k = 0; k < kRows; ++k) {
    while (logger.queue_depth() >= logger.capacity()) {
      ++waits;
      std::this_thread::yield();
    }
    ASSERT_TRUE(logger.push(make_row(k)));
  }
  const phri::LoggerStats stats = logger.close();
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf("logger: %ld rows in %.2f s wall (%.0f rows/s end to end), writer busy %.2f s (%.0f rows/s), "
              "max queue depth %zu of %zu, producer waited %ld times, dropped %llu\n",
              kRows, wall, kRows / wall, stats.writer_busy_s, stats.rows_per_busy_s(), stats.max_depth,
              logger.capacity(), waits, static_cast<unsigned long long>(stats.dropped));
  EXPECT_EQ(stats.pushed, static_cast<std::uint64_t>(kRows));
  EXPECT_EQ(stats.written, static_cast<std::uint64_t>(kRows));
  EXPECT_EQ(stats.dropped, 0u);
  EXPECT_FALSE(stats.write_error);
  // The writer must sustain far more than 1 kHz, or a long run would fill any ring.
  EXPECT_GT(stats.rows_per_busy_s(), 5000.0);

  const Csv csv = read_csv(settings.path);
  ASSERT_EQ(csv.rows.size(), static_cast<std::size_t>(kRows));
  const int time = csv.column("time_s"), cycle = csv.column("cycle"), q1 = csv.column("q_1"),
            q7 = csv.column("q_7"), tau3 = csv.column("tau_d_3"), cur7 = csv.column("current_7"),
            ee_y = csv.column("ee_y"), mode = csv.column("compliance_mode"), event = csv.column("event"),
            ct = csv.column("cycle_time_s");
  long bad = 0;
  for (long k = 0; k < kRows; ++k) {
    const auto& row = csv.rows[static_cast<std::size_t>(k)];
    const phri::LogRow expected = make_row(k);
    if (row.size() != csv.header.size()) {
      ++bad;
      continue;
    }
    const bool ok = to_double(row[time]) == expected.time_s && to_double(row[cycle]) == static_cast<double>(k) &&
                    to_double(row[q1]) == expected.q[0] && to_double(row[q7]) == expected.q[6] &&
                    to_double(row[tau3]) == expected.tau_d[2] && to_double(row[cur7]) == expected.current[6] &&
                    to_double(row[ee_y]) == expected.ee_position[1] &&
                    to_double(row[mode]) == expected.compliance_mode && to_double(row[event]) == expected.event &&
                    to_double(row[ct]) == expected.cycle_time_s;
    if (!ok) ++bad;
  }
  EXPECT_EQ(bad, 0);
  // Time stamps: strictly increasing by exactly one period's value.
  for (long k = 1; k < kRows; ++k) {
    ASSERT_EQ(to_double(csv.rows[static_cast<std::size_t>(k)][time]), static_cast<double>(k) * 1e-3) << k;
  }
}

// The realistic load: one row per millisecond of wall-clock time; nothing may be dropped and the
// queue stays short.
TEST(Logger, RealTimeOneKilohertzNeverDrops) {
  constexpr long kRows = 3000;
  phri::LoggerSettings settings;
  settings.path = temp_path("realtime.csv");
  phri::Logger logger(settings);
  auto next = std::chrono::steady_clock::now();
  for (long k = 0; k < kRows; ++k) {
    logger.push(make_row(k));
    next += std::chrono::milliseconds(1);
    std::this_thread::sleep_until(next);
  }
  const phri::LoggerStats stats = logger.close();
  std::printf("logger at 1 kHz real time: %s\n", logger.summary().c_str());
  EXPECT_EQ(stats.dropped, 0u);
  EXPECT_EQ(stats.written, static_cast<std::uint64_t>(kRows));
  EXPECT_EQ(read_csv(settings.path).rows.size(), static_cast<std::size_t>(kRows));
}

// A ring too small for the burst: push never blocks, the overflow is counted, and what was
// accepted is written.
TEST(Logger, FullRingDropsAndCounts) {
  phri::LoggerSettings settings;
  settings.path = temp_path("drops.csv");
  settings.capacity_rows = 4;
  settings.writer_sleep_ms = 50;  // a slow writer
  phri::Logger logger(settings);
  constexpr long kRows = 10'000;
  long refused = 0;
  const auto start = std::chrono::steady_clock::now();
  for (long k = 0; k < kRows; ++k) refused += logger.push(make_row(k)) ? 0 : 1;
  const double push_time = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  const phri::LoggerStats stats = logger.close();
  EXPECT_GT(refused, 0);
  EXPECT_EQ(stats.dropped, static_cast<std::uint64_t>(refused));
  EXPECT_EQ(stats.pushed + stats.dropped, static_cast<std::uint64_t>(kRows));
  EXPECT_EQ(stats.written, stats.pushed);
  EXPECT_EQ(read_csv(settings.path).rows.size(), stats.written);
  EXPECT_LT(push_time, 0.04);  // never waited for the 50 ms writer
  EXPECT_NE(logger.summary().find("dropped"), std::string::npos);
}

TEST(Logger, UnwritablePathAndTooManyJointsAreConfigErrorsNamingTheFile) {
  using phri::test::expect_config_error;
  phri::LoggerSettings settings;
  settings.path = "/nonexistent_phri_dir/run.csv";
  expect_config_error([&] { phri::Logger logger(settings); },
                      {.mentions = {"cannot create the log file"}, .file = settings.path});
  settings.path = temp_path("dof.csv");
  settings.dof = 8;
  expect_config_error([&] { phri::Logger logger(settings); }, {.element = "dof", .file = settings.path});
}

}  // namespace
