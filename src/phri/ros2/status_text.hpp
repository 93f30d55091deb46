#pragma once
// phri::status_text: the text of /phri/status (std_msgs/String), one line of space-separated
// key=value pairs, keys in this order (values never contain spaces; new keys are appended):
//
//   t=<robot time s> cycle=<n> mode=<compliance mode> touched=<0|1> loop=<low-level loop>
//   fsm=<startup|static|dynamic|stopped> safety=<normal|degraded|safe_stop> fault=<sample fault|none>
//   ft=<F/T source status> cycle_us=<compute time of the cycle, us> overruns=<n> stiffness=<scale>
//   err_mm=<end-effector position error, mm> inputs_accepted=<n> inputs_refused=<n>
//   last_refusal=<InputRefusal name> snapshots_dropped=<n>
//
// e.g. "t=3.250 cycle=3250 mode=dual touched=0 loop=kinova_torque fsm=static safety=normal
// fault=none ft=ok cycle_us=84.1 overruns=0 stiffness=1.000 err_mm=0.42 inputs_accepted=2
// inputs_refused=0 last_refusal=none snapshots_dropped=0" (one line). Names: config/event.hpp,
// control/compliance_mode.hpp, robot/low_level_mode.hpp, safety/state_supervisor.hpp,
// safety/wrench_supervisor.hpp, ros2/input_gate.hpp. A parser splits on spaces, then on the first '='.
#include <phri/app/snapshot_channel.hpp>

#include <cstddef>
#include <cstdint>
#include <string_view>

namespace phri {

struct BridgeCounters {
  std::uint64_t inputs_accepted = 0, inputs_refused = 0, snapshots_dropped = 0;
  std::string_view last_refusal = "none";
};

/// Writes the status line into `buffer` (NUL-terminated, cut to its size); returns its length.
std::size_t status_text(const LiveSnapshot& snapshot, const BridgeCounters& counters, char* buffer, std::size_t size);

}  // namespace phri
