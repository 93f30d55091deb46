#include <phri/core/error.hpp>

namespace phri {
namespace {
std::string compose(const std::string& file, const std::string& element, const std::string& reason) {
  std::string msg = file.empty() ? std::string("<string>") : file;
  if (!element.empty()) msg += ": " + element;
  msg += ": " + reason;
  return msg;
}
}  // namespace

ConfigError::ConfigError(std::string file, std::string element, std::string reason)
    : Error(compose(file, element, reason)),
      file_(std::move(file)),
      element_(std::move(element)),
      reason_(std::move(reason)) {}

IoError::IoError(std::string path, std::string reason) : Error(compose(path, "", reason)), path_(std::move(path)) {}

ExperimentError::ExperimentError(std::string experiment, std::string reason)
    : Error(compose(experiment, "", reason)), experiment_(std::move(experiment)) {}

void throw_size_error(const char* function, const char* argument, long actual, long expected) {
  throw ArgumentError(std::string(function) + ": " + argument + " has " + std::to_string(actual) + " entries, expected " +
                      std::to_string(expected));
}

}  // namespace phri
