// ctest-labels: unit
// The MCAP log: CDR bytes against a hand-laid layout; McapWriter -> read_mcap round trips of random
// messages over many chunks (stored and zstd); a file cut at every byte reads a prefix of intact
// messages and never throws; corrupt chunks, unknown compressions and non-MCAP files refused by
// name; the Logger's MCAP exported to CSV equals its CSV log byte for byte, for rows of random bit
// patterns (NaN, infinities, -0, subnormals). The independent reader (the ecosystem's @mcap/core and
// rosmsg2-serialization in node) checks the same files in ctest mcap_independent_read.
#include <phri/app/logger.hpp>
#include <phri/app/mcap_log.hpp>
#include <phri/core/cdr.hpp>
#include <phri/core/error.hpp>
#include <phri/core/mcap_format.hpp>
#include <phri/core/mcap_reader.hpp>
#include <phri/core/mcap_writer.hpp>

#include "temp_dir.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <limits>
#include <random>
#include <string>
#include <thread>
#include <vector>

namespace {

std::string temp_path(const std::string& name) { return phri::test::temp_path("phri_test_mcap", name); }

std::vector<std::uint8_t> file_bytes(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}
void write_bytes(const std::string& path, const std::vector<std::uint8_t>& bytes, std::size_t count) {
  std::ofstream(path, std::ios::binary).write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(count));
}

TEST(Cdr, LaysOutPrimitivesStringsAndSequencesAlignedFromTheEndOfTheHeader) {
  std::vector<std::uint8_t> bytes;
  phri::CdrWriter cdr(bytes);
  cdr.put(std::int32_t{1});
  cdr.put_string("ab");
  cdr.put(0.5);
  const double seq[2] = {1.0, -2.0};
  cdr.put_sequence(seq, 2);
  // header | int32 at 0 | string length 3 at 4, "ab\0" at 8..10 | 5 pad bytes | double at 16 |
  // count 2 at 24 | 4 pad bytes | doubles at 32, 40
  std::vector<std::uint8_t> expected = {0x00, 0x01, 0x00, 0x00, 1, 0, 0, 0, 3, 0, 0, 0, 'a', 'b', 0, 0, 0, 0, 0, 0};
  auto append_double = [&](double v) {
    std::uint8_t b[8];
    std::memcpy(b, &v, 8);
    expected.insert(expected.end(), b, b + 8);
  };
  append_double(0.5);
  expected.insert(expected.end(), {2, 0, 0, 0, 0, 0, 0, 0});
  append_double(1.0);
  append_double(-2.0);
  EXPECT_EQ(bytes, expected);

  phri::CdrReader in(bytes.data(), bytes.size(), "test");
  EXPECT_EQ(in.get<std::int32_t>(), 1);
  EXPECT_EQ(in.get_string(), "ab");
  EXPECT_EQ(in.get<double>(), 0.5);
  EXPECT_EQ(in.get<std::uint32_t>(), 2u);
  EXPECT_EQ(in.get<double>(), 1.0);
  EXPECT_EQ(in.get<double>(), -2.0);
  EXPECT_EQ(in.remaining(), 0u);
  EXPECT_THROW(in.get<double>(), phri::IoError);
}

struct SentMessage {
  std::uint16_t channel;
  std::uint64_t time_ns;
  std::vector<std::uint8_t> data;
};

// `count` random messages over three channels, small chunks so that there are many.
std::vector<SentMessage> write_random_file(const std::string& path, int zstd_level, int count, std::uint32_t seed) {
  std::mt19937 rng(seed);
  phri::McapWriter mcap(path, {.profile = "ros2", .library = "test", .chunk_bytes = 2000, .zstd_level = zstd_level});
  const auto schema = mcap.add_schema("test_msgs/msg/Blob", "ros2msg", "uint8[] data\n");
  std::vector<std::uint16_t> channels;
  for (const char* topic : {"/a", "/b", "/c"}) channels.push_back(mcap.add_channel(schema, topic, "cdr", {{"k", topic}}));
  mcap.add_metadata("info", {{"key", "value"}});
  std::vector<SentMessage> sent;
  for (int i = 0; i < count; ++i) {
    SentMessage m{channels[rng() % 3], 1000u * static_cast<std::uint64_t>(i), {}};
    m.data.resize(rng() % 300);
    for (auto& b : m.data) b = static_cast<std::uint8_t>(rng() % 7);  // compressible
    mcap.write(m.channel, m.time_ns, m.data.data(), m.data.size());
    sent.push_back(std::move(m));
  }
  mcap.close();
  EXPECT_GT(mcap.stats().chunks, 5u);
  return sent;
}

