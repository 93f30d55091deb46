#pragma once
// The run's own settings (a run YAML's `run:`): how long, and how the loop is paced (app/loop_clock.hpp).

namespace phri {

/// kLockstep: as fast as possible; kRealTime: one period of wall-clock time per cycle.
enum class LoopPacing { kLockstep, kRealTime };

struct RunSettings {
  /// Longest run: one hour of robot time. The run loop keeps one cycle time (a double) per period
  /// for its statistics, sized before the loop: 3.6e6 cycles at 1 kHz are 29 MB (1e9 s ended in
  /// std::bad_alloc); a longer session is several runs.
  static constexpr double kMaxDuration_s = 3600.0;
  double duration_s = 30.0;  ///< robot time after which the run ends (if `stop` has not ended it)
  LoopPacing pacing = LoopPacing::kRealTime;
};

}  // namespace phri
