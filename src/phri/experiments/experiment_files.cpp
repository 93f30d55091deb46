#include <phri/experiments/experiment_files.hpp>

#include <phri/core/error.hpp>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <ostream>
#include <system_error>

namespace phri {

void ensure_output_directory(const std::string& dir) {
  if (dir.empty()) return;
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir)) {
    throw ConfigError(dir, "", "cannot create the output directory: " + ec.message());
  }
}

void write_text_file(const std::string& path, const std::string& text) {
  std::ofstream file(path, std::ios::binary | std::ios::trunc);
  if (!file) throw ConfigError(path, "", "cannot open for writing");
  file << text;
  file.close();
  if (!file) throw ConfigError(path, "", "write failed");
}

std::string output_path(const std::string& dir, const std::string& name) {
  if (dir.empty()) return name;
  return (std::filesystem::path(dir) / name).string();
}

namespace {
// Single-quoted for /bin/sh: every ' becomes '\''.
std::string shell_quote(const std::string& s) {
  std::string q(1, '\'');
  for (char c : s) {
    if (c == '\'') {
      q.append("'\\''");
    } else {
      q.push_back(c);
    }
  }
  q.push_back('\'');
  return q;
}
}  // namespace

void report_files_and_figure(const std::vector<std::string>& files, const std::string& output_dir,
                             const std::string& figure_script, const std::string& figure_name, std::ostream& out) {
  for (const std::string& f : files) out << "wrote " << f << "\n";
  if (!output_dir.empty() && !figure_script.empty()) {
    const std::string png = output_path(output_dir, figure_name);
    if (run_figure_script(figure_script, {output_dir, png}, out)) out << "wrote " << png << "\n";
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
  std::string command = "MPLBACKEND=Agg ";
  command.append(kSystemPython).append(" ").append(shell_quote(script));
  for (const std::string& a : args) command.append(" ").append(shell_quote(a));
  command.append(" 2>&1");
  out.flush();
  std::FILE* pipe = ::popen(command.c_str(), "r");
  if (pipe == nullptr) {
    out << "figure: could not start " << kSystemPython << "\n";
    return false;
  }
  char buffer[512];
  while (std::fgets(buffer, sizeof(buffer), pipe) != nullptr) out << "  " << buffer;
  const int status = ::pclose(pipe);
  if (status != 0) {
    out << "figure: " << script << " failed (status " << status << ")\n";
    return false;
  }
  return true;
}

}  // namespace phri
