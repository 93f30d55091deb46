#pragma once
// phri::McapWriter: an MCAP file (https://mcap.dev/spec, major version 0) written in one pass, as
// rosbag2's MCAP storage writes it: schemas and channels at the start of the data section, messages
// in zstd-compressed chunks each followed by its message indexes, then Data End, a summary (schemas,
// channels, statistics, chunk indexes, metadata indexes) with its offsets, the footer and the magic.
//
//   McapWriter mcap("run.mcap", {.profile = "ros2", .library = "phri 0.9"});
//   const auto schema = mcap.add_schema("sensor_msgs/msg/JointState", "ros2msg", definition_text);
//   const auto channel = mcap.add_channel(schema, "/joint_states", "cdr", {{"offered_qos_profiles", qos}});
//   mcap.write(channel, log_time_ns, bytes, size);   // buffered in the open chunk
//   mcap.close();                                    // last chunk, summary, footer
//
// Nothing is lost on a crash or a signal beyond the open chunk: each chunk is written with its
// indexes and flushed to the kernel as soon as it holds `chunk_bytes` of records, so a file whose
// writer was killed reads (McapReader) up to its last complete chunk. Not thread-safe: one writer
// thread (the logger's) owns it; it allocates only while its buffers grow to the largest chunk.
#include <cstdint>
#include <cstdio>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace phri {

struct McapWriterOptions {
  std::string profile;                   ///< "ros2": the ros2 profile (cdr messages, ros2msg schemas)
  std::string library;                   ///< written into the header (who wrote the file)
  std::size_t chunk_bytes = 1 << 20;     ///< uncompressed records per chunk before it is written
  int zstd_level = 3;                    ///< chunk compression (1 fastest .. 19); 0: chunks stored uncompressed
};

struct McapWriterStats {
  std::uint64_t messages = 0;
  std::uint64_t chunks = 0;
  std::uint64_t uncompressed_bytes = 0;  ///< chunk records before compression
  std::uint64_t file_bytes = 0;          ///< written so far
};

class McapWriter {
public:
  using Metadata = std::map<std::string, std::string>;

  /// Creates (truncates) `path` and writes the magic and the header. IoError when it cannot.
  McapWriter(const std::string& path, McapWriterOptions options);
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// A schema (ids from 1), written at once into the data section.
  std::uint16_t add_schema(std::string_view name, std::string_view encoding, std::string_view data);
  /// A channel on `schema_id` (ids from 0), written at once into the data section.
  std::uint16_t add_channel(std::uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                            const Metadata& metadata);
  /// A Metadata record (outside chunks), indexed in the summary.
  void add_metadata(std::string_view name, const Metadata& metadata);

  /// One message; its sequence is the channel's count so far. Publish time = log time.
  void write(std::uint16_t channel_id, std::uint64_t log_time_ns, const std::uint8_t* data, std::size_t size);
  /// Writes the open chunk (if any) with its message indexes and flushes the file to the kernel.
  void flush();
  /// flush(), then Data End, the summary section, the summary offsets, the footer and the magic.
  /// Idempotent; the destructor calls it. IoError if a write failed at any point.
  void close();

  const McapWriterStats& stats() const { return stats_; }

private:
  struct ChannelInfo {
    std::uint16_t id = 0;
    std::vector<std::uint8_t> record;  // the whole Channel record, repeated in the summary
    std::uint64_t count = 0;           // messages so far (the Statistics record's per-channel count)
    std::vector<std::uint8_t> index;   // this chunk's (log_time, offset) pairs
  };
  struct ChunkIndex {
    std::uint64_t start_time = 0, end_time = 0, offset = 0, length = 0, index_length = 0;
    std::uint64_t compressed_size = 0, uncompressed_size = 0;
    std::vector<std::pair<std::uint16_t, std::uint64_t>> index_offsets;
  };
  struct MetadataIndex {
    std::uint64_t offset = 0, length = 0;
    std::string name;
  };

  void emit(const std::uint8_t* data, std::size_t size);
  void emit(const std::vector<std::uint8_t>& bytes) { emit(bytes.data(), bytes.size()); }
  void write_chunk();
  std::vector<std::uint8_t> summary_section(std::uint64_t start, std::vector<std::uint8_t>& offsets) const;

  std::string path_;
  McapWriterOptions options_;
  std::FILE* file_ = nullptr;
  bool failed_ = false;
  bool closed_ = false;
  std::uint32_t data_crc_ = 0;       // CRC-32 of every byte written before Data End
  std::vector<std::vector<std::uint8_t>> schema_records_;
  std::vector<ChannelInfo> channels_;
  std::vector<ChunkIndex> chunk_indexes_;
  std::vector<MetadataIndex> metadata_indexes_;
  std::vector<std::uint8_t> chunk_;       // the open chunk's records, uncompressed
  std::vector<std::uint8_t> compressed_;  // scratch for its compression
  std::vector<std::uint8_t> record_;      // scratch for one record
  std::uint64_t chunk_start_time_ = 0, chunk_end_time_ = 0;
  std::uint64_t file_start_time_ = 0, file_end_time_ = 0;
  McapWriterStats stats_;
};

}  // namespace phri
