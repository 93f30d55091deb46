#pragma once
// phri::CdrWriter / CdrReader: the plain little-endian CDR that ROS 2 puts on the wire and in its bags
// (OMG CDR as rmw_fastrtps and rmw_cyclonedds serialise: a 4-byte encapsulation header 00 01 00 00,
// then each primitive aligned to its own size counted from the end of that header; strings as a
// uint32 length including the terminating NUL, then the bytes and the NUL; sequences as a uint32
// count, then the elements). Enough for the messages phri logs (app/mcap_log.hpp); no
// optional members, no XCDR2.
#include <phri/core/error.hpp>

#include <bit>
#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace phri {

static_assert(std::endian::native == std::endian::little, "CdrWriter copies little-endian bytes as they are");

class CdrWriter {
public:
  /// Starts a message in `out` (cleared; its capacity is kept, so a reused buffer does not allocate).
  explicit CdrWriter(std::vector<std::uint8_t>& out) : out_(out) {
    out_.clear();
    const std::uint8_t header[4] = {0x00, 0x01, 0x00, 0x00};  // CDR_LE, no options
    out_.insert(out_.end(), header, header + 4);
  }

  template <class T>
  void put(T value) {
    static_assert(std::is_arithmetic_v<T>);
    align(sizeof(T));
    std::uint8_t bytes[sizeof(T)];
    std::memcpy(bytes, &value, sizeof(T));
    out_.insert(out_.end(), bytes, bytes + sizeof(T));
  }
  void put_string(std::string_view text) {
    put(static_cast<std::uint32_t>(text.size() + 1));
    out_.insert(out_.end(), text.begin(), text.end());
    out_.push_back(0);
  }
  void put_sequence(const double* values, std::size_t count) {
    put(static_cast<std::uint32_t>(count));
    for (std::size_t i = 0; i < count; ++i) put(values[i]);
  }

private:
  void align(std::size_t size) {
    const std::size_t offset = out_.size() - 4;
    out_.resize(out_.size() + (size - offset % size) % size, 0);
  }
  std::vector<std::uint8_t>& out_;
};

/// Reads what a CdrWriter wrote; a read past the end or a header that is not CDR_LE throws IoError
/// naming `what` (the topic or file being decoded).
class CdrReader {
public:
  CdrReader(const std::uint8_t* data, std::size_t size, std::string what) : data_(data), size_(size), what_(std::move(what)) {
    if (size < 4 || data[0] != 0x00 || data[1] != 0x01) fail("not a little-endian CDR message");
    offset_ = 4;
  }

  template <class T>
  T get() {
    static_assert(std::is_arithmetic_v<T>);
    offset_ += (sizeof(T) - (offset_ - 4) % sizeof(T)) % sizeof(T);
    need(sizeof(T));
    T value;
    std::memcpy(&value, data_ + offset_, sizeof(T));
    offset_ += sizeof(T);
    return value;
  }
  std::string_view get_string() {
    const auto length = get<std::uint32_t>();
    need(length);
    if (length == 0 || data_[offset_ + length - 1] != 0) fail("a string without its terminating NUL");
    const std::string_view text(reinterpret_cast<const char*>(data_ + offset_), length - 1);
    offset_ += length;
    return text;
  }
  std::size_t remaining() const { return size_ - offset_; }
  const std::string& what() const { return what_; }

private:
  void need(std::size_t bytes) const {
    if (bytes > size_ - offset_) fail("message ends early (" + std::to_string(size_) + " bytes)");
  }
  [[noreturn]] void fail(const std::string& why) const { throw IoError(what_, why); }

  const std::uint8_t* data_;
  std::size_t size_;
  std::size_t offset_ = 0;
  std::string what_;
};

}  // namespace phri
