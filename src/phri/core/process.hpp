#pragma once
// phri::run_process: the one way phri starts another program (figure scripts and the like). The
// program gets its arguments as a vector, exactly as given: no shell ever parses them, so a path
// with quotes, semicolons or spaces is only a path.
#include <string>
#include <vector>

namespace phri {

struct ProcessOptions {
  /// "NAME=value" entries set in the program's environment (the caller's, otherwise).
  std::vector<std::string> environment;
  /// When not null, the program's standard output and error are collected here instead of going
  /// to the caller's.
  std::string* output = nullptr;
};

/// Runs the program argv[0] (searched on PATH when it has no '/') with the arguments `argv` and
/// waits for it. Returns its exit status (0 to 255), or 128 + the signal number when a signal
/// ended it. Flushes the caller's stdio first, so that the program's output comes after it.
/// Throws IoError when argv is empty or the program cannot be started.
int run_process(const std::vector<std::string>& argv, const ProcessOptions& options = {});

}  // namespace phri
