#include <phri/hardware/bota_protocol.hpp>

#include <cstring>

namespace phri {
namespace {

// Little-endian on the wire whatever the host: assembled byte by byte.
void put_u16(std::uint8_t* p, std::uint16_t v) {
  p[0] = static_cast<std::uint8_t>(v & 0xFF);
  p[1] = static_cast<std::uint8_t>(v >> 8);
}
void put_u32(std::uint8_t* p, std::uint32_t v) {
  for (int i = 0; i < 4; ++i) p[i] = static_cast<std::uint8_t>((v >> (8 * i)) & 0xFF);
}
void put_f32(std::uint8_t* p, float v) {
  std::uint32_t bits = 0;
  std::memcpy(&bits, &v, sizeof bits);
  put_u32(p, bits);
}
std::uint16_t get_u16(const std::uint8_t* p) { return static_cast<std::uint16_t>(p[0] | (p[1] << 8)); }
std::uint32_t get_u32(const std::uint8_t* p) {
  return static_cast<std::uint32_t>(p[0]) | (static_cast<std::uint32_t>(p[1]) << 8) |
         (static_cast<std::uint32_t>(p[2]) << 16) | (static_cast<std::uint32_t>(p[3]) << 24);
}
float get_f32(const std::uint8_t* p) {
  const std::uint32_t bits = get_u32(p);
  float v = 0.0f;
  std::memcpy(&v, &bits, sizeof v);
  return v;
}

constexpr std::size_t kStatusOffset = 0;
constexpr std::size_t kWrenchOffset = 2;
constexpr std::size_t kTimestampOffset = 26;
constexpr std::size_t kTemperatureOffset = 30;

}  // namespace

std::uint16_t crc16_x25(std::span<const std::uint8_t> bytes) noexcept {
  std::uint16_t crc = 0xFFFF;
  for (const std::uint8_t byte : bytes) {
    crc ^= byte;
    for (int bit = 0; bit < 8; ++bit) crc = (crc & 1) ? static_cast<std::uint16_t>((crc >> 1) ^ 0x8408) : static_cast<std::uint16_t>(crc >> 1);
  }
  return static_cast<std::uint16_t>(crc ^ 0xFFFF);  // 0x8408: 0x1021 bit-reversed (reflected algorithm)
}

std::array<std::uint8_t, kBotaFrameBytes> encode_bota_frame(const BotaFrame& frame) noexcept {
  std::array<std::uint8_t, kBotaFrameBytes> bytes{};
  bytes[0] = kBotaFrameHeader;
  std::uint8_t* data = bytes.data() + 1;
  put_u16(data + kStatusOffset, frame.status);
  for (std::size_t i = 0; i < 6; ++i) put_f32(data + kWrenchOffset + 4 * i, frame.wrench[i]);
  put_u32(data + kTimestampOffset, frame.timestamp);
  put_f32(data + kTemperatureOffset, frame.temperature);
  put_u16(data + kBotaDataBytes, crc16_x25({data, kBotaDataBytes}));
  return bytes;
}

BotaFrame parse_bota_data(std::span<const std::uint8_t, kBotaDataBytes> data) noexcept {
  BotaFrame frame;
  const std::uint8_t* p = data.data();
  frame.status = get_u16(p + kStatusOffset);
  for (std::size_t i = 0; i < 6; ++i) frame.wrench[i] = get_f32(p + kWrenchOffset + 4 * i);
  frame.timestamp = get_u32(p + kTimestampOffset);
  frame.temperature = get_f32(p + kTemperatureOffset);
  return frame;
}

std::string bota_communication_command(const BotaSensorConfig& c) {
  return "c," + std::to_string(c.temperature_compensation) + "," + std::to_string(c.use_calibration) + "," +
         std::to_string(c.data_format) + "," + std::to_string(c.baud_config);
}

std::string bota_filter_command(const BotaSensorConfig& c) {
  return "f," + std::to_string(c.sinc_length) + "," + std::to_string(c.chop_enable) + "," +
         std::to_string(c.fast_enable) + "," + std::to_string(c.fir_disable);
}

std::string bota_ack(char command) { return std::string("r,0,") + command + ",0"; }

}  // namespace phri
