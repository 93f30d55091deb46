#include <phri/hardware/bota_emulator.hpp>

#include <phri/core/error.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <limits>
#include <poll.h>
#include <termios.h>
#include <unistd.h>

namespace phri {
namespace {

using Clock = std::chrono::steady_clock;
using Bytes = std::vector<std::uint8_t>;

constexpr auto kBootTextPeriod = std::chrono::milliseconds(100);

// The frame's bytes, nudged until no byte after the header is 0xAA (so that the only sync
// candidates a test stream holds are the ones the test put there): a wrench component holding one
// moves by 1/32, otherwise (CRC, temperature) the temperature by 1/16. Timestamps are clean by
// construction and non-finite values and status bits never contain 0xAA.
Bytes encode_clean(BotaFrame& frame) {
  for (;;) {
    const auto bytes = encode_bota_frame(frame);
    const auto header = std::find(bytes.begin() + 1, bytes.end(), kBotaFrameHeader);
    if (header == bytes.end()) return Bytes(bytes.begin(), bytes.end());
    const auto data_offset = static_cast<std::size_t>(header - bytes.begin()) - 1;
    if (data_offset >= 2 && data_offset < 26) {
      frame.wrench[(data_offset - 2) / 4] += 0.03125f;
    } else {
      frame.temperature += 0.0625f;
    }
  }
}

// Timestamps in base 128, one digit per byte: increasing with k, and no byte is ever 0xAA.
std::uint32_t timestamp_of(std::uint64_t k) {
  std::uint32_t t = 0;
  for (int digit = 0; digit < 4; ++digit) t |= static_cast<std::uint32_t>((k >> (7 * digit)) & 0x7F) << (8 * digit);
  return t;
}

// Changes `byte` by `mask`, by another bit when that would make it a header.
std::uint8_t flip(std::uint8_t byte, std::uint8_t mask) {
  const std::uint8_t flipped = byte ^ mask;
  return flipped == kBotaFrameHeader ? static_cast<std::uint8_t>(byte ^ (mask << 1 | 1)) : flipped;
}

void sleep_unless(const std::atomic<bool>& stopping, int ms) {
  const auto end = Clock::now() + std::chrono::milliseconds(ms);
  while (!stopping.load() && Clock::now() < end) std::this_thread::sleep_for(std::chrono::milliseconds(2));
}

}  // namespace

BotaFrame BotaEmulator::expected_frame(std::uint64_t k) {
  BotaFrame frame;
  // A bounded, slowly varying wrench a hand could give (a triangle over 4096 frames, within +-5 N and
  // +-0.1 N.m); tests compare a decoded frame with expected_frame(k) bit for bit.
  const float m = static_cast<float>(k % 4096 < 2048 ? k % 4096 : 4096 - k % 4096) / 2048.0f;  // 0 .. 1 .. 0
  frame.wrench = {10.0f * m - 5.0f, -4.0f * m, 3.0f + 2.0f * m, 0.125f * m - 0.0625f, -0.05f, 0.2f * m - 0.1f};
  frame.timestamp = timestamp_of(k);
  frame.temperature = 25.0f;
  encode_clean(frame);
  return frame;
}

BotaEmulator::BotaEmulator(BotaEmulatorSettings settings) : settings_(settings), random_(settings.seed) {
  char dir_template[] = "/tmp/phri_bota_XXXXXX";
  if (::mkdtemp(dir_template) == nullptr) throw IoError(dir_template, std::string("mkdtemp: ") + std::strerror(errno));
  dir_ = dir_template;
  link_path_ = dir_ + "/ttyBota";
  open_pty();
  booting_ = !settings_.streaming_at_start;
  stats_.run_mode = settings_.streaming_at_start;
  thread_ = std::thread([this] { run(); });
}

BotaEmulator::~BotaEmulator() {
  stopping_.store(true);
  if (thread_.joinable()) thread_.join();
  close_pty();
  ::rmdir(dir_.c_str());
}

void BotaEmulator::open_pty() {
  master_fd_ = ::posix_openpt(O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (master_fd_ < 0 || ::grantpt(master_fd_) != 0 || ::unlockpt(master_fd_) != 0)
    throw IoError("/dev/ptmx", std::string("cannot create a pseudo-terminal: ") + std::strerror(errno));
  char slave[128];  // ptsname_r: two emulators in one process (tests) must not share ptsname's buffer
  if (::ptsname_r(master_fd_, slave, sizeof slave) != 0) throw IoError("/dev/ptmx", "ptsname_r failed");
  slave_fd_ = ::open(slave, O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC);
  if (slave_fd_ < 0) throw IoError(slave, std::string("cannot open: ") + std::strerror(errno));
  termios tio{};
  ::tcgetattr(slave_fd_, &tio);
  ::cfmakeraw(&tio);  // raw before any byte flows: no echo of our frames back to us
  ::tcsetattr(slave_fd_, TCSANOW, &tio);
  ::unlink(link_path_.c_str());
  if (::symlink(slave, link_path_.c_str()) != 0) throw IoError(link_path_, std::string("symlink: ") + std::strerror(errno));
  command_buffer_.clear();
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.opens;
}

void BotaEmulator::close_pty() {
  ::unlink(link_path_.c_str());
  if (master_fd_ >= 0) ::close(master_fd_);  // the reader's end hangs up
  if (slave_fd_ >= 0) ::close(slave_fd_);
  master_fd_ = slave_fd_ = -1;
}

void BotaEmulator::inject(BotaFault fault, int param) {
  std::lock_guard<std::mutex> lock(mutex_);
  faults_.push_back({fault, param});
  stats_.faults_pending = faults_.size();
}

void BotaEmulator::set_streaming(bool streaming) {
  std::lock_guard<std::mutex> lock(mutex_);
  streaming_ = streaming;
}

BotaEmulatorStats BotaEmulator::stats() const {
  std::lock_guard<std::mutex> emitting(emit_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  return stats_;
}

std::vector<BotaFrame> BotaEmulator::good_frames() const {
  std::lock_guard<std::mutex> emitting(emit_mutex_);
  std::lock_guard<std::mutex> lock(mutex_);
  return good_frames_;
}

bool BotaEmulator::pop_fault(Pending& out) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (faults_.empty()) return false;
  out = faults_.front();
  faults_.pop_front();
  stats_.faults_pending = faults_.size();
  ++stats_.faults_applied;
  return true;
}

// ---------------------------------------------------------------------------- emulator thread

void BotaEmulator::run() {
  const auto period = std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(1.0 / settings_.rate_hz));
  Clock::time_point next_frame = Clock::now();
  Clock::time_point next_boot_text = Clock::now();
  while (!stopping_.load()) {
    serve_commands();
    bool streaming = false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      streaming = stats_.run_mode && streaming_;
    }
    const Clock::time_point now = Clock::now();
    if (booting_ && now >= next_boot_text) {
      send_text("App Init\r\n");
      next_boot_text = now + kBootTextPeriod;
    }
    if (!streaming) {
      next_frame = now;
    } else if (now >= next_frame) {
      {
        std::lock_guard<std::mutex> emitting(emit_mutex_);
        send_slot();
      }
      next_frame += period;
      // Behind after a stall, a disconnect or a preemption: go on from now, no catching up.
      if (Clock::now() - next_frame > 10 * period) next_frame = Clock::now();
    }
  }
}

