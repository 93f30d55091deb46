#pragma once
// A folder for one test process's files, removed when the process ends:
//   const std::string path = phri::test::temp_path("phri_test_logger", "run.csv");
#include <filesystem>
#include <string>
#include <system_error>

#include <unistd.h>

namespace phri::test {

struct TempDir {
  explicit TempDir(const std::string& prefix)
      : path(std::filesystem::temp_directory_path() / (prefix + "_" + std::to_string(::getpid()))) {
    std::filesystem::create_directories(path);
  }
  ~TempDir() {
    std::error_code ignored;
    std::filesystem::remove_all(path, ignored);
  }
  std::filesystem::path path;
};

/// `name` inside this process's folder `<tmp>/<prefix>_<pid>` (one prefix per test program).
inline std::string temp_path(const std::string& prefix, const std::string& name) {
  static TempDir dir(prefix);
  return (dir.path / name).string();
}

}  // namespace phri::test
