#pragma once
// phri::BotaEmulator: a fake SensONE on a pseudo-terminal, for tests and for trying the driver
// without the sensor (as FakeRobot stands in for the arm). It answers the start-up handshake the
// way Bota's example expects ('C', 'c,...', 'f,...', 'R', each with "r,0,<letter>,0"), streams
// frames at a set rate, and injects faults on request: damaged frames, dropped bytes, garbage,
// bursts, non-finite values, error status bits, stalls, and a disconnect (the pty is closed and,
// after a pause, a new one is opened behind the same device path, as udev's by-id links do).
//
// Frame k (k = 0, 1, ... over the emulator's life, one per slot, faults included) carries the
// sensor timestamp k and exactly representable values (expected_frame(k)), chosen so that no byte
// after the header is 0xAA: a test can then predict the decoder's counters exactly.
#include <phri/hardware/bota_protocol.hpp>

#include <atomic>
#include <cstdint>
#include <deque>
#include <mutex>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace phri {

enum class BotaFault {
  kCorruptCrc,   ///< one frame with its CRC wrong
  kFlippedByte,  ///< one frame with data byte `param` (0..33) changed
  kDroppedByte,  ///< one frame with data byte `param` left out (36 bytes sent)
  kTruncated,    ///< one frame cut after `param` bytes (1..36)
  kGarbage,      ///< `param` random bytes (0xAA among them), then the slot's frame intact
  kFrameBurst,   ///< `param` intact frames in one write, no pacing
  kNonFinite,    ///< one frame with a correct CRC and a NaN (`param` even) or an infinity (odd) in it
  kErrorStatus,  ///< one frame with a correct CRC and status bit `param` (0..15) set
  kStall,        ///< nothing sent for `param` ms (no catching up afterwards)
  kDisconnect,   ///< the pty is closed; `param` ms later a new one boots behind the same path
};

struct BotaEmulatorSettings {
  /// Frames per second while streaming: 100, the rate of the sinc filter 512 the driver sets
  /// (`f,512,0,0,1`, docs/hardware.md); tests stream faster to count more frames.
  double rate_hz = 100.0;
  bool streaming_at_start = true;  ///< true: already in run mode (left by an earlier session); false: booting
  BotaSensorConfig expected;     ///< the 'c' and 'f' commands it acknowledges (others get no answer)
  std::uint32_t seed = 1;        ///< garbage bytes
};

struct BotaEmulatorStats {
  std::uint64_t opens = 0;          ///< pseudo-terminals opened (1 + reopenings)
  std::uint64_t run_mode_acks = 0;  ///< 'R' acknowledged (completed handshakes)
  std::uint64_t slots = 0;          ///< frame slots used (good or faulty): the next timestamp
  std::uint64_t good_frames = 0;    ///< intact frames sent
  std::uint64_t stream_bytes = 0;   ///< bytes of frames and faults sent in run mode
  std::uint64_t faults_applied = 0;
  std::uint64_t faults_pending = 0;
  std::uint64_t garbage_headers = 0;  ///< 0xAA bytes among the garbage sent (each a false candidate)
  std::uint64_t write_overflows = 0;  ///< bytes the pty had no room for (the reader was not reading)
  bool run_mode = false;
};

class BotaEmulator {
public:
  explicit BotaEmulator(BotaEmulatorSettings settings = {});
  ~BotaEmulator();
  BotaEmulator(const BotaEmulator&) = delete;
  BotaEmulator& operator=(const BotaEmulator&) = delete;

  /// The path to open: a symbolic link to the current pty's slave, stable across reopenings.
  const std::string& device() const { return link_path_; }
  /// Queues a fault; faults apply in order, one per frame slot.
  void inject(BotaFault fault, int param = 0);
  /// Pauses (false) or resumes (true) the stream in run mode (the handshake is always answered).
  void set_streaming(bool streaming);
  BotaEmulatorStats stats() const;
  /// Every intact frame sent, in order (copies: for tests, off any real-time path).
  std::vector<BotaFrame> good_frames() const;

  /// The intact frame of slot k.
  static BotaFrame expected_frame(std::uint64_t k);

private:
  struct Pending {
    BotaFault fault;
    int param;
  };
  void run();
  void open_pty();
  void close_pty();
  void serve_commands();
  void handle_command(const std::string& command);
  void send_slot();
  void apply_fault(const Pending& fault, const BotaFrame& frame);
  void send_garbage(int length);
  void send_burst(int count);
  void send(const std::uint8_t* bytes, std::size_t count, bool stream);
  void send_text(const std::string& text) { send(reinterpret_cast<const std::uint8_t*>(text.data()), text.size(), false); }
  void send_good(const BotaFrame& frame);
  bool pop_fault(Pending& out);

  const BotaEmulatorSettings settings_;
  std::string dir_;
  std::string link_path_;

  // emulator thread's own
  int master_fd_ = -1;
  int slave_fd_ = -1;  // held open so the pty lives (and stays raw) while no reader has it open
  std::string command_buffer_;
  bool booting_ = false;
  std::mt19937 random_;

  mutable std::mutex emit_mutex_;  // one slot's emission (record, write, count) is atomic to observers
  mutable std::mutex mutex_;       // guards everything below
  std::deque<Pending> faults_;
  std::vector<BotaFrame> good_frames_;
  BotaEmulatorStats stats_;
  bool streaming_ = true;

  std::atomic<bool> stopping_{false};
  std::thread thread_;
};

}  // namespace phri
