#pragma once
// phri::BotaSensOne: the Bota SensONE F/T sensor over its serial streaming protocol. A reader
// thread owns the port: it opens it, runs the start-up handshake (config mode 'C', communication
// 'c,...', filter 'f,...', run mode 'R', each acknowledged within a timeout), decodes the stream
// (BotaFrameDecoder) and hands each good wrench to the control cycle through a TripleBuffer. The
// cycle calls latest() or read_into(): wait-free, no allocation, no system call but the clock; it
// never touches the port.
//
// What reaches the cycle is only ever a frame that passed the decoder's checks (sync, CRC, status
// bits, finite values in range). On a hang-up, EOF, read error or a silence longer than
// reconnect_after_silence_s, the thread publishes "disconnected" (valid = false), closes the port
// and retries opening it with exponential back-off, forever, until stop(). stop() (and the
// destructor) returns within about max(poll slice, write timeout), 0.1 s.
#include <phri/core/spsc_ring.hpp>
#include <phri/core/triple_buffer.hpp>
#include <phri/hardware/bota_frame_decoder.hpp>
#include <phri/hardware/bota_protocol.hpp>
#include <phri/robot/robot_state.hpp>

#include <array>
#include <atomic>
#include <chrono>
#include <condition_variable>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

namespace phri {

class SerialPort;

struct BotaSensOneSettings {
  std::string device = "/dev/ttyUSB0";  ///< better a stable name: /dev/serial/by-id/usb-...
  BotaSensorConfig sensor;              ///< sent with 'c' and 'f' at every connection
  BotaDecoderSettings decoder;
  double ack_timeout_s = 1.0;           ///< per command
  int config_mode_attempts = 3;         ///< 'C' is sent again when unanswered (a sensor still booting)
  double reconnect_after_silence_s = 1.0;  ///< no good frame this long while connected: reconnect
  double retry_initial_s = 0.05;        ///< back-off between connection attempts, doubling...
  double retry_max_s = 2.0;             ///< ...up to this
  double stale_after_s = 0.05;          ///< read_into(): older data is not valid (5 periods at 100 Hz)
  std::size_t history_capacity = 0;     ///< > 0: every published sample also queued for pop_history()
};

/// What the reader thread hands to the cycle: plain data, copied whole.
struct WrenchSample {
  std::array<double, 6> wrench{};  ///< Fx, Fy, Fz [N], Mx, My, Mz [N.m], sensor frame; the last good frame
  bool valid = false;              ///< false before the first good frame of a connection, and when disconnected
  bool connected = false;          ///< the handshake succeeded and the port has not failed since
  std::uint32_t sequence = 0;      ///< good frames published so far (all connections): +1 per new wrench
  std::int64_t host_stamp_ns = 0;  ///< steady_clock time the frame's bytes were read [ns]
  std::uint32_t sensor_timestamp = 0;  ///< the sensor's own clock, raw
  float temperature = 0.0f;
  std::uint16_t status = 0;        ///< the frame's status word (0 unless the mask lets bits through)

  /// Seconds since the frame was read, by the steady clock `now_ns`.
  double age_s(std::int64_t now_ns) const { return 1e-9 * static_cast<double>(now_ns - host_stamp_ns); }
};

struct BotaSensOneCounters {
  BotaDecoderCounters decoder;      ///< all connections together
  std::uint64_t connections = 0;    ///< handshakes that succeeded
  std::uint64_t disconnections = 0; ///< streams that ended (hang-up, error, silence)
  std::uint64_t open_failures = 0;
  std::uint64_t handshake_failures = 0;
  std::uint64_t silences = 0;       ///< reconnections for lack of good frames
  std::uint64_t published = 0;      ///< good wrenches handed over
  std::uint64_t history_dropped = 0;  ///< samples the history ring had no room for
};

class BotaSensOne {
public:
  using Clock = std::chrono::steady_clock;

  /// Starts the reader thread; never throws for the device (a missing device is retried and
  /// reported by last_error()).
  explicit BotaSensOne(BotaSensOneSettings settings);
  ~BotaSensOne();
  BotaSensOne(const BotaSensOne&) = delete;
  BotaSensOne& operator=(const BotaSensOne&) = delete;

  // ---- the control cycle (one consumer thread): wait-free, no allocation
  /// The newest sample (the reference stays valid until the next latest() or read_into()).
  const WrenchSample& latest() noexcept { return handoff_.latest(); }
  /// Fills the F/T fields of a RobotState: wrench_sensor (the last good wrench), and wrench with
  /// valid = a good frame no older than stale_after_s, sequence, stamp_s = host steady-clock
  /// seconds of the frame (the hardware backend maps it to its robot time).
  void read_into(RobotState& state) noexcept;

  // ---- any thread (not for the cycle: they lock a mutex)
  BotaSensOneCounters counters() const;
  std::string last_error() const;  ///< why the latest connection attempt or stream ended ("" if none)
  /// The next sample of the history (settings.history_capacity > 0), one consumer thread only.
  bool pop_history(WrenchSample& out) noexcept { return history_ && history_->try_pop(out); }

  void stop();  ///< ends the reader thread (idempotent); the latest sample stays readable
  const BotaSensOneSettings& settings() const { return settings_; }

private:
  void run();
  bool connect(std::unique_ptr<SerialPort>& port);
  bool handshake(SerialPort& port);
  bool command(SerialPort& port, const std::string& text, char ack_letter);
  void stream(SerialPort& port);
  void feed(const std::uint8_t* bytes, std::size_t count, Clock::time_point received, Clock::time_point& last_good);
  void publish_frame(const BotaFrame& frame, Clock::time_point received);
  void publish_link(bool connected);
  void wait_before_retry(double seconds);
  void note(const std::string& error);
  void update_counters();
  bool stopping() const { return stopping_.load(std::memory_order_relaxed); }

  const BotaSensOneSettings settings_;
  TripleBuffer<WrenchSample> handoff_;
  std::unique_ptr<SpscRing<WrenchSample>> history_;

  // reader thread's own
  BotaFrameDecoder decoder_;
  WrenchSample last_published_;
  std::string after_ack_;  // bytes that followed the 'R' acknowledgement: the first frames
  BotaSensOneCounters thread_counters_;

  mutable std::mutex mutex_;  // guards counters_ and last_error_
  BotaSensOneCounters counters_;
  std::string last_error_;

  std::atomic<bool> stopping_{false};
  std::mutex wake_mutex_;
  std::condition_variable wake_;
  std::thread thread_;
};

}  // namespace phri
