#include <phri/app/loop_clock.hpp>

#include <thread>

#include <pthread.h>
#include <sched.h>

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

RealTimePriorityScope::RealTimePriorityScope(bool wanted, int priority) {
  if (!wanted) return;
  sched_param old{};
  if (pthread_getschedparam(pthread_self(), &old_policy_, &old) != 0) return;
  old_priority_ = old.sched_priority;
  sched_param p{};
  p.sched_priority = priority;
  granted_ = pthread_setschedparam(pthread_self(), SCHED_FIFO, &p) == 0;
}

RealTimePriorityScope::~RealTimePriorityScope() {
  if (!granted_) return;
  sched_param old{};
  old.sched_priority = old_priority_;
  pthread_setschedparam(pthread_self(), old_policy_, &old);
}

}  // namespace phri