void BotaEmulator::serve_commands() {
  if (master_fd_ < 0) return;
  pollfd pfd{master_fd_, POLLIN, 0};
  if (::poll(&pfd, 1, 1) <= 0 || !(pfd.revents & POLLIN)) return;
  char chunk[256];
  const ssize_t n = ::read(master_fd_, chunk, sizeof chunk);
  if (n <= 0) return;
  command_buffer_.append(chunk, static_cast<std::size_t>(n));
  // No terminator: 'C' and 'R' are one letter; 'c' and 'f' have four fields, the last one digit.
  while (!command_buffer_.empty()) {
    const char first = command_buffer_[0];
    std::size_t length = 1;
    if (first == 'c' || first == 'f') {
      std::size_t commas = 0, i = 0;
      for (; i < command_buffer_.size() && commas < 4; ++i) commas += command_buffer_[i] == ',';
      if (commas < 4 || i >= command_buffer_.size()) return;  // incomplete: wait for more
      length = i + 1;
    }
    handle_command(command_buffer_.substr(0, length));
    command_buffer_.erase(0, length);
  }
}

void BotaEmulator::handle_command(const std::string& command) {
  bool acknowledge = false;
  if (command == kBotaConfigModeCommand) {
    booting_ = false;
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.run_mode = false;
    acknowledge = true;
  } else if (command == kBotaRunModeCommand) {
    acknowledge = true;
  } else {
    acknowledge = command == bota_communication_command(settings_.expected) ||
                  command == bota_filter_command(settings_.expected);
  }
  if (!acknowledge) return;
  send_text(bota_ack(command[0]));
  if (command == kBotaRunModeCommand) {
    std::lock_guard<std::mutex> lock(mutex_);
    stats_.run_mode = true;
    ++stats_.run_mode_acks;
  }
}

void BotaEmulator::send(const std::uint8_t* bytes, std::size_t count, bool stream) {
  std::size_t written = 0;
  if (master_fd_ >= 0) {
    const ssize_t n = ::write(master_fd_, bytes, count);
    written = n > 0 ? static_cast<std::size_t>(n) : 0;
  }
  std::lock_guard<std::mutex> lock(mutex_);
  if (stream) stats_.stream_bytes += written;
  stats_.write_overflows += count - written;
}

