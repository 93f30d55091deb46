#pragma once
// phri::TaskSpec: one task as the run YAML declares it (`controller.tasks:`), plain data for the
// task registry (task_registry.hpp). Numbers are lists (a scalar is a list of one), words are
// strings; which keys a type reads, and their ranges, its factory says. Every error names
// `source` and the key, e.g. "controller.tasks[2].force_N".
#include <phri/core/error.hpp>
#include <phri/model/spatial.hpp>

#include <map>
#include <string_view>
#include <optional>
#include <string>
#include <vector>

namespace phri {

struct TaskSpec {
  std::string type;    ///< a registered type: pose, posture, force, frame
  std::string name;    ///< unique in the run; "end_effector" and "posture" configure the paper's two
  std::string source;  ///< the file it was declared in, for errors
  std::string path;    ///< its key path there, e.g. "controller.tasks[2]"
  std::map<std::string, std::vector<double>, std::less<>> numbers;
  std::map<std::string, std::string, std::less<>> words;

  bool has(std::string_view key) const { return numbers.count(key) || words.count(key); }
  [[noreturn]] void fail(const std::string& key, const std::string& reason) const {
    throw ConfigError(source, path.empty() ? key : path + "." + key, reason);
  }
  /// A number in [low, high]; `fallback` when absent.
  double number(std::string_view key, double fallback, double low, double high) const;
  /// Six numbers (or one, for all six) each in [low, high]; `fallback` when absent.
  Vector6d six(std::string_view key, const Vector6d& fallback, double low, double high) const;
  /// Three numbers (or one, for all three) each in [low, high]; `fallback` when absent.
  Eigen::Vector3d three(std::string_view key, const Eigen::Vector3d& fallback, double low, double high) const;
  /// A word among `choices`; `fallback` when absent.
  std::string word(std::string_view key, const std::string& fallback, const std::vector<std::string>& choices) const;
  /// Fails on the first key not among `keys` (besides type and name), e.g. "unknown key for a
  /// force task (known: ...)"; `kind` is "task" or "constraint".
  void check_keys(std::string_view kind, const std::vector<std::string_view>& keys) const;
};

/// "a, b, c": the names listed in error messages.
std::string join_words(const std::vector<std::string_view>& words);

}  // namespace phri
