#pragma once
// phri::read_mcap: an MCAP file (https://mcap.dev/spec) read from its start, record by record, as a
// streaming reader does: schemas, channels, metadata and every message (chunks decompressed, zstd or
// stored, their CRC checked), in file order. A file cut short (a writer killed by SIGKILL, a full
// disk) is read up to its last complete record and reported as truncated, not refused; a file that
// is not MCAP, a corrupt chunk or an unknown compression throws IoError naming the file and the
// byte offset.
//
//   McapVisitor v;
//   v.on_message = [&](const McapChannel& c, const McapMessage& m) { ... m.data, m.size ... };
//   const McapReadSummary s = read_mcap("run.mcap", v);   // s.truncated, s.messages, s.profile
#include <cstdint>
#include <functional>
#include <map>
#include <string>

namespace phri {

struct McapSchema {
  std::uint16_t id = 0;
  std::string name, encoding, data;
};

struct McapChannel {
  std::uint16_t id = 0;
  std::uint16_t schema_id = 0;
  std::string topic, message_encoding;
  std::map<std::string, std::string> metadata;
  const McapSchema* schema = nullptr;  ///< the schema it names (nullptr: none)
};

struct McapMessage {
  std::uint32_t sequence = 0;
  std::uint64_t log_time_ns = 0;
  std::uint64_t publish_time_ns = 0;
  const std::uint8_t* data = nullptr;  ///< valid during the callback only
  std::size_t size = 0;
};

struct McapVisitor {
  std::function<void(const McapSchema&)> on_schema;
  std::function<void(const McapChannel&)> on_channel;
  std::function<void(const std::string& name, const std::map<std::string, std::string>&)> on_metadata;
  std::function<void(const McapChannel&, const McapMessage&)> on_message;
};

struct McapReadSummary {
  std::string profile, library;
  std::uint64_t messages = 0;
  std::uint64_t chunks = 0;
  std::uint64_t bytes = 0;     ///< file size
  bool complete = false;       ///< Data End, footer and closing magic all present
  bool truncated = false;      ///< the file ends inside a record: read up to the last complete one
  std::uint64_t valid_bytes = 0;  ///< bytes up to the end of the last complete record
};

/// Reads `path` from the start (above). Callbacks left empty are not called.
McapReadSummary read_mcap(const std::string& path, const McapVisitor& visitor);

}  // namespace phri
