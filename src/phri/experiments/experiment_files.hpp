#pragma once
// Small file helpers shared by the paper's experiments (src/phri/experiments): the output
// directory, CSV/text files, and the figure scripts of tools/report run through /usr/bin/python3.
// Experiments are drivers around the control cycle, not part of it: these helpers may allocate
// and throw (IoError when a file cannot be written).
#include <iosfwd>
#include <string>
#include <vector>

namespace phri {

/// Creates `dir` (and its parents) when missing; throws IoError when that fails.
void ensure_output_directory(const std::string& dir);

/// Writes `text` to `path`, replacing it; throws IoError when the file cannot be written.
void write_text_file(const std::string& path, const std::string& text);

/// `dir` joined with `name` ("dir/name"; `name` alone when `dir` is empty).
std::string output_path(const std::string& dir, const std::string& name);

/// The python interpreter that has numpy/scipy/matplotlib on Debian (the system one).
inline constexpr const char* kSystemPython = "/usr/bin/python3";

/// Runs `kSystemPython script args...` (headless: MPLBACKEND=Agg; through run_process, no shell),
/// copying the script's output, indented, to `out`.
/// Returns true when the script ran and exited with 0; false, with a line on `out`, when the
/// script or the interpreter is missing or the script failed. Never throws.
bool run_figure_script(const std::string& script, const std::vector<std::string>& args, std::ostream& out);

/// The end of an experiment command: lists the files written and, when both an output folder and a
/// figure script are set, draws `figure_name` (a PNG in output_dir) from the CSVs there.
void report_files_and_figure(const std::vector<std::string>& files, const std::string& output_dir,
                             const std::string& figure_script, const std::string& figure_name, std::ostream& out);

}  // namespace phri
