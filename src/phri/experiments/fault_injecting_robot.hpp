#pragma once
// phri::FaultInjectingRobot: a RobotInterface decorator that corrupts what a robot reports (and
// may refuse what it is sent), for hostile testing of the controller's safety stage
// (safety-fuzz experiment). It wraps another RobotInterface (the simulated arm) and, during a
// window of control cycles, changes the RobotState it returns:
//
//   kNaN / kInf          one joint's q, q̇, τ_s or current (or the wrench's f_z) set to NaN / +inf
//   kAdd                 `value` added to one joint's signal (spikes: ±1e6, +50 N.m, +3 rad/s,
//                        +0.5 rad; offsets: smaller values held for many cycles); kWrench: f_z
//   kFrozenValues        q, q̇, τ_s and current keep the values of the window's first cycle while
//                        the sequence and the stamps advance (a sensor stuck, its bus alive)
//   kStaleFrame          the whole previous state is returned again (sequence and stamps too)
//   kSequenceJump        the joint/torque/current sequences jump ahead by `value`
//   kStampJump           the joint/torque/current stamps jump ahead by `value` seconds
//   kStampFrozen         the stamps keep their value of the window's first cycle; sequence advances
//   kShortVector         current_A of size `size` (0 or dof - 1) while current.valid stays true
//   kWriteRefused        write() refuses every command (WriteStatus::kFault), the robot keeps its last
//   kStall               a control-thread stall: at the window's first read() the wrapped robot is
//                        read `value` extra times (rounded, >= 0), so the plant runs that many more
//                        periods on its last accepted command and the controller sees only the last
//                        state (its sequences and stamps jump by value + 1); later reads pass through
//   kDrift               `value` x (k / cycles) added to one joint's signal (kWrench: f_z), k = 0 at
//                        the window's first read: a drift growing linearly from 0 by value / cycles
//                        per read (value x (cycles - 1) / cycles at its last read)
//   kWrenchStuck         wrench_sensor keeps the window's first value while wrench.sequence, stamp
//                        and valid advance (an F/T sensor stuck, its bus alive)
//   kWrenchStale         wrench_sensor, wrench.sequence, stamp and valid keep the window's first
//                        values (no new F/T sample); the joints pass through
//   kWrenchInvalid       wrench.valid = false (the values pass through)
// The F/T wrench's NaN and spikes are kNaN / kAdd on FaultSignal::kWrench (f_z).
//
// Outside the window the wrapped robot's state passes through unchanged (same values, bit for bit),
// so a run with a fault and a fault-free run with the same plant seed share their path until the
// window opens. read() and write() allocate nothing: the short vectors are swapped in from buffers
// sized at construction.
#include <phri/robot/robot_interface.hpp>

#include <Eigen/Core>

#include <cstdint>
#include <string_view>

namespace phri {

enum class FaultKind : std::uint8_t {
  kNone = 0,
  kNaN,
  kInf,
  kAdd,
  kFrozenValues,
  kStaleFrame,
  kSequenceJump,
  kStampJump,
  kStampFrozen,
  kShortVector,
  kWriteRefused,
  kStall,
  kDrift,
  kWrenchStuck,
  kWrenchStale,
  kWrenchInvalid,
};

constexpr std::string_view to_string(FaultKind k) {
  switch (k) {
    case FaultKind::kNone: return "none";
    case FaultKind::kNaN: return "nan";
    case FaultKind::kInf: return "inf";
    case FaultKind::kAdd: return "add";
    case FaultKind::kFrozenValues: return "frozen_values";
    case FaultKind::kStaleFrame: return "stale_frame";
    case FaultKind::kSequenceJump: return "sequence_jump";
    case FaultKind::kStampJump: return "stamp_jump";
    case FaultKind::kStampFrozen: return "stamp_frozen";
    case FaultKind::kShortVector: return "short_vector";
    case FaultKind::kWriteRefused: return "write_refused";
    case FaultKind::kStall: return "stall";
    case FaultKind::kDrift: return "drift";
    case FaultKind::kWrenchStuck: return "wrench_stuck";
    case FaultKind::kWrenchStale: return "wrench_stale";
    case FaultKind::kWrenchInvalid: return "wrench_invalid";
  }
  return "unknown";
}

enum class FaultSignal : std::uint8_t { kPosition = 0, kVelocity, kTorque, kCurrent, kWrench };

constexpr std::string_view to_string(FaultSignal s) {
  switch (s) {
    case FaultSignal::kPosition: return "q";
    case FaultSignal::kVelocity: return "qd";
    case FaultSignal::kTorque: return "tau";
    case FaultSignal::kCurrent: return "current";
    case FaultSignal::kWrench: return "wrench";
  }
  return "unknown";
}

/// One injected fault: what, on which signal and joint, from which read() (0: the first) for how many.
struct FaultSpec {
  FaultKind kind = FaultKind::kNone;
  FaultSignal signal = FaultSignal::kPosition;
  int joint = 0;
  double value = 0.0;      ///< kAdd: added; kDrift: reached at the window's end; kSequenceJump:
                           ///< sequence steps; kStampJump: seconds; kStall: extra periods
  int size = 0;            ///< kShortVector: length of current_A
  long start_cycle = 0;    ///< index of the first corrupted read()
  long cycles = 1;         ///< length of the window

  bool active(long cycle) const { return kind != FaultKind::kNone && cycle >= start_cycle && cycle < start_cycle + cycles; }
};

class FaultInjectingRobot final : public RobotInterface {
public:
  /// `inner` must outlive this object; a joint out of range is clamped to the last one.
  FaultInjectingRobot(RobotInterface& inner, const FaultSpec& fault);

  int dof() const override { return inner_.dof(); }
  double period_s() const override { return inner_.period_s(); }
  const RobotState& read() override;
  WriteStatus write(const RobotCommand& command) override;

  const FaultSpec& fault() const { return fault_; }
  /// Number of read() calls so far.
  long cycles() const { return cycle_; }
  /// Whether the state returned by the latest read() was corrupted (or writes are being refused).
  bool fault_active() const { return active_; }
  /// Writes refused by the injection (not by the wrapped robot).
  long injected_refusals() const { return injected_refusals_; }
  /// Extra reads of the wrapped robot so far (kStall).
  long stalled_periods() const { return stalled_periods_; }

private:
  void corrupt();
  void corrupt_value(double replacement, bool add);
  double drift_fraction(long cycle) const;
  void restore_sizes();

  RobotInterface& inner_;
  FaultSpec fault_;
  RobotState out_;
  RobotState frozen_;                // the window's first clean state (frozen values, stamps)
  Eigen::VectorXd short_current_;    // swapped into out_.current_A by kShortVector
  bool swapped_ = false;
  bool active_ = false;
  long cycle_ = 0;
  long injected_refusals_ = 0;
  long stalled_periods_ = 0;
};

}  // namespace phri
