#pragma once
// phri::Logger: one row per control cycle (config/log_row.hpp), written to disk off the control
// thread (DESIGN.md section 2, last stage), as CSV text or as an MCAP file (settings.format;
// app/mcap_log.hpp: the same columns, ROS 2 messages in zstd chunks, each chunk flushed within 1 s).
//
//   phri::Logger logger({.path = "run.csv"});   // opens the file, writes header + legend, starts the writer
//   for (...) {                                   // control thread, 1 kHz
//     cycle.step(state, command);
//     phri::fill_log_row(row, state, cycle);     // row: a LogRow kept by the loop (no allocation)
//     logger.push(row);                          // copies into the ring; never blocks, never allocates
//   }
//   const phri::LoggerStats stats = logger.close();   // drains everything, reports drops
//
// push() copies the row into a preallocated single-producer/single-consumer ring (SpscRing). A
// writer thread drains it, formats each row (std::to_chars: shortest text that reads back to the
// same double) into a 1 MiB buffer and writes the buffer with one fwrite; when the ring is empty
// it sleeps `writer_sleep_ms`. If the ring is full the row is dropped and counted (the control
// thread never waits for the disk); close() drains what is left and reports the count.
//
// Sizing: a row is ~1.5 KB; the default 16384 rows (24 MB, 16 s at 1 kHz) rides out a stalled
// disk or a descheduled writer for 16 s, while the writer drains ~10^5 rows/s on one core
// (figures in the test, tests/test_logger.cpp). The file:
//   * line 1: named columns (LogRow's header), e.g. time_s,cycle,q_1,...,q_7,qd_1,...
//   * then one line per row, numbers only (integer codes for modes and statuses),
// which pandas.read_csv and PlotJuggler's CSV loader open directly. The codes' legend goes to
// a sidecar <path without .csv>.legend.yaml (legend_yaml()).
#include <phri/config/log_row.hpp>
#include <phri/config/logger_settings.hpp>
#include <phri/app/mcap_log.hpp>
#include <phri/core/spsc_ring.hpp>

#include <atomic>
#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

namespace phri {

struct LoggerStats {
  std::uint64_t pushed = 0;      ///< rows accepted by push()
  std::uint64_t dropped = 0;     ///< rows refused because the ring was full
  std::uint64_t written = 0;     ///< rows written to the file
  std::size_t max_depth = 0;     ///< largest ring occupancy seen right after a push
  double writer_busy_s = 0.0;    ///< writer time spent formatting and writing (not sleeping)
  double rows_per_busy_s() const { return writer_busy_s > 0.0 ? static_cast<double>(written) / writer_busy_s : 0.0; }
  bool write_error = false;      ///< an fwrite failed (disk full...): rows after it are lost
};

class Logger {
public:
  /// Opens the file, writes the header (and the legend) and starts the writer thread. Throws
  /// ConfigError(path, ...) when the file cannot be created or dof is out of range.
  explicit Logger(const LoggerSettings& settings);
  ~Logger();
  Logger(const Logger&) = delete;
  Logger& operator=(const Logger&) = delete;

  /// Control thread (one producer thread, before close()): copies `row` into the ring. False
  /// (and counted as dropped) when full.
  bool push(const LogRow& row) noexcept;

  /// Drains the ring, stops the writer, closes the file. Idempotent; the destructor calls it.
  LoggerStats close();
  /// Counters so far (any thread; the writer's are approximate while it runs).
  LoggerStats stats() const;
  /// One line: rows written, dropped, max queue depth, writer throughput.
  std::string summary() const;

  const std::string& path() const { return settings_.path; }
  const std::string& legend_path() const { return legend_path_; }
  std::size_t capacity() const { return ring_.capacity(); }
  /// Rows waiting in the ring now (any thread).
  std::size_t queue_depth() const { return ring_.size_approx(); }

  /// The CSV header line (no newline) for `dof` joints.
  static std::string header(int dof);
  /// One CSV line of `row` (no newline) into [out, end) (end - out >= kMaxCsvLineBytes); returns its end.
  static char* csv_line(const LogRow& row, int dof, char* out, char* end);
  static constexpr std::size_t kMaxCsvLineBytes = 8192;  // > 120 columns x 25 characters
  /// The legend of the integer columns, as YAML.
  /// `pfl_links`: the names of the pfl_link column's indices (LoggerSettings::pfl_links).
  static std::string legend_yaml(const std::vector<std::string>& pfl_links = {});
  /// Sidecar name: "a/run.csv" -> "a/run.legend.yaml".
  static std::string legend_path_for(const std::string& csv_path);

private:
  void writer_loop();
  void drain();
  void flush_buffer();

  LoggerSettings settings_;
  std::string legend_path_;
  SpscRing<LogRow> ring_;
  std::FILE* file_ = nullptr;               // CSV
  std::unique_ptr<McapLogWriter> mcap_;     // MCAP
  std::vector<char> buffer_;
  std::size_t buffer_used_ = 0;
  std::thread writer_;
  std::atomic<bool> running_{false};
  bool closed_ = false;
  // producer side
  std::atomic<std::uint64_t> pushed_{0};
  std::atomic<std::uint64_t> dropped_{0};
  std::atomic<std::size_t> max_depth_{0};
  // writer side
  std::atomic<std::uint64_t> written_{0};
  std::atomic<double> busy_s_{0.0};
  std::atomic<bool> write_error_{false};
};

}  // namespace phri
