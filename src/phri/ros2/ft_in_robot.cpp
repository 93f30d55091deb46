#include <phri/ros2/ft_in_robot.hpp>

#include <chrono>

namespace phri {

FtInRobot::FtInRobot(RobotInterface& inner, TripleBuffer<FtInSample>& source, std::size_t ages_capacity)
    : inner_(inner), source_(source), state_(inner.dof()) {
  ages_.reserve(ages_capacity);
  stamp_ages_.reserve(ages_capacity);
}

const RobotState& FtInRobot::read() {
  state_ = inner_.read();  // same sizes every cycle: Eigen copies without allocating
  const FtInSample& s = source_.latest();
  if (s.count == 0) {
    state_.wrench = SignalStatus{};  // nothing received yet: no signal
    state_.wrench_sensor.setZero();
    return state_;
  }
  const std::int64_t now_ns =
      std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch()).count();
  const double age_s = 1e-9 * static_cast<double>(now_ns - s.received_ns);
  if (s.count != last_count_) {  // a new sample: the sequence advances, its stamp is when it came
    last_count_ = s.count;
    ++seen_;
    stamp_s_ = state_.time_s - age_s;
    if (ages_.size() < ages_.capacity()) ages_.push_back(age_s);
    if (stamp_ages_.size() < stamp_ages_.capacity()) {
      const std::int64_t wall_ns =
          std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
      stamp_ages_.push_back(1e-9 * static_cast<double>(wall_ns - s.stamp_ns));
    }
  }
  state_.wrench.sequence = static_cast<std::uint32_t>(seen_);
  state_.wrench.stamp_s = stamp_s_;
  state_.wrench.valid = true;
  for (int i = 0; i < 6; ++i) state_.wrench_sensor[i] = s.wrench[static_cast<std::size_t>(i)];
  return state_;
}

}  // namespace phri
