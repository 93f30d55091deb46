#pragma once
// The one check of "this must be refused with a phri::ConfigError" for every test program:
//
//   phri::test::expect_config_error([&] { load(...); }, {.element = "controller.observer_gain",
//                                                         .mentions = {"> 0"}, .file = "test.yaml"});
//
// It fails (at the caller's line) when the callable returns normally, throws anything else than a
// ConfigError, or throws one whose key path (ConfigError::element) or file differs from the
// expected ones (checked when given), or whose message lacks one of the `mentions`. It returns the
// error caught, for any further check.
#include <phri/core/error.hpp>

#include <gtest/gtest.h>

#include <exception>
#include <optional>
#include <source_location>
#include <string>
#include <utility>
#include <vector>

namespace phri::test {

struct ExpectedConfigError {
  // (Default member initializers: a designated initializer may leave any of them out.)
  std::string element{};                ///< the key path, exactly (not checked when empty)
  std::vector<std::string> mentions{};  ///< fragments the message (what()) must contain
  std::string file{};                   ///< the file, exactly (not checked when empty)
};

inline std::string describe(const ExpectedConfigError& expected) {
  std::string s = "a ConfigError";
  if (!expected.element.empty()) s += " on '" + expected.element + "'";
  if (!expected.file.empty()) s += " in '" + expected.file + "'";
  for (const std::string& m : expected.mentions) s += ", mentioning '" + m + "'";
  return s;
}

template <class Action>
std::optional<ConfigError> expect_config_error(Action&& action, const ExpectedConfigError& expected,
                                               std::source_location where = std::source_location::current()) {
  try {
    std::forward<Action>(action)();
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    if (!expected.element.empty() && e.element() != expected.element) {
      ADD_FAILURE_AT(where.file_name(), static_cast<int>(where.line()))
          << "key path '" << e.element() << "', expected '" << expected.element << "'\n  message: " << what;
    }
    if (!expected.file.empty() && e.file() != expected.file) {
      ADD_FAILURE_AT(where.file_name(), static_cast<int>(where.line()))
          << "file '" << e.file() << "', expected '" << expected.file << "'\n  message: " << what;
    }
    for (const std::string& m : expected.mentions) {
      if (what.find(m) == std::string::npos) {
        ADD_FAILURE_AT(where.file_name(), static_cast<int>(where.line()))
            << "the message does not mention '" << m << "'\n  message: " << what;
      }
    }
    return e;
  } catch (const std::exception& e) {
    ADD_FAILURE_AT(where.file_name(), static_cast<int>(where.line()))
        << "expected " << describe(expected) << ", got another exception: " << e.what();
    return std::nullopt;
  }
  ADD_FAILURE_AT(where.file_name(), static_cast<int>(where.line())) << "expected " << describe(expected) << ", nothing thrown";
  return std::nullopt;
}

}  // namespace phri::test
