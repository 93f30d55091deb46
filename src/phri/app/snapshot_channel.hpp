#pragma once
// phri::SnapshotChannel: one observer's lock-free hand-off of the run (RunOptions::observers): every
// `decimation`-th cycle the loop publishes a LiveSnapshot (the cycle's log row and what the loop
// knows beside it) into a ring allocated at construction; the observer's own thread takes them with
// next_snapshot(). The loop never blocks, locks or allocates: a full ring drops the snapshot
// (counted), so a slow observer loses snapshots and never slows the cycle. One writer (the control
// thread), one reader. The dashboard is one observer (its LiveChannel holds one), a recorder or a
// bridge another.
#include <phri/config/log_row.hpp>
#include <phri/core/spsc_ring.hpp>

#include <Eigen/Core>

#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>

namespace phri {

/// A force on a link of the simulated arm (drag-to-push).
struct LivePush {
  int body = -1;  ///< model body (the child of joint `body`); -1: none
  Eigen::Vector3d point_local = Eigen::Vector3d::Zero();  ///< application point, body frame [m]
  Eigen::Vector3d force_world = Eigen::Vector3d::Zero();  ///< [N], world axes
};

/// Most links whose power-and-force-limiting ratio a snapshot carries.
inline constexpr int kLiveMaxContactLinks = 16;

struct LiveSnapshot {
  LogRow row;     ///< the cycle as logged (cycle_time_s included)
  int dof = 0;
  LivePush push;  ///< the push the plant feels now (body -1: none)
  bool paused = false;
  double ee_gamma_override = -1.0, posture_gamma_override = -1.0;  ///< -1: the mode decides
  double posture_stiffness = 0.0;
  std::uint64_t overruns = 0;  ///< of the real-time period so far
  /// v / v_max of each monitored link (RunOptions::body_regions; PowerForceLimitMonitor's order).
  std::array<double, kLiveMaxContactLinks> contact_ratio{};
  int contact_links = 0;
};

struct SnapshotChannelSettings {
  int decimation = 16;         ///< a snapshot every this many cycles (16: ~60 Hz at 1 kHz)
  std::size_t capacity = 64;   ///< snapshots waiting for the observer
};

class SnapshotChannel {
public:
  explicit SnapshotChannel(const SnapshotChannelSettings& settings = {})
      : settings_(settings), snapshots_(settings.capacity) {}

  // ---- loop side (the control thread)
  bool due(std::uint64_t cycle) const noexcept {
    return settings_.decimation <= 1 || cycle % static_cast<std::uint64_t>(settings_.decimation) == 0;
  }
  /// False (counted as dropped) when the observer has not kept up and the ring is full.
  bool publish(const LiveSnapshot& snapshot) noexcept {
    const bool queued = snapshots_.try_push(snapshot);
    (queued ? published_ : dropped_).fetch_add(1, std::memory_order_relaxed);
    return queued;
  }

  // ---- observer side (one reader thread)
  /// The oldest snapshot not read yet.
  bool next_snapshot(LiveSnapshot& out) noexcept { return snapshots_.try_pop(out); }

  // ---- any thread
  const SnapshotChannelSettings& settings() const { return settings_; }
  std::uint64_t published() const { return published_.load(std::memory_order_relaxed); }
  std::uint64_t dropped() const { return dropped_.load(std::memory_order_relaxed); }

private:
  SnapshotChannelSettings settings_;
  SpscRing<LiveSnapshot> snapshots_;
  std::atomic<std::uint64_t> published_{0}, dropped_{0};
};

}  // namespace phri
