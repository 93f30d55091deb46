#include <phri/experiments/fault_injecting_robot.hpp>

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace phri {

FaultInjectingRobot::FaultInjectingRobot(RobotInterface& inner, const FaultSpec& fault)
    : inner_(inner),
      fault_(fault),
      out_(inner.dof()),
      frozen_(inner.dof()),
      short_current_(Eigen::VectorXd::Zero(std::clamp(fault.size, 0, inner.dof()))) {
  fault_.joint = std::clamp(fault_.joint, 0, inner.dof() - 1);
  fault_.cycles = std::max<long>(fault_.cycles, 0);
}

void FaultInjectingRobot::restore_sizes() {
  if (!swapped_) return;
  out_.current_A.swap(short_current_);  // pointer swap: no allocation
  swapped_ = false;
}

const RobotState& FaultInjectingRobot::read() {
  const RobotState* inner = &inner_.read();
  const long c = cycle_++;
  active_ = fault_.active(c);
  restore_sizes();
  if (active_ && c == fault_.start_cycle && fault_.kind == FaultKind::kStall) {
    // The controller's thread missed these periods: the robot ran on, on its last command.
    const long extra = std::lround(std::max(0.0, fault_.value));
    for (long k = 0; k < extra; ++k) inner = &inner_.read();
    stalled_periods_ += extra;
  }
  const RobotState& clean = *inner;
  if (active_ && c == fault_.start_cycle) frozen_ = clean;
  // A stale frame: the previous state again, whatever the robot now reports.
  if (active_ && fault_.kind == FaultKind::kStaleFrame) return out_;
  out_ = clean;
  if (injected_refusals_ > 0) {
    out_.rejected_writes += static_cast<std::uint64_t>(injected_refusals_);
  }
  if (active_) corrupt();
  return out_;
}

WriteStatus FaultInjectingRobot::write(const RobotCommand& command) {
  if (active_ && fault_.kind == FaultKind::kWriteRefused) {
    ++injected_refusals_;
    out_.last_write_status = WriteStatus::kFault;
    return WriteStatus::kFault;
  }
  return inner_.write(command);
}

void FaultInjectingRobot::corrupt_value(double replacement, bool add) {
  if (fault_.signal == FaultSignal::kWrench) {
    out_.wrench_sensor[2] = add ? out_.wrench_sensor[2] + replacement : replacement;
    return;
  }
  Eigen::VectorXd* v = nullptr;
  switch (fault_.signal) {
    case FaultSignal::kPosition: v = &out_.q_rad; break;
    case FaultSignal::kVelocity: v = &out_.qd_rad_s; break;
    case FaultSignal::kTorque: v = &out_.tau_sensor_Nm; break;
    case FaultSignal::kCurrent: v = &out_.current_A; break;
    case FaultSignal::kWrench: return;
  }
  if (v == nullptr || fault_.joint >= v->size()) return;
  double& x = (*v)[fault_.joint];
  x = add ? x + replacement : replacement;
}

double FaultInjectingRobot::drift_fraction(long cycle) const {
  return fault_.cycles > 0 ? static_cast<double>(cycle - fault_.start_cycle) / static_cast<double>(fault_.cycles) : 0.0;
}

void FaultInjectingRobot::corrupt() {
  SignalStatus* signals[] = {&out_.joints, &out_.torque, &out_.current};
  switch (fault_.kind) {
    case FaultKind::kNone:
    case FaultKind::kStaleFrame:
    case FaultKind::kWriteRefused:
    case FaultKind::kStall: return;
    case FaultKind::kDrift: corrupt_value(fault_.value * drift_fraction(cycle_ - 1), true); return;
    case FaultKind::kWrenchStuck: out_.wrench_sensor = frozen_.wrench_sensor; return;
    case FaultKind::kWrenchStale:
      out_.wrench_sensor = frozen_.wrench_sensor;
      out_.wrench = frozen_.wrench;
      return;
    case FaultKind::kWrenchInvalid: out_.wrench.valid = false; return;
    case FaultKind::kNaN: corrupt_value(std::numeric_limits<double>::quiet_NaN(), false); return;
    case FaultKind::kInf: corrupt_value(std::numeric_limits<double>::infinity(), false); return;
    case FaultKind::kAdd: corrupt_value(fault_.value, true); return;
    case FaultKind::kFrozenValues:
      out_.q_rad = frozen_.q_rad;
      out_.qd_rad_s = frozen_.qd_rad_s;
      out_.tau_sensor_Nm = frozen_.tau_sensor_Nm;
      out_.current_A = frozen_.current_A;
      return;
    case FaultKind::kSequenceJump:
      for (SignalStatus* s : signals) s->sequence += static_cast<std::uint32_t>(fault_.value);
      return;
    case FaultKind::kStampJump:
      for (SignalStatus* s : signals) s->stamp_s += fault_.value;
      return;
    case FaultKind::kStampFrozen:
      out_.joints.stamp_s = frozen_.joints.stamp_s;
      out_.torque.stamp_s = frozen_.torque.stamp_s;
      out_.current.stamp_s = frozen_.current.stamp_s;
      return;
    case FaultKind::kShortVector:
      short_current_ = out_.current_A.head(short_current_.size());
      out_.current_A.swap(short_current_);
      swapped_ = true;
      return;
  }
}

}  // namespace phri
