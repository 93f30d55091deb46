#pragma once
// The Bota Systems SensONE serial protocol (variant BFT-SENS-SER-M8): the frame layout, its CRC and
// the configuration commands, in one place. Source of every number here: Bota's serial example
// (bota_serial_example.py, as copied in github.com/tud-phi/bota_ft_sensors @ 6218269d), transcribed
// into the project's notes on the sensor; the byte order (little-endian) is inferred from that
// example's struct.unpack on x86, not stated by Bota.
//
// Frame: 0xAA, then 34 data bytes, then the CRC-16/X-25 of the 34 data bytes (2 bytes, low first):
//   offset  0  uint16  status
//   offset  2  float32 Fx, 6 Fy, 10 Fz [N]; 14 Mx, 18 My, 22 Mz [N.m]   (units inferred)
//   offset 26  uint32  timestamp (units not stated by Bota)
//   offset 30  float32 temperature (presumably degrees C)
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>

namespace phri {

inline constexpr std::uint8_t kBotaFrameHeader = 0xAA;
inline constexpr std::size_t kBotaDataBytes = 34;
inline constexpr std::size_t kBotaCrcBytes = 2;
inline constexpr std::size_t kBotaFrameBytes = 1 + kBotaDataBytes + kBotaCrcBytes;  // 37
inline constexpr int kBotaBaudRate = 460800;
inline constexpr int kBotaBaudConfig460800 = 4;  // the 'c' command's code: 0 9600, 1 57600, 2 115200, 3 230400, 4 460800
/// Sample period per sinc-filter length [s per tap]: sinc 512 -> 0.01 s (100 Hz).
inline constexpr double kBotaSecondsPerSincTap = 0.00001953125;

/// One decoded frame, as the sensor sent it.
struct BotaFrame {
  std::uint16_t status = 0;
  std::array<float, 6> wrench{};  ///< Fx, Fy, Fz [N], Mx, My, Mz [N.m], sensor frame
  std::uint32_t timestamp = 0;    ///< sensor clock, raw
  float temperature = 0.0f;
  bool operator==(const BotaFrame&) const = default;
};

/// CRC-16/X-25: poly 0x1021 reflected, init 0xFFFF, final xor 0xFFFF ("123456789" -> 0x906E).
std::uint16_t crc16_x25(std::span<const std::uint8_t> bytes) noexcept;

/// The 37 bytes the sensor sends for `frame` (header, data, CRC). The emulator and tests use it.
std::array<std::uint8_t, kBotaFrameBytes> encode_bota_frame(const BotaFrame& frame) noexcept;
/// Parses the 34 data bytes (no checks: the decoder checks CRC and contents).
BotaFrame parse_bota_data(std::span<const std::uint8_t, kBotaDataBytes> data) noexcept;

/// The sensor's configuration, as the 'c' and 'f' commands set it (defaults: Bota's example).
struct BotaSensorConfig {
  int temperature_compensation = 0;  ///< 0 disabled ("recommended" by Bota), 1 enabled
  int use_calibration = 1;           ///< 1 calibration matrix active (N, N.m), 0 raw
  int data_format = 0;               ///< 0 binary frames (the only format this driver reads), 1 CSV
  int baud_config = kBotaBaudConfig460800;
  int sinc_length = 512;             ///< sets the sample period (kBotaSecondsPerSincTap x length)
  int chop_enable = 0;
  int fast_enable = 0;
  int fir_disable = 1;
  double sample_period_s() const { return kBotaSecondsPerSincTap * sinc_length; }
};

// Commands are plain ASCII with no terminator; each is answered by "r,0,<letter>,0".
inline constexpr const char* kBotaConfigModeCommand = "C";
inline constexpr const char* kBotaRunModeCommand = "R";
std::string bota_communication_command(const BotaSensorConfig& config);  ///< "c,<temp>,<calib>,<format>,<baud>"
std::string bota_filter_command(const BotaSensorConfig& config);         ///< "f,<sinc>,<chop>,<fast>,<fir_disable>"
/// The acknowledgement of the command whose first letter is `command` ('C', 'c', 'f', 'R').
std::string bota_ack(char command);

}  // namespace phri
