#pragma once
// Owning handles of MuJoCo's model and data: std::unique_ptr whose deleters call mj_deleteModel and
// mj_deleteData. Only MuJoCo's forward declarations here, so that public headers holding a handle
// (sim_robot.hpp) stay free of MuJoCo's headers.
#include <memory>
#include <string>

struct mjModel_;
struct mjData_;

namespace phri {

struct MjModelDeleter {
  void operator()(mjModel_* model) const noexcept;
};

struct MjDataDeleter {
  void operator()(mjData_* data) const noexcept;
};

using MjModelPtr = std::unique_ptr<mjModel_, MjModelDeleter>;
using MjDataPtr = std::unique_ptr<mjData_, MjDataDeleter>;

/// MuJoCo's error buffer (mj_loadXML's, several lines: "XML Error: ...\nElement 'joint', line 55\n")
/// as one line for a ConfigError: lines trimmed, empty ones dropped, the rest joined by "; ".
std::string mujoco_error_line(const char* error);

/// MuJoCo model from MJCF text (through MuJoCo's virtual file system); null on failure, with
/// MuJoCo's message (as one line) in `error`. Blank text is refused here: MuJoCo 2.2.2's file
/// system treats an empty file as a fatal error (mju_error: a message, then exit).
MjModelPtr load_mjcf_text(const std::string& xml, std::string& error);

/// True when `xml` holds nothing but white space.
bool is_blank(const std::string& xml);

/// For programs only (apps/phri.cpp): MuJoCo's fatal errors, which its default handler reports on
/// stdout with "Press Enter to exit" and exit(1), become one line on stderr "phri: error: MuJoCo:
/// ..." and exit status 2; its warnings one line "phri: warning: MuJoCo: ..." on stderr (not
/// stdout and MUJOCO_LOG.TXT). MuJoCo cannot go on after an error, so the handler exits: a library
/// or a test must not install it. phri checks what it hands MuJoCo; this is the backstop.
void route_mujoco_messages_to_stderr();

}  // namespace phri
