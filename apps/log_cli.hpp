#pragma once
// `phri log export --csv OUT.csv LOG.mcap` and `phri log info LOG.mcap`: a run's MCAP log
// (app/mcap_log.hpp) back to the CSV the logger would have written, and what a log file holds.
#include <CLI/CLI.hpp>

#include <string>

class LogCommands {
public:
  explicit LogCommands(CLI::App& app);
  bool parsed() const { return export_->parsed() || info_->parsed(); }
  int run() const;

private:
  std::string log_path_, csv_path_;
  bool legend_ = true;
  CLI::App* export_ = nullptr;
  CLI::App* info_ = nullptr;
};
