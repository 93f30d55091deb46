#include <phri/core/mcap_writer.hpp>

#include <phri/core/error.hpp>
#include <phri/core/mcap_format.hpp>

#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>

namespace phri {

using mcap::begin_prefixed;
using mcap::begin_record;
using mcap::end_prefixed;
using mcap::end_record;
using mcap::Op;
using mcap::put;
using mcap::put_string;

namespace {

std::uint32_t crc32_of(std::uint32_t crc, const std::uint8_t* data, std::size_t size) {
  while (size > 0) {  // zlib's crc32 takes a uInt length
    const auto part = static_cast<uInt>(std::min<std::size_t>(size, 1u << 30));
    crc = static_cast<std::uint32_t>(::crc32(crc, data, part));
    data += part;
    size -= part;
  }
  return crc;
}

void put_map(std::vector<std::uint8_t>& out, const McapWriter::Metadata& map) {
  const std::size_t start = begin_prefixed(out);
  for (const auto& [key, value] : map) {
    put_string(out, key);
    put_string(out, value);
  }
  end_prefixed(out, start);
}

}  // namespace

McapWriter::McapWriter(const std::string& path, McapWriterOptions options) : path_(path), options_(std::move(options)) {
  if (options_.zstd_level < 0 || options_.zstd_level > ZSTD_maxCLevel()) {
    throw ConfigError(path, "zstd_level", "0 (stored) or 1 to " + std::to_string(ZSTD_maxCLevel()));
  }
  file_ = std::fopen(path.c_str(), "wb");
  if (file_ == nullptr) throw IoError(path, std::string("cannot create the MCAP file: ") + std::strerror(errno));
  emit(mcap::kMagic.data(), mcap::kMagic.size());
  record_.clear();
  const std::size_t start = begin_record(record_, Op::kHeader);
  put_string(record_, options_.profile);
  put_string(record_, options_.library);
  end_record(record_, start);
  emit(record_);
  chunk_.reserve(options_.chunk_bytes + (64 << 10));
}

McapWriter::~McapWriter() {
  try {
    close();
  } catch (const Error&) {  // a destructor reports nothing; close() called explicitly throws
  }
}

void McapWriter::emit(const std::uint8_t* data, std::size_t size) {
  if (failed_) return;
  if (std::fwrite(data, 1, size, file_) != size) {
    failed_ = true;
    return;
  }
  data_crc_ = crc32_of(data_crc_, data, size);
  stats_.file_bytes += size;
}

std::uint16_t McapWriter::add_schema(std::string_view name, std::string_view encoding, std::string_view data) {
  const auto id = static_cast<std::uint16_t>(schema_records_.size() + 1);
  std::vector<std::uint8_t> record;
  const std::size_t start = begin_record(record, Op::kSchema);
  put(record, id);
  put_string(record, name);
  put_string(record, encoding);
  put_string(record, data);  // uint32-prefixed bytes
  end_record(record, start);
  emit(record);
  schema_records_.push_back(std::move(record));
  return id;
}

std::uint16_t McapWriter::add_channel(std::uint16_t schema_id, std::string_view topic, std::string_view message_encoding,
                                      const Metadata& metadata) {
  ChannelInfo channel;
  channel.id = static_cast<std::uint16_t>(channels_.size());
  const std::size_t start = begin_record(channel.record, Op::kChannel);
  put(channel.record, channel.id);
  put(channel.record, schema_id);
  put_string(channel.record, topic);
  put_string(channel.record, message_encoding);
  put_map(channel.record, metadata);
  end_record(channel.record, start);
  emit(channel.record);
  channels_.push_back(std::move(channel));
  return channels_.back().id;
}

void McapWriter::add_metadata(std::string_view name, const Metadata& metadata) {
  flush();  // metadata records stand outside chunks
  record_.clear();
  const std::size_t start = begin_record(record_, Op::kMetadata);
  put_string(record_, name);
  put_map(record_, metadata);
  end_record(record_, start);
  metadata_indexes_.push_back({stats_.file_bytes, record_.size(), std::string(name)});
  emit(record_);
}

void McapWriter::write(std::uint16_t channel_id, std::uint64_t log_time_ns, const std::uint8_t* data, std::size_t size) {
  if (closed_) throw ArgumentError("McapWriter::write: the file is closed");
  if (channel_id >= channels_.size()) throw ArgumentError("McapWriter::write: unknown channel " + std::to_string(channel_id));
  ChannelInfo& channel = channels_[channel_id];
  if (chunk_.empty()) chunk_start_time_ = log_time_ns;
  chunk_start_time_ = std::min(chunk_start_time_, log_time_ns);
  chunk_end_time_ = std::max(chunk_end_time_, log_time_ns);
  put(channel.index, log_time_ns);
  put(channel.index, static_cast<std::uint64_t>(chunk_.size()));
  const std::size_t start = begin_record(chunk_, Op::kMessage);
  put(chunk_, channel_id);
  put(chunk_, static_cast<std::uint32_t>(channel.count));
  put(chunk_, log_time_ns);
  put(chunk_, log_time_ns);
  chunk_.insert(chunk_.end(), data, data + size);
  end_record(chunk_, start);
  if (stats_.messages == 0) file_start_time_ = log_time_ns;
  file_start_time_ = std::min(file_start_time_, log_time_ns);
  file_end_time_ = std::max(file_end_time_, log_time_ns);
  ++channel.count;
  ++stats_.messages;
  if (chunk_.size() >= options_.chunk_bytes) write_chunk();
}

void McapWriter::flush() {
  if (!chunk_.empty()) write_chunk();
  if (file_ != nullptr && std::fflush(file_) != 0) failed_ = true;
}

// The open chunk, compressed, then one Message Index per channel that has messages in it.
void McapWriter::write_chunk() {
  const bool compress = options_.zstd_level > 0;
  const std::uint8_t* records = chunk_.data();
  std::size_t records_size = chunk_.size();
  if (compress) {
    compressed_.resize(ZSTD_compressBound(chunk_.size()));
    const std::size_t n = ZSTD_compress(compressed_.data(), compressed_.size(), chunk_.data(), chunk_.size(),
                                        options_.zstd_level);
    if (ZSTD_isError(n)) throw IoError(path_, std::string("zstd: ") + ZSTD_getErrorName(n));
    records = compressed_.data();
    records_size = n;
  }
  ChunkIndex index;
  index.start_time = chunk_start_time_;
  index.end_time = chunk_end_time_;
  index.offset = stats_.file_bytes;
  index.compressed_size = records_size;
  index.uncompressed_size = chunk_.size();
  record_.clear();
  const std::size_t start = begin_record(record_, Op::kChunk);
  put(record_, chunk_start_time_);
  put(record_, chunk_end_time_);
  put(record_, static_cast<std::uint64_t>(chunk_.size()));
  put(record_, crc32_of(0, chunk_.data(), chunk_.size()));
  put_string(record_, compress ? "zstd" : "");
  put(record_, static_cast<std::uint64_t>(records_size));
  const std::uint64_t length = record_.size() - start + records_size;
  std::memcpy(record_.data() + start - 8, &length, 8);
  emit(record_);
  emit(records, records_size);
  index.length = mcap::kRecordPrefixBytes + length;

  const std::uint64_t indexes_start = stats_.file_bytes;
  for (ChannelInfo& channel : channels_) {
    if (channel.index.empty()) continue;
    index.index_offsets.emplace_back(channel.id, stats_.file_bytes);
    record_.clear();
    const std::size_t s = begin_record(record_, Op::kMessageIndex);
    put(record_, channel.id);
    put(record_, static_cast<std::uint32_t>(channel.index.size()));
    record_.insert(record_.end(), channel.index.begin(), channel.index.end());
    end_record(record_, s);
    emit(record_);
    channel.index.clear();
  }
  index.index_length = stats_.file_bytes - indexes_start;
  chunk_indexes_.push_back(std::move(index));
  stats_.uncompressed_bytes += chunk_.size();
  ++stats_.chunks;
  chunk_.clear();
  chunk_start_time_ = chunk_end_time_ = 0;
  if (std::fflush(file_) != 0) failed_ = true;
}

// The summary section (records grouped by opcode) and, in `offsets`, its Summary Offset records.
std::vector<std::uint8_t> McapWriter::summary_section(std::uint64_t start, std::vector<std::uint8_t>& offsets) const {
  std::vector<std::uint8_t> out;
  auto group = [&](Op op, auto&& write_records) {
    const std::size_t begin = out.size();
    write_records();
    if (out.size() == begin) return;
    const std::size_t s = begin_record(offsets, Op::kSummaryOffset);
    put(offsets, static_cast<std::uint8_t>(op));
    put(offsets, start + begin);
    put(offsets, static_cast<std::uint64_t>(out.size() - begin));
    end_record(offsets, s);
  };
  group(Op::kSchema, [&] {
    for (const auto& r : schema_records_) out.insert(out.end(), r.begin(), r.end());
  });
  group(Op::kChannel, [&] {
    for (const ChannelInfo& c : channels_) out.insert(out.end(), c.record.begin(), c.record.end());
  });
  group(Op::kStatistics, [&] {
    const std::size_t s = begin_record(out, Op::kStatistics);
    put(out, stats_.messages);
    put(out, static_cast<std::uint16_t>(schema_records_.size()));
    put(out, static_cast<std::uint32_t>(channels_.size()));
    put(out, std::uint32_t{0});  // attachments
    put(out, static_cast<std::uint32_t>(metadata_indexes_.size()));
    put(out, static_cast<std::uint32_t>(chunk_indexes_.size()));
    put(out, file_start_time_);
    put(out, file_end_time_);
    const std::size_t m = begin_prefixed(out);
    for (const ChannelInfo& c : channels_) {
      put(out, c.id);
      put(out, c.count);
    }
    end_prefixed(out, m);
    end_record(out, s);
  });
  group(Op::kChunkIndex, [&] {
    for (const ChunkIndex& c : chunk_indexes_) {
      const std::size_t s = begin_record(out, Op::kChunkIndex);
      put(out, c.start_time);
      put(out, c.end_time);
      put(out, c.offset);
      put(out, c.length);
      const std::size_t m = begin_prefixed(out);
      for (const auto& [channel, offset] : c.index_offsets) {
        put(out, channel);
        put(out, offset);
      }
      end_prefixed(out, m);
      put(out, c.index_length);
      put_string(out, options_.zstd_level > 0 ? "zstd" : "");
      put(out, c.compressed_size);
      put(out, c.uncompressed_size);
      end_record(out, s);
    }
  });
  group(Op::kMetadataIndex, [&] {
    for (const MetadataIndex& m : metadata_indexes_) {
      const std::size_t s = begin_record(out, Op::kMetadataIndex);
      put(out, m.offset);
      put(out, m.length);
      put_string(out, m.name);
      end_record(out, s);
    }
  });
  return out;
}

void McapWriter::close() {
  if (closed_) return;
  closed_ = true;
  flush();
  record_.clear();
  const std::size_t s = begin_record(record_, Op::kDataEnd);
  put(record_, data_crc_);
  end_record(record_, s);
  emit(record_);

  const std::uint64_t summary_start = stats_.file_bytes;
  std::vector<std::uint8_t> offsets;
  std::vector<std::uint8_t> summary = summary_section(summary_start, offsets);
  const std::uint64_t offsets_start = summary_start + summary.size();
  summary.insert(summary.end(), offsets.begin(), offsets.end());
  // Footer: the summary CRC covers the summary, its offsets and the footer up to summary_offset_start.
  summary.push_back(static_cast<std::uint8_t>(Op::kFooter));
  put(summary, std::uint64_t{20});
  put(summary, summary_start);
  put(summary, offsets.empty() ? std::uint64_t{0} : offsets_start);
  put(summary, crc32_of(0, summary.data(), summary.size()));
  emit(summary);
  emit(mcap::kMagic.data(), mcap::kMagic.size());
  const bool close_failed = std::fclose(file_) != 0;
  file_ = nullptr;
  if (failed_ || close_failed) throw IoError(path_, "writing the MCAP file failed (disk full?)");
}

}  // namespace phri
