#include <phri/core/mcap_reader.hpp>

#include <phri/core/error.hpp>
#include <phri/core/mcap_format.hpp>

#include <zlib.h>
#include <zstd.h>

#include <cerrno>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string_view>
#include <vector>

namespace phri {
namespace {

using mcap::Op;

// A bounded little-endian cursor over one record's content; reading past its end throws.
class Fields {
public:
  Fields(const std::uint8_t* data, std::size_t size, const std::string& path, std::uint64_t offset)
      : data_(data), size_(size), path_(path), offset_(offset) {}
  template <class T>
  T get() {
    need(sizeof(T));
    T value;
    std::memcpy(&value, data_ + at_, sizeof(T));
    at_ += sizeof(T);
    return value;
  }
  std::string_view bytes(std::size_t n) {
    need(n);
    const std::string_view out(reinterpret_cast<const char*>(data_ + at_), n);
    at_ += n;
    return out;
  }
  std::string string() { return std::string(bytes(get<std::uint32_t>())); }
  std::map<std::string, std::string> string_map() {
    const auto length = get<std::uint32_t>();
    need(length);
    Fields entries(data_ + at_, length, path_, offset_ + at_);
    at_ += length;
    std::map<std::string, std::string> out;
    while (entries.at_ < entries.size_) {
      std::string key = entries.string();
      out[std::move(key)] = entries.string();
    }
    return out;
  }
  const std::uint8_t* here() const { return data_ + at_; }
  std::size_t left() const { return size_ - at_; }
  [[noreturn]] void fail(const std::string& why) const {
    throw IoError(path_, "byte " + std::to_string(offset_ + at_) + ": " + why);
  }

private:
  void need(std::size_t n) const {
    if (n > size_ - at_) fail("a record's field runs past its end (corrupt file)");
  }
  const std::uint8_t* data_;
  std::size_t size_;
  const std::string& path_;
  std::uint64_t offset_;
  std::size_t at_ = 0;
};

struct ReadState {
  const std::string& path;
  const McapVisitor& visitor;
  McapReadSummary& summary;
  std::map<std::uint16_t, McapSchema> schemas;
  std::map<std::uint16_t, McapChannel> channels;
  std::vector<std::uint8_t> chunk;
};

void read_records(ReadState& s, const std::uint8_t* data, std::size_t size, std::uint64_t base, bool in_chunk);

void on_schema(ReadState& s, Fields& f) {
  McapSchema schema;
  schema.id = f.get<std::uint16_t>();
  schema.name = f.string();
  schema.encoding = f.string();
  schema.data = f.string();
  if (schema.id == 0) return;  // invalid by the spec: ignored
  const McapSchema& stored = s.schemas[schema.id] = std::move(schema);
  for (auto& [id, channel] : s.channels) {
    if (channel.schema_id == stored.id) channel.schema = &stored;
  }
  if (s.visitor.on_schema) s.visitor.on_schema(stored);
}

void on_channel(ReadState& s, Fields& f) {
  McapChannel channel;
  channel.id = f.get<std::uint16_t>();
  channel.schema_id = f.get<std::uint16_t>();
  channel.topic = f.string();
  channel.message_encoding = f.string();
  channel.metadata = f.string_map();
  const auto schema = s.schemas.find(channel.schema_id);
  if (schema != s.schemas.end()) channel.schema = &schema->second;
  const bool known = s.channels.count(channel.id) > 0;
  const McapChannel& stored = s.channels[channel.id] = std::move(channel);
  if (!known && s.visitor.on_channel) s.visitor.on_channel(stored);
}

void on_message(ReadState& s, Fields& f) {
  const auto channel_id = f.get<std::uint16_t>();
  McapMessage message;
  message.sequence = f.get<std::uint32_t>();
  message.log_time_ns = f.get<std::uint64_t>();
  message.publish_time_ns = f.get<std::uint64_t>();
  message.data = f.here();
  message.size = f.left();
  const auto channel = s.channels.find(channel_id);
  if (channel == s.channels.end()) f.fail("a message on channel " + std::to_string(channel_id) + ", never declared");
  ++s.summary.messages;
  if (s.visitor.on_message) s.visitor.on_message(channel->second, message);
}

void on_chunk(ReadState& s, Fields& f) {
  f.get<std::uint64_t>();  // message start time
  f.get<std::uint64_t>();  // message end time
  const auto uncompressed_size = f.get<std::uint64_t>();
  const auto crc = f.get<std::uint32_t>();
  const std::string compression = f.string();
  const auto records_size = f.get<std::uint64_t>();
  if (records_size > f.left()) f.fail("a chunk's records run past the chunk");
  const std::uint8_t* records = f.here();
  std::vector<std::uint8_t> plain;
  if (compression == "zstd") {
    plain.resize(uncompressed_size);
    const std::size_t n = ZSTD_decompress(plain.data(), plain.size(), records, records_size);
    if (ZSTD_isError(n) || n != uncompressed_size) f.fail("a zstd chunk that does not decompress to its stated size");
    records = plain.data();
  } else if (compression.empty()) {
    if (records_size != uncompressed_size) f.fail("a stored chunk whose size is not its uncompressed size");
  } else {
    f.fail("a chunk compressed with '" + compression + "' (phri reads zstd and uncompressed chunks)");
  }
  if (crc != 0 && static_cast<std::uint32_t>(::crc32(0, records, static_cast<uInt>(uncompressed_size))) != crc) {
    f.fail("a chunk whose CRC does not match its records (corrupt file)");
  }
  ++s.summary.chunks;
  read_records(s, records, uncompressed_size, 0, true);
}

// Records from `data`; outside a chunk a record cut short ends the read (truncated file).
void read_records(ReadState& s, const std::uint8_t* data, std::size_t size, std::uint64_t base, bool in_chunk) {
  std::size_t at = 0;
  while (at < size) {
    if (size - at < mcap::kRecordPrefixBytes) break;
    const auto op = static_cast<Op>(data[at]);
    std::uint64_t length;
    std::memcpy(&length, data + at + 1, 8);
    if (length > size - at - mcap::kRecordPrefixBytes) break;
    Fields f(data + at + mcap::kRecordPrefixBytes, length, s.path, base + at + mcap::kRecordPrefixBytes);
    if (op == Op::kSchema) on_schema(s, f);
    if (op == Op::kChannel) on_channel(s, f);
    if (op == Op::kMessage) on_message(s, f);
    if (op == Op::kChunk && !in_chunk) on_chunk(s, f);
    if (op == Op::kMetadata && !in_chunk && s.visitor.on_metadata) {
      const std::string name = f.string();
      s.visitor.on_metadata(name, f.string_map());
    }
    at += mcap::kRecordPrefixBytes + length;
    if (!in_chunk) s.summary.valid_bytes = base + at;
    if (op == Op::kDataEnd && !in_chunk) {
      s.summary.complete = true;  // the summary and footer follow; checked below
      return;
    }
  }
  if (in_chunk && at != size) throw IoError(s.path, "a chunk whose records do not fill it (corrupt file)");
  if (!in_chunk) s.summary.truncated = true;
}

}  // namespace

McapReadSummary read_mcap(const std::string& path, const McapVisitor& visitor) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw IoError(path, std::string("cannot open: ") + std::strerror(errno));
  const std::vector<std::uint8_t> file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  McapReadSummary summary;
  summary.bytes = file.size();
  const std::size_t magic = mcap::kMagic.size();
  if (file.size() < magic || std::memcmp(file.data(), mcap::kMagic.data(), magic) != 0) {
    throw IoError(path, "not an MCAP file (its first bytes are not the MCAP magic)");
  }
  ReadState state{path, visitor, summary, {}, {}, {}};
  // The header is the first record: its profile and library.
  if (file.size() >= magic + mcap::kRecordPrefixBytes && file[magic] == static_cast<std::uint8_t>(Op::kHeader)) {
    std::uint64_t length;
    std::memcpy(&length, file.data() + magic + 1, 8);
    if (length <= file.size() - magic - mcap::kRecordPrefixBytes) {
      Fields f(file.data() + magic + mcap::kRecordPrefixBytes, length, path, magic + mcap::kRecordPrefixBytes);
      summary.profile = f.string();
      summary.library = f.string();
    }
  }
  read_records(state, file.data() + magic, file.size() - magic, magic, false);
  if (summary.complete) {
    summary.complete = file.size() >= 2 * magic &&
                       std::memcmp(file.data() + file.size() - magic, mcap::kMagic.data(), magic) == 0;
  }
  return summary;
}

}  // namespace phri
