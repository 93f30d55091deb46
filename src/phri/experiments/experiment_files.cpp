#include <phri/experiments/experiment_files.hpp>

#include <phri/core/error.hpp>
#include <phri/core/process.hpp>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <string_view>
#include <system_error>

namespace phri {

void ensure_output_directory(const std::string& dir) {
  if (dir.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    throw IoError(dir, "cannot create the output directory: " + (ec ? ec.message() : "not a directory"));
  }
  // Writable: a probe file, created and removed (a read-only mount, a folder without write permission).
  const std::filesystem::path probe = std::filesystem::path(dir) / ".phri_write_probe";
  std::ofstream file(probe, std::ios::binary | std::ios::trunc);
  const bool writable = static_cast<bool>(file << "probe\n");
  file.close();
  std::filesystem::remove(probe, ec);
  if (!writable) throw IoError(dir, "cannot write into the output directory");
}

void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) throw IoError(path, "cannot open for writing");
  file << text;
  file.close();
  if (!file) throw IoError(path, "write failed");
}

std::string output_path(const std::string& dir, const std::string& name) {
  if (dir.empty()) return name;
  return (std::filesystem::path(dir) / name).string();
}

std::vector<std::string> write_output_files(const std::string& dir, const std::vector<OutputFile>& files) {
  std::vector<std::string> paths;
  if (dir.empty()) return paths;
  ensure_output_directory(dir);
  for (const OutputFile& file : files) {
    paths.push_back(output_path(dir, file.name));
    write_text_file(paths.back(), file.text);
  }
  return paths;
}

namespace {
// The script's output, each line indented under ours.
void print_indented(const std::string& text, std::ostream& out) {
  std::size_t start = 0;
  while (start < text.size()) {
    const std::size_t end = std::min(text.find('\n', start), text.size() - 1) + 1;
    out << "  " << std::string_view(text).substr(start, end - start);
    start = end;
  }
}
}  // namespace

void report_experiment(const ExperimentReport& report, std::ostream& out) {
  out << "\n" << report.table;
  for (const std::string& f : report.files) out << "wrote " << f << "\n";
  if (!report.output_dir.empty() && !report.figure_script.empty()) {
    const std::string png = output_path(report.output_dir, report.figure_name);
    if (run_figure_script(report.figure_script, {report.output_dir, png}, out)) out << "wrote " << png << "\n";
  }
  out.flush();
}

bool run_figure_script(const std::string& script, const std::vector<std::string>& args, std::ostream& out) {
  if (script.empty()) return false;
  if (!std::filesystem::exists(kSystemPython)) {
    out << "figure: skipped (" << kSystemPython << " not found)\n";
    return false;
  }
  if (!std::filesystem::exists(script)) {
    out << "figure: skipped (script " << script << " not found)\n";
    return false;
  }
  std::string output;
  int status = 0;
  try {
    std::vector<std::string> argv = {kSystemPython, script};
    argv.insert(argv.end(), args.begin(), args.end());
    status = run_process(argv, {{"MPLBACKEND=Agg"}, &output});  // headless
  } catch (const IoError& e) {
    out << "figure: could not start " << kSystemPython << " (" << e.what() << ")\n";
    return false;
  }
  print_indented(output, out);
  if (status != 0) {
    out << "figure: " << script << " failed (status " << status << ")\n";
    return false;
  }
  return true;
}

}  // namespace phri
