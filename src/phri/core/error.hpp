#pragma once
// phri::ConfigError: the one exception phri throws, only while loading files and configuration
// (never inside the control cycle). The message names the file, the element or key, and the reason.
#include <stdexcept>
#include <string>

namespace phri {

class ConfigError : public std::runtime_error {
public:
  ConfigError(std::string file, std::string element, std::string reason);

  const std::string& file() const { return file_; }
  const std::string& element() const { return element_; }
  const std::string& reason() const { return reason_; }

private:
  std::string file_;
  std::string element_;
  std::string reason_;
};

}  // namespace phri
