#include <phri/app/logger.hpp>

#include <phri/control/controller.hpp>
#include <phri/config/event.hpp>
#include <phri/app/fsm.hpp>
#include <phri/core/error.hpp>
#include <phri/qp/qp_status.hpp>

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstring>
#include <filesystem>

namespace phri {
namespace {

constexpr std::size_t kBufferBytes = 1 << 20;
constexpr std::size_t kMaxRowBytes = Logger::kMaxCsvLineBytes;
// An MCAP chunk still open after this long is written anyway: a crash loses at most this much.
constexpr double kMcapFlushPeriodS = 1.0;

// Header names.
struct HeaderVisitor {
  std::string out;
  void name(std::string_view n) {
    if (!out.empty()) out += ',';
    out += n;
  }
  void number(std::string_view n, double) { name(n); }
  void integer(std::string_view n, std::int64_t) { name(n); }
  template <std::size_t N>
  void joints(std::string_view n, const std::array<double, N>&, int dof) {
    for (int i = 1; i <= dof; ++i) name(std::string(n) + "_" + std::to_string(i));
  }
};

// Values, straight into the output buffer (no allocation).
struct RowVisitor {
  char* p;
  char* end;
  bool first = true;
  void separator() {
    if (!first) *p++ = ',';
    first = false;
  }
  void number(std::string_view, double v) {
    separator();
    p = std::to_chars(p, end, v).ptr;
  }
  void integer(std::string_view, std::int64_t v) {
    separator();
    p = std::to_chars(p, end, v).ptr;
  }
  template <std::size_t N>
  void joints(std::string_view, const std::array<double, N>& values, int dof) {
    for (int i = 0; i < dof; ++i) number({}, values[static_cast<std::size_t>(i)]);
  }
};

template <class Enum, std::size_t N>
void legend_entry(std::string& out, std::string_view column, const Enum (&values)[N]) {
  out += std::string(column) + ":\n";
  for (Enum v : values) {
    out += "  " + std::to_string(static_cast<int>(v)) + ": " + std::string(to_string(v)) + "\n";
  }
}

}  // namespace

std::string Logger::header(int dof) {
  HeaderVisitor v;
  visit_log_columns(LogRow{}, dof, v);
  return v.out;
}

char* Logger::csv_line(const LogRow& row, int dof, char* out, char* end) {
  RowVisitor v{out, end};
  visit_log_columns(row, dof, v);
  return v.p;
}

std::string Logger::legend_yaml(const std::vector<std::string>& pfl_links) {
  std::string out =
      "# Integer codes of the phri log's columns (phri::Logger). Units of the other columns: see\n"
      "# src/phri/config/log_row.hpp (SI: s, rad, rad/s, N.m, A, m, N).\n";
  legend_entry(out, "compliance_mode", {ComplianceMode::kStiff, ComplianceMode::kNullSpace, ComplianceMode::kFullBody,
                                        ComplianceMode::kDual});
  out += "touched:\n  0: free\n  1: touched\n";
  legend_entry(out, "low_level_loop", {LowLevelMode::kPosition, LowLevelMode::kKinovaTorque,
                                       LowLevelMode::kKinovaTorqueHighVelocity, LowLevelMode::kCurrent,
                                       LowLevelMode::kTorque});
  out += "fsm_state:\n  -1: none\n";
  for (FsmState st : {FsmState::kStartup, FsmState::kStatic, FsmState::kDynamic, FsmState::kStopped}) {
    out += "  " + std::to_string(static_cast<int>(st)) + ": " + std::string(to_string(st)) + "\n";
  }
  out += "event:\n  -1: none\n";
  for (int i = 0; i < kEventCount; ++i) {
    out += "  " + std::to_string(i) + ": " + std::string(kEventNames[static_cast<std::size_t>(i)]) + "\n";
  }
  legend_entry(out, "cycle_status", {CycleStatus::kOk, CycleStatus::kQpFallback, CycleStatus::kInvalidState,
                                     CycleStatus::kStaleState, CycleStatus::kTargetsRejected, CycleStatus::kSafeStop});
  legend_entry(out, "safety_state", {SupervisorState::kNormal, SupervisorState::kDegraded, SupervisorState::kSafeStop});
  out += "safety_fault:\n";
  for (int f = 0; f <= static_cast<int>(SafetyFault::kLast); ++f) {
    out += "  " + std::to_string(f) + ": " + std::string(to_string(static_cast<SafetyFault>(f))) + "\n";
  }
  out += "ft_status:\n";
  for (int f = 0; f <= static_cast<int>(WrenchStatus::kLast); ++f) {
    out += "  " + std::to_string(f) + ": " + std::string(to_string(static_cast<WrenchStatus>(f))) + "\n";
  }
  legend_entry(out, "controller_status", {WholeBodyQpStatus::kOk, WholeBodyQpStatus::kQpInfeasible,
                                          WholeBodyQpStatus::kQpIterationLimit, WholeBodyQpStatus::kQpFailed,
                                          WholeBodyQpStatus::kInvalidInput, WholeBodyQpStatus::kBrakingScaled});
  legend_entry(out, "qp_status", {QpStatus::kOptimal, QpStatus::kInfeasible, QpStatus::kIterationLimit,
                                  QpStatus::kInvalidInput, QpStatus::kNumericalError});
  out += "pfl_link:\n  -1: none\n";
  for (std::size_t i = 0; i < pfl_links.size(); ++i) out += "  " + std::to_string(i) + ": " + pfl_links[i] + "\n";
  return out;
}

std::string Logger::legend_path_for(const std::string& csv_path) {
  std::filesystem::path p(csv_path);
  if (p.extension() == ".csv") p.replace_extension();
  return p.string() + ".legend.yaml";
}

namespace {
// The ring size, checked before the ring is allocated (kLogRingMaxBytes).
std::size_t checked_capacity(const LoggerSettings& settings) {
  if (settings.capacity_rows > log_ring_max_rows()) {
    throw ConfigError(settings.path, "capacity_rows",
                      "at most " + std::to_string(log_ring_max_rows()) + " rows (the ring stays under 100 MiB)");
  }
  return settings.capacity_rows;
}
}  // namespace

Logger::Logger(const LoggerSettings& settings)
    : settings_(settings), legend_path_(legend_path_for(settings.path)), ring_(checked_capacity(settings)) {
  if (settings.dof < 1 || settings.dof > kLogMaxJoints) {
    throw ConfigError(settings.path, "dof", "the logger records 1 to " + std::to_string(kLogMaxJoints) + " joints");
  }
  if (settings.format == LogFormat::kMcap) {
    try {
      mcap_ = std::make_unique<McapLogWriter>(settings);
    } catch (const IoError& e) {
      throw ConfigError(settings.path, "", std::string("cannot create the log file: ") + e.what());
    }
    running_ = true;
    writer_ = std::thread([this] { writer_loop(); });
    return;
  }
  file_ = std::fopen(settings.path.c_str(), "wb");
  if (file_ == nullptr) {
    throw ConfigError(settings.path, "", std::string("cannot create the log file: ") + std::strerror(errno));
  }
  const std::string head = header(settings.dof) + "\n";
  std::fwrite(head.data(), 1, head.size(), file_);
  if (settings.write_legend) {
    std::FILE* legend = std::fopen(legend_path_.c_str(), "wb");
    if (legend == nullptr) {
      std::fclose(file_);
      throw ConfigError(legend_path_, "", std::string("cannot create the log legend: ") + std::strerror(errno));
    }
    const std::string text = legend_yaml(settings.pfl_links);
    std::fwrite(text.data(), 1, text.size(), legend);
    std::fclose(legend);
  }
  buffer_.resize(kBufferBytes);
  running_ = true;
  writer_ = std::thread([this] { writer_loop(); });
}

Logger::~Logger() { close(); }

bool Logger::push(const LogRow& row) noexcept {
  if (!ring_.try_push(row)) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  pushed_.fetch_add(1, std::memory_order_relaxed);
  const std::size_t depth = ring_.depth_after_push();
  if (depth > max_depth_.load(std::memory_order_relaxed)) max_depth_.store(depth, std::memory_order_relaxed);
  return true;
}

void Logger::flush_buffer() {
  if (buffer_used_ == 0) return;
  if (!write_error_.load(std::memory_order_relaxed) &&
      std::fwrite(buffer_.data(), 1, buffer_used_, file_) != buffer_used_) {
    write_error_.store(true, std::memory_order_relaxed);
  }
  buffer_used_ = 0;
}

// Formats every row in the ring; writes the buffer whenever it fills up and once at the end.
void Logger::drain() {
  std::uint64_t count = 0;
  if (mcap_) {
    while (const LogRow* row = ring_.front()) {
      if (!write_error_.load(std::memory_order_relaxed)) {
        try {
          mcap_->write(*row);
        } catch (const Error&) {  // a compression failure: rows after it are lost, as after a failed fwrite
          write_error_.store(true, std::memory_order_relaxed);
        }
      }
      ring_.pop_front();
      ++count;
    }
    written_.fetch_add(count, std::memory_order_relaxed);
    return;
  }
  while (const LogRow* row = ring_.front()) {
    if (kBufferBytes - buffer_used_ < kMaxRowBytes) flush_buffer();
    char* end = csv_line(*row, settings_.dof, buffer_.data() + buffer_used_, buffer_.data() + kBufferBytes);
    *end++ = '\n';
    buffer_used_ = static_cast<std::size_t>(end - buffer_.data());
    ring_.pop_front();
    ++count;
  }
  flush_buffer();
  if (count > 0) {
    std::fflush(file_);
    written_.fetch_add(count, std::memory_order_relaxed);
  }
}

void Logger::writer_loop() {
  using Clock = std::chrono::steady_clock;
  const auto pause = std::chrono::milliseconds(settings_.writer_sleep_ms);
  auto last_flush = Clock::now();
  for (;;) {
    const bool last = !running_.load(std::memory_order_acquire);
    const auto start = Clock::now();
    drain();
    if (mcap_ && std::chrono::duration<double>(start - last_flush).count() > kMcapFlushPeriodS) {
      try {
        mcap_->flush();
      } catch (const Error&) {
        write_error_.store(true, std::memory_order_relaxed);
      }
      last_flush = start;
    }
    busy_s_.store(busy_s_.load(std::memory_order_relaxed) + std::chrono::duration<double>(Clock::now() - start).count(),
                  std::memory_order_relaxed);
    if (last) return;  // the producer stopped before this final drain: nothing is left behind
    std::this_thread::sleep_for(pause);
  }
}

LoggerStats Logger::close() {
  if (!closed_) {
    closed_ = true;
    running_.store(false, std::memory_order_release);
    if (writer_.joinable()) writer_.join();
    if (mcap_) {
      try {
        mcap_->close();
      } catch (const Error&) {
        write_error_ = true;
      }
    }
    if (file_ != nullptr) {
      if (std::fclose(file_) != 0) write_error_ = true;
      file_ = nullptr;
    }
  }
  return stats();
}

LoggerStats Logger::stats() const {
  LoggerStats s;
  s.pushed = pushed_.load(std::memory_order_relaxed);
  s.dropped = dropped_.load(std::memory_order_relaxed);
  s.written = written_.load(std::memory_order_relaxed);
  s.max_depth = max_depth_.load(std::memory_order_relaxed);
  s.writer_busy_s = busy_s_.load(std::memory_order_relaxed);
  s.write_error = write_error_.load(std::memory_order_relaxed);
  return s;
}

std::string Logger::summary() const {
  const LoggerStats s = stats();
  char text[256];
  std::snprintf(text, sizeof(text),
                "log %s: %llu rows written, %llu dropped, max queue depth %zu of %zu, writer %.0f rows/s busy%s",
                settings_.path.c_str(), static_cast<unsigned long long>(s.written),
                static_cast<unsigned long long>(s.dropped), s.max_depth, capacity(), s.rows_per_busy_s(),
                s.write_error ? ", WRITE ERROR" : "");
  return text;
}

}  // namespace phri
