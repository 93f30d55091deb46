#pragma once
// What the paper's experiments (src/phri/experiments) share at their end: the output folder and
// its CSV/markdown/YAML files (write_output_files), and the command's report: the table, the files
// written and the figure drawn by a script of tools/report through /usr/bin/python3 (report_experiment).
// Experiments are drivers around the control cycle, not part of it: these helpers may allocate
// and throw (IoError when a file cannot be written).
#include <iosfwd>
#include <string>
#include <vector>

namespace phri {

/// Creates `dir` (and its parents) when missing and checks that a file can be written there;
/// throws IoError when either fails. Commands call it before their work, so that an unwritable
/// output folder is refused at once rather than after minutes of simulation.
void ensure_output_directory(const std::string& dir);

/// Writes `text` to `path`, replacing it; throws IoError when the file cannot be written.
void write_text_file(const std::string& path, const std::string& text);

/// `dir` joined with `name` ("dir/name"; `name` alone when `dir` is empty).
std::string output_path(const std::string& dir, const std::string& name);

/// One file an experiment writes: its name in the output folder and its text.
struct OutputFile {
  std::string name;
  std::string text;
};

/// Writes `files` into `dir` (created when missing) and returns their paths, in order; writes
/// nothing and returns nothing when `dir` is empty. Throws IoError.
std::vector<std::string> write_output_files(const std::string& dir, const std::vector<OutputFile>& files);

/// The python interpreter that has numpy/scipy/matplotlib on Debian (the system one).
inline constexpr const char* kSystemPython = "/usr/bin/python3";

/// Runs `kSystemPython script args...` (headless: MPLBACKEND=Agg; through run_process, no shell),
/// copying the script's output, indented, to `out`.
/// Returns true when the script ran and exited with 0; false, with a line on `out`, when the
/// script or the interpreter is missing or the script failed. Never throws.
bool run_figure_script(const std::string& script, const std::vector<std::string>& args, std::ostream& out);

/// What an experiment command prints at its end.
struct ExperimentReport {
  std::string table;               ///< the result (markdown)
  std::vector<std::string> files;  ///< written by the experiment
  std::string output_dir;          ///< where the figure script reads them
  std::string figure_script;       ///< empty: no figure
  std::string figure_name;         ///< a PNG in output_dir
};

/// The end of every experiment command: the table, "wrote <file>" for each file and, when both an
/// output folder and a figure script are set, the figure drawn from the files there.
void report_experiment(const ExperimentReport& report, std::ostream& out);

}  // namespace phri
