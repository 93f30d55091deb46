#pragma once
// phri::SerialPort: a serial device (or a pseudo-terminal) in raw mode, 8N1, no flow control,
// opened non-blocking so that every read and write is bounded by a timeout (poll()): the thread
// that owns it can always notice a stop request or a silent device.
//
// Opening throws phri::IoError naming the device and, for the usual causes, what to do (a missing
// device, no permission: the user's group dialout). After that nothing throws: reads and writes
// return a status, and a hang-up, EOF or error is kClosed, after which the port is useless.
#include <cstddef>
#include <cstdint>
#include <string>
#include <string_view>

namespace phri {

enum class SerialStatus {
  kData,     ///< bytes were read or written
  kTimeout,  ///< nothing within the timeout
  kClosed,   ///< hang-up, end of file or an I/O error: the device is gone
};

struct SerialResult {
  SerialStatus status = SerialStatus::kTimeout;
  std::size_t bytes = 0;
  int error = 0;  ///< errno of a kClosed caused by an error (0 for a hang-up or EOF)
};

class SerialPort {
public:
  /// Opens `device` (O_NOCTTY: never our controlling terminal) at `baud` bits/s (a standard
  /// rate: 9600 ... 460800); throws IoError "device: reason".
  SerialPort(const std::string& device, int baud);
  ~SerialPort();
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  const std::string& device() const { return device_; }

  /// Reads what is there (up to `capacity` bytes), waiting up to `timeout_ms` for the first byte.
  SerialResult read_some(std::uint8_t* buffer, std::size_t capacity, int timeout_ms) noexcept;
  /// Writes all of `bytes` within `timeout_ms` in total (kTimeout: only part was written).
  SerialResult write_all(std::string_view bytes, int timeout_ms) noexcept;
  /// Drops bytes received and not read yet.
  void discard_input() noexcept;

private:
  std::string device_;
  int fd_ = -1;
};

/// The termios speed constant for a rate in bits/s; 0 when the rate is not a standard one.
unsigned int serial_speed_constant(int baud) noexcept;

}  // namespace phri
