#pragma once
// phri::LoopClock: paces a read -> compute -> write loop. With a simulated robot the physics runs
// in lockstep inside read(), so the clock alone decides the wall-clock pace:
//   kLockstep  as fast as possible (experiments, tests, benchmarks): wait_next() returns at once;
//   kRealTime  one period of wall-clock time per cycle (interactive use, hardware-in-the-loop):
//              wait_next() sleeps until the next deadline on std::chrono::steady_clock. A late
//              cycle is counted as an overrun and the schedule is not caught up (the next deadline
//              is one period after now), so a stall does not cause a burst of fast cycles.
// With the real arm, read() itself blocks on the robot's 1 kHz feedback; use kLockstep there.
#include <phri/config/run_settings.hpp>

#include <chrono>
#include <cstdint>

namespace phri {

class LoopClock {
public:
  using Pacing = LoopPacing;

  LoopClock(double period_s, Pacing pacing);

  /// Starts the schedule now (called by the first wait_next() otherwise).
  void start();
  /// Ends a cycle; see the pacing modes above. Returns the lateness of this cycle [s] (0 when on
  /// time or in lockstep).
  double wait_next();

  Pacing pacing() const { return pacing_; }
  double period_s() const { return period_s_; }
  std::uint64_t cycles() const { return cycles_; }
  std::uint64_t overruns() const { return overruns_; }

private:
  using Clock = std::chrono::steady_clock;
  double period_s_;
  Pacing pacing_;
  bool started_ = false;
  Clock::time_point next_;
  std::uint64_t cycles_ = 0;
  std::uint64_t overruns_ = 0;
};

/// Real-time pacing's scheduling: for its lifetime the calling thread runs under SCHED_FIFO (a
/// 1 kHz loop that sleeps most of each period, so it never starves the machine), as a controller
/// on a real-time kernel would; a busy machine (a browser rendering the dashboard, builds) then
/// cannot preempt a cycle past its period. Where the OS refuses (no CAP_SYS_NICE / RLIMIT_RTPRIO)
/// the thread stays as it was and granted() says so. The destructor restores the old policy.
class RealTimePriorityScope {
public:
  explicit RealTimePriorityScope(bool wanted, int priority = 80);
  ~RealTimePriorityScope();
  RealTimePriorityScope(const RealTimePriorityScope&) = delete;
  RealTimePriorityScope& operator=(const RealTimePriorityScope&) = delete;
  bool granted() const { return granted_; }

private:
  bool granted_ = false;
  int old_policy_ = 0;
  int old_priority_ = 0;
};

}  // namespace phri
