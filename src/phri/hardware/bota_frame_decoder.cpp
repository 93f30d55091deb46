#include <phri/hardware/bota_frame_decoder.hpp>

#include <algorithm>
#include <cmath>

namespace phri {

bool BotaFrameDecoder::push(std::uint8_t byte) noexcept {
  ++counters_.bytes;
  bool delivered = false;
  if (held_) {
    held_ = false;
    if (byte == kBotaFrameHeader) {
      delivered = evaluate(held_frame_);  // confirmed; the header byte then starts the next frame
    } else {
      ++counters_.unconfirmed;
      skip(kBotaFrameBytes);
    }
  }
  if (fill_ == 0 && byte != kBotaFrameHeader) {
    skip(1);
    return delivered;
  }
  buffer_[fill_++] = byte;
  if (fill_ == kBotaFrameBytes) delivered = check_candidate() || delivered;
  return delivered;
}

bool BotaFrameDecoder::check_candidate() noexcept {
  const std::span<const std::uint8_t, kBotaDataBytes> data(buffer_.data() + 1, kBotaDataBytes);
  const std::uint16_t sent = static_cast<std::uint16_t>(buffer_[1 + kBotaDataBytes] | (buffer_[2 + kBotaDataBytes] << 8));
  if (crc16_x25(data) != sent) {
    ++counters_.crc_errors;
    rescan_after_crc_error();
    return false;
  }
  fill_ = 0;
  const BotaFrame frame = parse_bota_data(data);
  if (!in_sync_) {
    held_ = true;
    held_frame_ = frame;
    return false;
  }
  return evaluate(frame);
}

bool BotaFrameDecoder::evaluate(const BotaFrame& frame) noexcept {
  in_sync_ = true;
  skipping_ = false;
  if ((frame.status & settings_.status_error_mask) != 0) {
    ++counters_.status_errors;
    return false;
  }
  const bool wrench_ok = std::all_of(frame.wrench.begin(), frame.wrench.end(), [&](float v) {
    return std::isfinite(v) && std::fabs(v) <= settings_.max_abs_wrench;
  });
  if (!wrench_ok || !std::isfinite(frame.temperature)) {
    ++counters_.invalid_values;
    return false;
  }
  ++counters_.frames_ok;
  frame_ = frame;
  return true;
}

void BotaFrameDecoder::skip(std::uint64_t count) noexcept {
  if (!skipping_) ++counters_.resyncs;
  skipping_ = true;
  in_sync_ = false;
  counters_.bytes_skipped += count;
}

// The candidate's header was false (or its frame damaged): drop it and the bytes up to the next
// 0xAA inside the candidate, which may be the true start of a frame.
void BotaFrameDecoder::rescan_after_crc_error() noexcept {
  const auto next = std::find(buffer_.begin() + 1, buffer_.end(), kBotaFrameHeader);
  const auto dropped = static_cast<std::size_t>(next - buffer_.begin());
  skip(dropped);
  std::copy(next, buffer_.end(), buffer_.begin());
  fill_ = kBotaFrameBytes - dropped;
}

void BotaFrameDecoder::reset() noexcept {
  if (buffered() > 0) skip(buffered());  // the counters still account for every byte
  fill_ = 0;
  held_ = false;
  in_sync_ = false;
  skipping_ = false;
}

}  // namespace phri
