#pragma once
// phri::BotaFrameDecoder: bytes from the SensONE's serial stream in, checked frames out. Pure (no
// I/O, no clock, no allocation), fed one byte at a time, so every fault is testable byte by byte.
//
// Sync: a frame starts with 0xAA, which may also occur inside data, CRC bytes or line garbage.
// A candidate (0xAA + 36 bytes) whose CRC fails is not thrown away whole: the search for the next
// 0xAA restarts inside it, so a dropped or truncated frame costs that frame only, not the next one.
// A random candidate passes a 16-bit CRC once in 65536, so after lost sync (any skipped byte) a
// CRC-good frame is held until the next byte is seen to be 0xAA (the next frame's header: one
// sample period of delay, only for the first frame after a resync). In sync, a frame is delivered
// as soon as its CRC is checked.
//
// Checks on a CRC-good frame, in order: status bits (see BotaDecoderSettings), then the values:
// all seven floats finite and each wrench component within max_abs_wrench.
//
// Counters (every byte fed is either buffered, part of a checked frame, or skipped):
//   bytes = 37 x (frames_ok + status_errors + invalid_values) + bytes_skipped + bytes buffered
#include <phri/hardware/bota_protocol.hpp>

#include <array>
#include <cstdint>

namespace phri {

struct BotaDecoderSettings {
  /// A frame whose status has any of these bits set is rejected. Bota does not document the
  /// status word (its example reads it and ignores it). Assumed here: 0 means healthy, and any set
  /// bit may flag a fault (saturation, ADC, calibration...), so by default every set bit rejects
  /// the frame. If the real sensor sets informational bits while healthy (watch status_errors
  /// and the raw status in `phri ft-monitor`), clear those bits from the mask in the settings.
  std::uint16_t status_error_mask = 0xFFFF;
  /// Larger components [N or N.m] are rejected: far beyond any 6-axis sensor of this size (the
  /// SensONE's range is not in our notes), it catches garbage floats such as 1e30, not overloads.
  float max_abs_wrench = 1.0e5f;
};

struct BotaDecoderCounters {
  std::uint64_t bytes = 0;           ///< bytes fed
  std::uint64_t frames_ok = 0;       ///< frames delivered
  std::uint64_t crc_errors = 0;      ///< candidates (0xAA + 36 bytes) whose CRC did not match
  std::uint64_t status_errors = 0;   ///< CRC-good frames rejected for their status bits
  std::uint64_t invalid_values = 0;  ///< CRC-good frames with a non-finite or out-of-range value
  std::uint64_t unconfirmed = 0;     ///< CRC-good frames after a resync not followed by 0xAA (skipped)
  std::uint64_t resyncs = 0;         ///< runs of skipped bytes (each a loss of sync)
  std::uint64_t bytes_skipped = 0;   ///< bytes discarded while searching for a frame
  bool operator==(const BotaDecoderCounters&) const = default;
};

class BotaFrameDecoder {
public:
  explicit BotaFrameDecoder(BotaDecoderSettings settings = {}) : settings_(settings) {}

  /// Feeds one byte; true when it completed a good frame, then in frame() until the next true.
  bool push(std::uint8_t byte) noexcept;
  const BotaFrame& frame() const noexcept { return frame_; }
  const BotaDecoderCounters& counters() const noexcept { return counters_; }
  const BotaDecoderSettings& settings() const noexcept { return settings_; }
  /// Forgets any partial or held frame (counted as skipped) and the sync, after a reconnection.
  void reset() noexcept;
  /// Bytes held: a partial candidate, or a frame waiting for its confirming header.
  std::size_t buffered() const noexcept { return fill_ + (held_ ? kBotaFrameBytes : 0); }

private:
  bool check_candidate() noexcept;  // buffer full: CRC, then hold or evaluate
  bool evaluate(const BotaFrame& frame) noexcept;  // status and values; true if delivered
  void skip(std::uint64_t count) noexcept;
  void rescan_after_crc_error() noexcept;

  BotaDecoderSettings settings_;
  BotaDecoderCounters counters_;
  std::array<std::uint8_t, kBotaFrameBytes> buffer_{};
  std::size_t fill_ = 0;
  bool in_sync_ = false;   // the last frame was checked and nothing skipped since
  bool skipping_ = false;  // inside a run of skipped bytes
  bool held_ = false;      // held_frame_ waits for the next byte to be 0xAA
  BotaFrame held_frame_;
  BotaFrame frame_;
};

}  // namespace phri