// A good frame is on record before its bytes leave: the driver may publish it before write()
// returns here (a test that compares what was published with what was sent raced on that). The
// whole slot is one step for observers (emit_mutex_, held by run()): stats() and good_frames()
// never see a frame recorded but not yet written.
void BotaEmulator::send_good(const BotaFrame& frame) {
  BotaFrame copy = frame;
  const Bytes bytes = encode_clean(copy);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    good_frames_.push_back(copy);
    ++stats_.good_frames;
  }
  send(bytes.data(), bytes.size(), true);
}

void BotaEmulator::send_slot() {
  std::uint64_t k = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    k = stats_.slots;
  }
  const BotaFrame frame = expected_frame(k);
  Pending fault{};
  if (pop_fault(fault)) {
    apply_fault(fault, frame);
    return;
  }
  send_good(frame);
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.slots;
}

// `length` random bytes with at least one 0xAA: each 0xAA starts a false frame candidate.
void BotaEmulator::send_garbage(int length) {
  Bytes bytes(static_cast<std::size_t>(std::max(1, length)));
  std::uniform_int_distribution<int> byte(0, 255);
  for (std::uint8_t& b : bytes) b = static_cast<std::uint8_t>(byte(random_));
  bytes[std::uniform_int_distribution<std::size_t>(0, bytes.size() - 1)(random_)] = kBotaFrameHeader;
  send(bytes.data(), bytes.size(), true);
  std::lock_guard<std::mutex> lock(mutex_);
  stats_.garbage_headers += static_cast<std::uint64_t>(std::count(bytes.begin(), bytes.end(), kBotaFrameHeader));
}

// `count` intact frames of consecutive slots in one write.
void BotaEmulator::send_burst(int count) {
  std::uint64_t k = 0;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    k = stats_.slots;
  }
  Bytes bytes;
  std::vector<BotaFrame> frames;
  for (int i = 0; i < std::max(1, count); ++i) {
    BotaFrame frame = expected_frame(k + static_cast<std::uint64_t>(i));
    const Bytes one = encode_clean(frame);
    bytes.insert(bytes.end(), one.begin(), one.end());
    frames.push_back(frame);
  }
  {
    std::lock_guard<std::mutex> lock(mutex_);  // on record before the bytes leave (send_good)
    good_frames_.insert(good_frames_.end(), frames.begin(), frames.end());
    stats_.good_frames += frames.size();
    stats_.slots += frames.size();
  }
  send(bytes.data(), bytes.size(), true);
}

void BotaEmulator::apply_fault(const Pending& f, const BotaFrame& frame) {
  BotaFrame bad = frame;
  Bytes bytes;
  bool uses_slot = true;
  switch (f.fault) {
    case BotaFault::kCorruptCrc:
      bytes = encode_clean(bad);
      bytes[kBotaFrameBytes - 2] = flip(bytes[kBotaFrameBytes - 2], 0x01);
      break;
    case BotaFault::kFlippedByte:
      bytes = encode_clean(bad);
      bytes[1 + static_cast<std::size_t>(std::clamp(f.param, 0, 33))] = flip(bytes[1 + static_cast<std::size_t>(std::clamp(f.param, 0, 33))], 0x10);
      break;
    case BotaFault::kDroppedByte:
      bytes = encode_clean(bad);
      bytes.erase(bytes.begin() + 1 + std::clamp(f.param, 0, 33));
      break;
    case BotaFault::kTruncated:
      bytes = encode_clean(bad);
      bytes.resize(static_cast<std::size_t>(std::clamp(f.param, 1, 36)));
      break;
    case BotaFault::kGarbage:
      send_garbage(f.param);
      send_good(frame);
      break;
    case BotaFault::kFrameBurst:
      send_burst(f.param);
      return;  // the burst counted its own slots
    case BotaFault::kNonFinite:
      bad.wrench[static_cast<std::size_t>(std::abs(f.param) % 6)] =
          f.param % 2 == 0 ? std::numeric_limits<float>::quiet_NaN() : std::numeric_limits<float>::infinity();
      bytes = encode_clean(bad);
      break;
    case BotaFault::kErrorStatus:
      bad.status = static_cast<std::uint16_t>(1u << std::clamp(f.param, 0, 15));
      bytes = encode_clean(bad);
      break;
    case BotaFault::kStall:
      sleep_unless(stopping_, f.param);
      uses_slot = false;
      break;
    case BotaFault::kDisconnect:
      close_pty();
      sleep_unless(stopping_, f.param);
      open_pty();
      booting_ = true;  // a sensor powered up again says "App Init" until configured
      {
        std::lock_guard<std::mutex> lock(mutex_);
        stats_.run_mode = false;
      }
      uses_slot = false;
      break;
  }
  if (!bytes.empty()) send(bytes.data(), bytes.size(), true);
  if (!uses_slot) return;
  std::lock_guard<std::mutex> lock(mutex_);
  ++stats_.slots;
}

}  // namespace phri
