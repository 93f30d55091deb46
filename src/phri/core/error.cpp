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

SubjectError::SubjectError(std::string subject, const std::string& reason)
    : Error(compose(subject, "", reason)), subject_(std::move(subject)) {}

void throw_size_error(const char* function, const char* argument, long actual, long expected) {
  throw ArgumentError(std::string(function) + ": " + argument + " has " + std::to_string(actual) + " entries, expected " +
                      std::to_string(expected));
}

}  // namespace phri
