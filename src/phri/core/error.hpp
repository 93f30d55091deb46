#pragma once
// phri's exceptions: one family, all derived from phri::Error (a std::runtime_error), each message
// one line naming where and why. They are thrown only while loading, configuring, writing outputs or
// running an experiment, never inside the control cycle (a stage there returns a status instead).
//
//   Error            base: catch this to report any phri failure
//   ConfigError      a file, key or argument is wrong (malformed, out of range, inconsistent)
//   IoError          a file or directory cannot be read or written, an external tool failed
//   ExperimentError  an experiment ran but could not produce its result (e.g. a fit failed)
//   ArgumentError    a library function was handed a vector or matrix of the wrong size: a
//                    programming error, caught where the data enter (check_size), never silently
//                    read out of bounds
#include <stdexcept>
#include <string>

namespace phri {

class Error : public std::runtime_error {
public:
  using std::runtime_error::runtime_error;
};

class ConfigError : public Error {
public:
  /// Message "file: element: reason" (file "<string>" when empty, element left out when empty).
  ConfigError(std::string file, std::string element, std::string reason);

  const std::string& file() const { return file_; }
  const std::string& element() const { return element_; }
  const std::string& reason() const { return reason_; }

private:
  std::string file_;
  std::string element_;
  std::string reason_;
};

/// An error about one named thing (a path, an experiment): message "subject: reason".
class SubjectError : public Error {
public:
  SubjectError(std::string subject, const std::string& reason);
  const std::string& subject() const { return subject_; }

private:
  std::string subject_;
};

/// subject(): the path.
class IoError : public SubjectError {
public:
  using SubjectError::SubjectError;
  const std::string& path() const { return subject(); }
};

/// subject(): the experiment.
class ExperimentError : public SubjectError {
public:
  using SubjectError::SubjectError;
};

class ArgumentError : public Error {
public:
  using Error::Error;
};

/// Throws ArgumentError "function: argument has N entries, expected M" unless actual == expected.
[[noreturn]] void throw_size_error(const char* function, const char* argument, long actual, long expected);
inline void check_size(const char* function, const char* argument, long actual, long expected) {
  if (actual != expected) [[unlikely]] throw_size_error(function, argument, actual, expected);
}

}  // namespace phri
