#pragma once
// phri::WriteStatus: the answer of RobotInterface::write. Anything but kOk means the command was
// refused as a whole: the robot keeps executing the previous accepted command, and the refusal is
// reported in the next RobotState (last_write_status, rejected_writes).
#include <cstdint>
#include <string_view>

namespace phri {

enum class WriteStatus : std::uint8_t {
  kOk = 0,
  kInvalidMode,    ///< the mode is not a LowLevelMode
  kSizeMismatch,   ///< the set-point vector of the mode does not have one entry per joint
  kNotFinite,      ///< a set-point of the mode is NaN or infinite
  kOutOfRange,     ///< a set-point exceeds a joint position, torque or current limit
  kFault,          ///< the robot is in fault and accepts no command
};

constexpr std::string_view to_string(WriteStatus status) {
  switch (status) {
    case WriteStatus::kOk: return "ok";
    case WriteStatus::kInvalidMode: return "invalid_mode";
    case WriteStatus::kSizeMismatch: return "size_mismatch";
    case WriteStatus::kNotFinite: return "not_finite";
    case WriteStatus::kOutOfRange: return "out_of_range";
    case WriteStatus::kFault: return "fault";
  }
  return "unknown";
}

}  // namespace phri
