#pragma once
// phri::LiveChannel: the run loop's lock-free hand-off to a live front end (the dashboard,
// dashboard/dashboard_server.hpp). Two queues, both allocated at construction:
//   commands   front end -> loop: events and gain changes (posted to the FSM, the gamepad's
//              path), pushes on the simulated arm, run / pause / single-step;
//   snapshots  loop -> front end: every `decimation`-th cycle (16: ~60 Hz at 1 kHz) the cycle's
//              log row and what the loop knows beside it (the push it applies, paused or not).
// The loop side never blocks, locks or allocates: a full snapshot queue drops the snapshot (the
// front end shows the next one), an empty command queue is no news. The front-end side may call
// send() from several threads (they are serialised by a mutex the loop never takes); one thread
// reads the snapshots.
#include <phri/app/event.hpp>
#include <phri/app/live_gain.hpp>
#include <phri/app/log_row.hpp>
#include <phri/core/spsc_ring.hpp>

#include <Eigen/Core>

#include <atomic>
#include <cstdint>
#include <mutex>

namespace phri {

/// A force on a link of the simulated arm (drag-to-push).
struct LivePush {
  int body = -1;  ///< model body (the child of joint `body`); -1: none
  Eigen::Vector3d point_local = Eigen::Vector3d::Zero();  ///< application point, body frame [m]
  Eigen::Vector3d force_world = Eigen::Vector3d::Zero();  ///< [N], world axes
};

struct LiveCommand {
  enum class Kind : std::uint8_t { kEvent, kGain, kPush, kRelease, kRun, kPause, kStep };
  Kind kind = Kind::kEvent;
  Event event = Event::kStop;  ///< kEvent
  GainRequest gain;            ///< kGain
  LivePush push;               ///< kPush: replaces the push applied so far
  int steps = 1;               ///< kStep: cycles to run before pausing again
};

struct LiveSnapshot {
  LogRow row;     ///< the cycle as logged (cycle_time_s included)
  int dof = 0;
  LivePush push;  ///< the push the plant feels now (body -1: none)
  bool paused = false;
  double ee_gamma_override = -1.0, posture_gamma_override = -1.0;  ///< -1: the mode decides
  double posture_stiffness = 0.0;
  std::uint64_t overruns = 0;  ///< of the real-time period so far
};

struct LiveChannelSettings {
  int decimation = 16;  ///< a snapshot every this many cycles
  std::size_t command_capacity = 256;
  std::size_t snapshot_capacity = 64;
  /// A push lasts this long after its last update unless renewed (a front end that vanishes
  /// mid-drag stops pushing) [s].
  double push_hold_s = 0.5;
};

class LiveChannel {
public:
  explicit LiveChannel(const LiveChannelSettings& settings = {})
      : settings_(settings), commands_(settings.command_capacity), snapshots_(settings.snapshot_capacity) {}

  // ---- front-end side
  /// Queues a command for the loop; false when the queue is full (the loop is not reading it).
  bool send(const LiveCommand& command) {
    const std::lock_guard<std::mutex> lock(send_mutex_);
    return commands_.try_push(command);
  }
  /// The oldest snapshot not read yet (one reader thread).
  bool next_snapshot(LiveSnapshot& out) noexcept { return snapshots_.try_pop(out); }

  // ---- loop side (the control thread)
  bool receive(LiveCommand& out) noexcept { return commands_.try_pop(out); }
  bool due(std::uint64_t cycle) const noexcept {
    return settings_.decimation <= 1 || cycle % static_cast<std::uint64_t>(settings_.decimation) == 0;
  }
  /// False (counted as dropped) when the reader has not kept up and the queue is full.
  bool publish(const LiveSnapshot& snapshot) noexcept {
    const bool queued = snapshots_.try_push(snapshot);
    (queued ? published_ : dropped_).fetch_add(1, std::memory_order_relaxed);
    return queued;
  }

  // ---- any thread
  const LiveChannelSettings& settings() const { return settings_; }
  std::uint64_t published() const { return published_.load(std::memory_order_relaxed); }
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

private:
  LiveChannelSettings settings_;
  std::mutex send_mutex_;
  SpscRing<LiveCommand> commands_;
  SpscRing<LiveSnapshot> snapshots_;
  std::atomic<std::uint64_t> published_{0}, dropped_{0};
};

}  // namespace phri