struct ReadBack {
  std::vector<SentMessage> messages;
  std::vector<std::uint32_t> sequences;
  std::map<std::string, std::string> metadata;
  phri::McapReadSummary summary;
};
ReadBack read_back(const std::string& path) {
  ReadBack out;
  phri::McapVisitor v;
  v.on_message = [&](const phri::McapChannel& c, const phri::McapMessage& m) {
    out.messages.push_back({c.id, m.log_time_ns, std::vector<std::uint8_t>(m.data, m.data + m.size)});
    out.sequences.push_back(m.sequence);
    EXPECT_EQ(m.publish_time_ns, m.log_time_ns);
    ASSERT_NE(c.schema, nullptr);
    EXPECT_EQ(c.schema->name, "test_msgs/msg/Blob");
    EXPECT_EQ(c.metadata.at("k"), c.topic);
  };
  v.on_metadata = [&](const std::string& name, const std::map<std::string, std::string>& m) {
    if (name == "info") out.metadata = m;
  };
  out.summary = phri::read_mcap(path, v);
  return out;
}

TEST(McapWriter, EveryMessageReadsBackInOrderWithItsChannelTimeAndSequence) {
  for (int level : {0, 3}) {
    const std::string path = temp_path("random_" + std::to_string(level) + ".mcap");
    const std::vector<SentMessage> sent = write_random_file(path, level, 400, 7u + static_cast<std::uint32_t>(level));
    const ReadBack back = read_back(path);
    EXPECT_TRUE(back.summary.complete);
    EXPECT_FALSE(back.summary.truncated);
    EXPECT_EQ(back.summary.profile, "ros2");
    EXPECT_EQ(back.summary.library, "test");
    EXPECT_EQ(back.metadata.at("key"), "value");
    ASSERT_EQ(back.messages.size(), sent.size());
    std::map<std::uint16_t, std::uint32_t> next_sequence;
    for (std::size_t i = 0; i < sent.size(); ++i) {
      EXPECT_EQ(back.messages[i].channel, sent[i].channel);
      EXPECT_EQ(back.messages[i].time_ns, sent[i].time_ns);
      EXPECT_EQ(back.messages[i].data, sent[i].data);
      EXPECT_EQ(back.sequences[i], next_sequence[sent[i].channel]++);
    }
  }
}

TEST(McapReader, AFileCutAtAnyByteReadsAPrefixOfIntactMessagesAndSaysItIsCutShort) {
  const std::string path = temp_path("whole.mcap");
  const std::vector<SentMessage> sent = write_random_file(path, 3, 120, 11u);
  const std::vector<std::uint8_t> whole = file_bytes(path);
  const std::string cut = temp_path("cut.mcap");
  std::size_t previous = 0;
  for (std::size_t size = phri::mcap::kMagic.size(); size < whole.size(); size += 7) {
    write_bytes(cut, whole, size);
    ReadBack back;
    ASSERT_NO_THROW(back = read_back(cut)) << "cut at byte " << size;
    ASSERT_LE(back.messages.size(), sent.size());
    for (std::size_t i = 0; i < back.messages.size(); ++i) ASSERT_EQ(back.messages[i].data, sent[i].data);
    EXPECT_GE(back.messages.size(), previous) << "a longer prefix reads fewer messages";
    previous = back.messages.size();
    EXPECT_FALSE(back.summary.complete && size < whole.size() - phri::mcap::kMagic.size());
    EXPECT_LE(back.summary.valid_bytes, size);
  }
  EXPECT_EQ(previous, sent.size()) << "the summary cut off loses no message";
  write_bytes(cut, whole, whole.size() / 2);
  const ReadBack half = read_back(cut);
  EXPECT_TRUE(half.summary.truncated);
  EXPECT_GT(half.messages.size(), sent.size() / 4);
  EXPECT_LT(half.messages.size(), sent.size());
}

