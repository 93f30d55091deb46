#include <phri/sim/mujoco_handles.hpp>

#include <mujoco/mujoco.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>

namespace phri {

void MjModelDeleter::operator()(mjModel_* model) const noexcept { mj_deleteModel(model); }

void MjDataDeleter::operator()(mjData_* data) const noexcept { mj_deleteData(data); }

bool is_blank(const std::string& xml) { return xml.find_first_not_of(" \t\r\n") == std::string::npos; }

MjModelPtr load_mjcf_text(const std::string& xml, std::string& error) {
  if (is_blank(xml)) {
    error = "the file is empty (expected a <mujoco> model)";
    return nullptr;
  }
  mjVFS vfs;
  mj_defaultVFS(&vfs);
  const char* name = "phri_text.xml";
  if (mj_makeEmptyFileVFS(&vfs, name, static_cast<int>(xml.size())) != 0) {
    error = "MuJoCo virtual file system is full";
    return nullptr;
  }
  std::memcpy(vfs.filedata[mj_findFileVFS(&vfs, name)], xml.data(), xml.size());
  char buffer[1024] = "";
  MjModelPtr m(mj_loadXML(name, &vfs, buffer, sizeof(buffer)));
  mj_deleteVFS(&vfs);
  if (!m) error = mujoco_error_line(buffer);
  return m;
}

namespace {

// One line each: MuJoCo's messages may hold line breaks.
void print_mujoco_message(const char* prefix, const char* message) {
  std::fprintf(stderr, "%s%s\n", prefix, mujoco_error_line(message).c_str());
}

}  // namespace

void route_mujoco_messages_to_stderr() {
  mju_user_error = [](const char* message) {
    print_mujoco_message("phri: error: MuJoCo: ", message);
    std::exit(2);
  };
  mju_user_warning = [](const char* message) { print_mujoco_message("phri: warning: MuJoCo: ", message); };
}

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
