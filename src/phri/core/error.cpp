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
    : std::runtime_error(compose(file, element, reason)),
      file_(std::move(file)),
      element_(std::move(element)),
      reason_(std::move(reason)) {}

}  // namespace phri
