#pragma once
// phri::LiveChannel: the run loop's lock-free hand-off to a live front end (the dashboard,
// dashboard/dashboard_server.hpp), which is also one of the run's observers. Two queues, both
// allocated at construction:
//   commands   front end -> loop: events and gain changes (posted to the FSM, the gamepad's
//              path), pushes on the simulated arm, run / pause / single-step;
//   snapshots  loop -> front end: its SnapshotChannel (app/snapshot_channel.hpp), every
//              `decimation`-th cycle (16: ~60 Hz at 1 kHz) the cycle's log row and what the loop
//              knows beside it (the push it applies, paused or not).
// The loop side never blocks, locks or allocates: a full snapshot queue drops the snapshot (the
// front end shows the next one), an empty command queue is no news. The front-end side may call
// send() from several threads (they are serialised by a mutex the loop never takes); one thread
// reads the snapshots.
#include <phri/config/event.hpp>
#include <phri/app/live_gain.hpp>
#include <phri/app/snapshot_channel.hpp>
#include <phri/core/spsc_ring.hpp>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <atomic>
#include <cstdint>
#include <mutex>

namespace phri {

/// An end-effector target from outside (the ROS 2 bridge's /phri/target_pose), checked by its
/// sender (finite, unit quaternion, within reach and rate); the FSM takes it while it holds a pose.
struct LiveTarget {
  Eigen::Vector3d position = Eigen::Vector3d::Zero();             ///< world [m]
  Eigen::Quaterniond orientation = Eigen::Quaterniond::Identity();  ///< unit
};

struct LiveCommand {
  enum class Kind : std::uint8_t { kEvent, kGain, kPush, kRelease, kRun, kPause, kStep, kTarget };
  Kind kind = Kind::kEvent;
  Event event = Event::kStop;  ///< kEvent
  LiveTarget target;           ///< kTarget
  GainRequest gain;            ///< kGain
  LivePush push;               ///< kPush: replaces the push applied so far
  int steps = 1;               ///< kStep: cycles to run before pausing again
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
      : settings_(settings),
        commands_(settings.command_capacity),
        snapshots_(SnapshotChannelSettings{settings.decimation, settings.snapshot_capacity}) {}

  // ---- front-end side
  /// Queues a command for the loop; false when the queue is full (the loop is not reading it).
  bool send(const LiveCommand& command) {
    const std::lock_guard<std::mutex> lock(send_mutex_);
    return commands_.try_push(command);
  }
  /// The oldest snapshot not read yet (one reader thread).
  bool next_snapshot(LiveSnapshot& out) noexcept { return snapshots_.next_snapshot(out); }

  // ---- loop side (the control thread)
  bool receive(LiveCommand& out) noexcept { return commands_.try_pop(out); }
  bool due(std::uint64_t cycle) const noexcept { return snapshots_.due(cycle); }
  /// False (counted as dropped) when the reader has not kept up and the queue is full.
  bool publish(const LiveSnapshot& snapshot) noexcept { return snapshots_.publish(snapshot); }
  /// The front end's snapshots: the run loop feeds it as one of its observers.
  SnapshotChannel& snapshots() noexcept { return snapshots_; }

  // ---- any thread
  const LiveChannelSettings& settings() const { return settings_; }
  std::uint64_t published() const { return snapshots_.published(); }
  std::uint64_t dropped() const { return snapshots_.dropped(); }

private:
  LiveChannelSettings settings_;
  std::mutex send_mutex_;
  SpscRing<LiveCommand> commands_;
  SnapshotChannel snapshots_;
};

}  // namespace phri
