#pragma once
// The MCAP format's constants and its field encodings (https://mcap.dev/spec: little-endian integers,
// strings and byte arrays with a uint32 length, records as opcode + uint64 length + content), shared by
// McapWriter and McapReader.
#include <array>
#include <cstdint>
#include <cstring>
#include <string_view>
#include <vector>

namespace phri::mcap {

inline constexpr std::array<std::uint8_t, 8> kMagic = {0x89, 'M', 'C', 'A', 'P', 0x30, '\r', '\n'};

enum class Op : std::uint8_t {
  kHeader = 0x01,
  kFooter = 0x02,
  kSchema = 0x03,
  kChannel = 0x04,
  kMessage = 0x05,
  kChunk = 0x06,
  kMessageIndex = 0x07,
  kChunkIndex = 0x08,
  kStatistics = 0x0B,
  kMetadata = 0x0C,
  kMetadataIndex = 0x0D,
  kSummaryOffset = 0x0E,
  kDataEnd = 0x0F,
};

/// Opcode + uint64 length + content.
inline constexpr std::size_t kRecordPrefixBytes = 9;

template <class T>
void put(std::vector<std::uint8_t>& out, T value) {
  std::uint8_t bytes[sizeof(T)];
  std::memcpy(bytes, &value, sizeof(T));  // little-endian machine (static_assert in cdr.hpp)
  out.insert(out.end(), bytes, bytes + sizeof(T));
}
inline void put_string(std::vector<std::uint8_t>& out, std::string_view text) {
  put(out, static_cast<std::uint32_t>(text.size()));
  out.insert(out.end(), text.begin(), text.end());
}
/// Starts a record: its opcode and a length to be patched by end_record.
inline std::size_t begin_record(std::vector<std::uint8_t>& out, Op op) {
  out.push_back(static_cast<std::uint8_t>(op));
  put(out, std::uint64_t{0});
  return out.size();
}
inline void end_record(std::vector<std::uint8_t>& out, std::size_t content_start) {
  const std::uint64_t length = out.size() - content_start;
  std::memcpy(out.data() + content_start - 8, &length, 8);
}
/// Starts a uint32-length-prefixed field (a map or an array), patched by end_prefixed.
inline std::size_t begin_prefixed(std::vector<std::uint8_t>& out) {
  put(out, std::uint32_t{0});
  return out.size();
}
inline void end_prefixed(std::vector<std::uint8_t>& out, std::size_t start) {
  const auto length = static_cast<std::uint32_t>(out.size() - start);
  std::memcpy(out.data() + start - 4, &length, 4);
}

}  // namespace phri::mcap