TEST(McapReader, RefusesACorruptChunkAnUnknownCompressionAndAFileThatIsNotMcap) {
  for (int level : {0, 3}) {
    const std::string path = temp_path("corrupt.mcap");
    write_random_file(path, level, 200, 5u);
    std::vector<std::uint8_t> bytes = file_bytes(path);
    // The first chunk's records start after magic, header, schema, 3 channels and the metadata:
    // flip a byte in the middle of the file, inside some chunk's records.
    bytes[bytes.size() / 2] ^= 0x5A;
    write_bytes(path, bytes, bytes.size());
    EXPECT_THROW(read_back(path), phri::IoError) << "zstd level " << level;
  }
  // A stored chunk labelled lz4, laid out by hand.
  std::vector<std::uint8_t> file(phri::mcap::kMagic.begin(), phri::mcap::kMagic.end());
  std::size_t s = phri::mcap::begin_record(file, phri::mcap::Op::kHeader);
  phri::mcap::put_string(file, "ros2");
  phri::mcap::put_string(file, "hand");
  phri::mcap::end_record(file, s);
  s = phri::mcap::begin_record(file, phri::mcap::Op::kChunk);
  for (int i = 0; i < 3; ++i) phri::mcap::put(file, std::uint64_t{0});
  phri::mcap::put(file, std::uint32_t{0});
  phri::mcap::put_string(file, "lz4");
  phri::mcap::put(file, std::uint64_t{0});
  phri::mcap::end_record(file, s);
  const std::string lz4 = temp_path("lz4.mcap");
  write_bytes(lz4, file, file.size());
  try {
    read_back(lz4);
    ADD_FAILURE() << "an lz4 chunk was read";
  } catch (const phri::IoError& e) {
    EXPECT_NE(std::string(e.what()).find("'lz4'"), std::string::npos) << e.what();
  }
  const std::string csv = temp_path("not.mcap");
  std::ofstream(csv) << "time_s,cycle\n0,1\n";
  EXPECT_THROW(read_back(csv), phri::IoError);
  EXPECT_FALSE(phri::is_mcap_file(csv));
  EXPECT_THROW(read_back(temp_path("missing.mcap")), phri::IoError);
}

// Fills a row's every 8-byte cell with a random bit pattern (NaN, infinities, -0, subnormals).
struct RandomFill {
  std::mt19937_64& rng;
  double value() {
    const std::uint64_t pick = rng() % 8;
    if (pick == 0) return std::numeric_limits<double>::quiet_NaN();
    if (pick == 1) return -std::numeric_limits<double>::infinity();
    if (pick == 2) return -0.0;
    if (pick == 3) return std::numeric_limits<double>::denorm_min() * static_cast<double>(rng() % 1000);
    const std::uint64_t bits = rng();
    double v;
    std::memcpy(&v, &bits, 8);
    return std::isnan(v) ? 1.0 : v;  // a NaN's payload is not kept by the CSV's text either
  }
  void number(const char*, double& v) { v = value(); }
  void integer(const char*, std::int64_t& v) { v = static_cast<std::int64_t>(rng()); }
  void integer(const char*, std::int32_t& v) { v = static_cast<std::int32_t>(rng()); }
  template <std::size_t N>
  void joints(const char*, std::array<double, N>& a, int) {
    for (double& v : a) v = value();
  }
};

std::vector<phri::LogRow> random_rows(int count, std::uint32_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<phri::LogRow> rows(static_cast<std::size_t>(count));
  for (std::size_t i = 0; i < rows.size(); ++i) {
    visit_log_columns(rows[i], phri::kLogMaxJoints, RandomFill{rng});
    rows[i].time_s = 0.001 * static_cast<double>(i);  // the message times: increasing
  }
  return rows;
}

