#include <phri/sim/mujoco_handles.hpp>

#include <mujoco/mujoco.h>

namespace phri {

void MjModelDeleter::operator()(mjModel_* model) const noexcept { mj_deleteModel(model); }

void MjDataDeleter::operator()(mjData_* data) const noexcept { mj_deleteData(data); }

std::string mujoco_error_line(const char* error) {
  const std::string text = error != nullptr ? error : "";
  std::string out;
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find_first_of("\r\n", start);
    if (end == std::string::npos) end = text.size();
    const std::size_t first = text.find_first_not_of(" \t", start);
    if (first != std::string::npos && first < end) {
      const std::size_t last = text.find_last_not_of(" \t", end - 1);
      out += (out.empty() ? "" : "; ") + text.substr(first, last + 1 - first);
    }
    start = end + 1;
  }
  return out.empty() ? "unknown error" : out;
}

}  // namespace phri
