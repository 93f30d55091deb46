#include "log_cli.hpp"

#include "exit_status.hpp"

#include <phri/app/logger.hpp>
#include <phri/app/mcap_log.hpp>
#include <phri/core/mcap_reader.hpp>

#include <cstdio>
#include <map>

namespace {

// "complete", or how a file that was cut short was read.
std::string file_state(const phri::McapReadSummary& s) {
  if (s.complete) return "complete";
  return "cut short (no summary or footer: its writer was killed?), read up to its last complete chunk, byte " +
         std::to_string(s.valid_bytes) + " of " + std::to_string(s.bytes);
}

int export_command(const std::string& log_path, const std::string& csv_path, bool legend) {
  const phri::McapLogInfo info = phri::export_mcap_log_csv(log_path, csv_path, legend);
  std::printf("phri log export: %s -> %s: %llu rows, %d joints; file %s\n", log_path.c_str(), csv_path.c_str(),
              static_cast<unsigned long long>(info.rows), info.dof, file_state(info.file).c_str());
  if (legend && !info.legend.empty()) std::printf("legend: %s\n", phri::Logger::legend_path_for(csv_path).c_str());
  return phri::cli::kOk;
}

int info_command(const std::string& log_path) {
  struct Topic {
    std::string type;
    std::uint64_t count = 0;
    double first_s = 0.0, last_s = 0.0;
  };
  std::map<std::string, Topic> topics;
  phri::McapVisitor visitor;
  visitor.on_channel = [&](const phri::McapChannel& c) {
    topics[c.topic].type = c.schema != nullptr ? c.schema->name : "(no schema)";
  };
  visitor.on_message = [&](const phri::McapChannel& c, const phri::McapMessage& m) {
    Topic& t = topics[c.topic];
    const double time_s = static_cast<double>(m.log_time_ns) * 1e-9;
    if (t.count++ == 0) t.first_s = time_s;
    t.last_s = time_s;
  };
  const phri::McapReadSummary s = phri::read_mcap(log_path, visitor);
  std::printf("%s: MCAP, profile '%s', written by '%s', %llu bytes, %llu chunks, %llu messages; %s\n", log_path.c_str(),
              s.profile.c_str(), s.library.c_str(), static_cast<unsigned long long>(s.bytes),
              static_cast<unsigned long long>(s.chunks), static_cast<unsigned long long>(s.messages), file_state(s).c_str());
  for (const auto& [name, t] : topics) {
    std::printf("  %-24s %-32s %8llu messages, %.3f to %.3f s\n", name.c_str(), t.type.c_str(),
                static_cast<unsigned long long>(t.count), t.first_s, t.last_s);
  }
  return phri::cli::kOk;
}

}  // namespace

LogCommands::LogCommands(CLI::App& app) {
  auto* log = app.add_subcommand("log", "A run's log: export an MCAP log to CSV, or list what a log holds");
  log->require_subcommand(1);
  export_ = log->add_subcommand("export", "An MCAP log back to the CSV the run would have written (every column, bit for bit)");
  export_->add_option("log", log_path_, "the run's MCAP log (phri run --log mcap)")->required()->check(CLI::ExistingFile);
  export_->add_option("--csv", csv_path_, "CSV file to write")->required();
  export_->add_flag("!--no-legend", legend_, "leave out the <csv>.legend.yaml of the integer codes");
  info_ = log->add_subcommand("info", "The topics, message counts and times of an MCAP log, and whether it is complete");
  info_->add_option("log", log_path_, "an MCAP file")->required()->check(CLI::ExistingFile);
}

int LogCommands::run() const {
  return export_->parsed() ? export_command(log_path_, csv_path_, legend_) : info_command(log_path_);
}