TEST(McapLog, ExportsToTheCsvTheLoggerWritesByteForByteAndReadsBackEveryCell) {
  for (int dof : {6, 7}) {
    const std::vector<phri::LogRow> rows = random_rows(3000, 42u + static_cast<std::uint32_t>(dof));
    phri::LoggerSettings csv_settings;
    csv_settings.path = temp_path("rows_" + std::to_string(dof) + ".csv");
    csv_settings.dof = dof;
    csv_settings.pfl_links = {"a", "b"};
    phri::LoggerSettings mcap_settings = csv_settings;
    mcap_settings.path = temp_path("rows_" + std::to_string(dof) + ".mcap");
    mcap_settings.format = phri::LogFormat::kMcap;
    mcap_settings.mcap_chunk_bytes = 64 << 10;
    mcap_settings.joint_names = {"j1", "j2", "j3", "j4", "j5", "j6", "j7"};
    mcap_settings.joint_names.resize(static_cast<std::size_t>(dof));
    mcap_settings.has_ft_sensor = true;
    {
      phri::Logger csv(csv_settings), mcap(mcap_settings);
      for (const phri::LogRow& r : rows) {
        while (!csv.push(r)) std::this_thread::yield();
        while (!mcap.push(r)) std::this_thread::yield();
      }
      EXPECT_FALSE(csv.close().write_error);
      const phri::LoggerStats stats = mcap.close();
      EXPECT_FALSE(stats.write_error);
      EXPECT_EQ(stats.written, rows.size());
    }
    const std::string exported = temp_path("exported_" + std::to_string(dof) + ".csv");
    const phri::McapLogInfo info = phri::export_mcap_log_csv(mcap_settings.path, exported, true);
    EXPECT_EQ(info.rows, rows.size());
    EXPECT_EQ(info.dof, dof);
    EXPECT_TRUE(info.file.complete);
    EXPECT_EQ(file_bytes(exported), file_bytes(csv_settings.path)) << "dof " << dof;
    EXPECT_EQ(file_bytes(phri::Logger::legend_path_for(exported)), file_bytes(phri::Logger::legend_path_for(csv_settings.path)));
    EXPECT_FALSE(std::filesystem::exists(phri::Logger::legend_path_for(mcap_settings.path)))
        << "an MCAP log carries its legend inside";

    // Cell by cell, bit for bit (a NaN is a NaN: its payload is not promised).
    std::size_t i = 0;
    phri::read_mcap_log(mcap_settings.path, [&](const phri::LogRow& got, int got_dof) {
      ASSERT_EQ(got_dof, dof);
      const std::string a = [&] {
        std::vector<char> line(phri::Logger::kMaxCsvLineBytes);
        return std::string(line.data(), phri::Logger::csv_line(got, dof, line.data(), line.data() + line.size()));
      }();
      std::vector<char> line(phri::Logger::kMaxCsvLineBytes);
      const std::string b(line.data(), phri::Logger::csv_line(rows[i], dof, line.data(), line.data() + line.size()));
      ASSERT_EQ(a, b) << "row " << i;
      for (std::size_t j = 0; j < static_cast<std::size_t>(dof); ++j) {
        const bool same_bits = std::memcmp(&got.tau_ext[j], &rows[i].tau_ext[j], sizeof(double)) == 0;
        EXPECT_TRUE(same_bits || (std::isnan(got.tau_ext[j]) && std::isnan(rows[i].tau_ext[j]))) << "row " << i;
      }
      ++i;
    });
    EXPECT_EQ(i, rows.size());
  }
}

TEST(McapLog, AFileWithoutACycleChannelIsNotAPhriLog) {
  const std::string path = temp_path("other.mcap");
  write_random_file(path, 3, 200, 3u);
  EXPECT_THROW(phri::read_mcap_log(path, [](const phri::LogRow&, int) {}), phri::IoError);
}

}  // namespace
