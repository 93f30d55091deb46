#include <phri/app/loop_clock.hpp>

#include <thread>

namespace phri {

LoopClock::LoopClock(double period_s, Pacing pacing) : period_s_(period_s), pacing_(pacing) {}

void LoopClock::start() {
  started_ = true;
  next_ = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period_s_));
}

double LoopClock::wait_next() {
  ++cycles_;
  if (pacing_ == Pacing::kLockstep) return 0.0;
  if (!started_) start();
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(period_s_));
  const auto now = Clock::now();
  if (now > next_) {
    ++overruns_;
    const double late = std::chrono::duration<double>(now - next_).count();
    next_ = now + period;
    return late;
  }
  std::this_thread::sleep_until(next_);
  next_ += period;
  return 0.0;
}

}  // namespace phri
