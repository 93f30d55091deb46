// ctest-labels: unit
// The SensONE's frame format and decoder (hardware/bota_protocol.hpp, bota_frame_decoder.hpp), byte
// by byte, no I/O:
//   CRC-16/X-25 against the catalogue check value ("123456789" -> 0x906E); the frame layout written
//   out by hand (little-endian, CRC low byte first); a clean stream; every fault of the serial line
//   (garbage with false headers, a corrupt CRC, a flipped byte, a dropped byte, a truncated frame,
//   NaN / infinity / absurd values, error status bits, a frame after a resync not confirmed by the
//   next header, back-to-back bursts) with its exact counters; the byte accounting invariant
//   bytes = 37 x checked frames + skipped + buffered after every byte; a seeded fuzz in which no
//   delivered frame is ever anything but a good frame that was sent; no allocation.
#include <phri/hardware/bota_frame_decoder.hpp>
#include <phri/hardware/bota_protocol.hpp>

#include "allocation_counter.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <random>
#include <string>
#include <vector>

namespace {

using phri::BotaDecoderCounters;
using phri::BotaDecoderSettings;
using phri::BotaFrame;
using phri::BotaFrameDecoder;
using Bytes = std::vector<std::uint8_t>;
constexpr std::size_t kFrameBytes = phri::kBotaFrameBytes;

Bytes encode(const BotaFrame& frame) {
  const auto bytes = phri::encode_bota_frame(frame);
  return Bytes(bytes.begin(), bytes.end());
}

// Frame k with exactly representable values, nudged until no byte after the header is 0xAA, so
// that the only sync candidates in a test stream are the ones a test puts there (timestamps odd:
// their low byte is never 0xAA, and k stays small).
BotaFrame clean_frame(int k) {
  BotaFrame f;
  f.wrench = {1.5f * k, -2.0f, 10.25f, 0.125f * k, -0.5f, 0.0f};
  f.timestamp = static_cast<std::uint32_t>(2 * k + 1);
  f.temperature = 30.0f;
  for (;;) {
    const Bytes b = encode(f);
    const auto header = std::find(b.begin() + 1, b.end(), 0xAA);
    if (header == b.end()) return f;
    const auto offset = static_cast<std::size_t>(header - b.begin()) - 1;  // in the data
    if (offset >= 2 && offset < 26) {
      f.wrench[(offset - 2) / 4] += 0.03125f;
    } else {
      f.temperature += 0.0625f;
    }
  }
}

struct Fed {
  std::vector<BotaFrame> frames;
  std::vector<std::size_t> at;  // index of the byte that delivered each frame
};

// Feeds every byte, checking the accounting invariant after each one.
Fed feed(BotaFrameDecoder& decoder, const Bytes& bytes) {
  Fed out;
  for (std::size_t i = 0; i < bytes.size(); ++i) {
    if (decoder.push(bytes[i])) {
      out.frames.push_back(decoder.frame());
      out.at.push_back(i);
    }
    const BotaDecoderCounters& c = decoder.counters();
    const std::uint64_t checked = c.frames_ok + c.status_errors + c.invalid_values;
    EXPECT_EQ(c.bytes, kFrameBytes * checked + c.bytes_skipped + decoder.buffered()) << "after byte " << i;
  }
  return out;
}

void append(Bytes& to, const Bytes& more) { to.insert(to.end(), more.begin(), more.end()); }

Bytes frames(int first, int count) {
  Bytes out;
  for (int k = first; k < first + count; ++k) append(out, encode(clean_frame(k)));
  return out;
}

BotaDecoderCounters counters(std::uint64_t bytes, std::uint64_t ok) {
  BotaDecoderCounters c;
  c.bytes = bytes;
  c.frames_ok = ok;
  return c;
}

TEST(BotaCrc, MatchesTheCatalogueCheckValueOfCrc16X25) {
  const std::string check = "123456789";
  const Bytes bytes(check.begin(), check.end());
  EXPECT_EQ(phri::crc16_x25(bytes), 0x906E);
  EXPECT_EQ(phri::crc16_x25({}), 0x0000);  // init 0xFFFF, final xor 0xFFFF
}

TEST(BotaFrameLayout, IsLittleEndianWithTheCrcOverTheDataBytesLowByteFirst) {
  Bytes bytes(kFrameBytes, 0);
  bytes[0] = 0xAA;
  bytes[1] = 0x02;  // status 0x0102
  bytes[2] = 0x01;
  const float values[6] = {1.0f, -2.0f, 0.5f, 3.25f, -0.125f, 100.0f};
  for (int i = 0; i < 6; ++i) std::memcpy(&bytes[3 + 4 * i], &values[i], 4);  // x86 is little-endian
  const std::uint8_t stamp[4] = {0x44, 0x33, 0x22, 0x11};                    // 0x11223344
  std::memcpy(&bytes[27], stamp, 4);
  const float temperature = 36.5f;
  std::memcpy(&bytes[31], &temperature, 4);
  const std::uint16_t crc = phri::crc16_x25({bytes.data() + 1, 34});
  bytes[35] = static_cast<std::uint8_t>(crc & 0xFF);
  bytes[36] = static_cast<std::uint8_t>(crc >> 8);

  BotaFrame expected;
  expected.status = 0x0102;
  std::copy(values, values + 6, expected.wrench.begin());
  expected.timestamp = 0x11223344;
  expected.temperature = 36.5f;
  EXPECT_EQ(encode(expected), bytes);
  const BotaFrame parsed = phri::parse_bota_data(std::span<const std::uint8_t, 34>(bytes.data() + 1, 34));
  EXPECT_EQ(parsed, expected);
}

TEST(BotaFrameDecoder, DeliversACleanStreamHoldingOnlyTheFirstFrameForItsConfirmation) {
  BotaFrameDecoder decoder;
  const Fed fed = feed(decoder, frames(0, 5));
  ASSERT_EQ(fed.frames.size(), 5u);
  // The first frame (no sync yet) waits for the next header, byte 37; in sync, each frame comes
  // with its own last byte.
  EXPECT_EQ(fed.at[0], kFrameBytes);
  for (std::size_t i = 1; i < 5; ++i) EXPECT_EQ(fed.at[i], (i + 1) * kFrameBytes - 1);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_EQ(fed.frames[i], clean_frame(static_cast<int>(i)));
  EXPECT_EQ(decoder.counters(), counters(5 * kFrameBytes, 5));
  EXPECT_EQ(decoder.buffered(), 0u);
}

TEST(BotaFrameDecoder, ResynchronisesAfterLeadingGarbageWithoutHeaders) {
  BotaFrameDecoder decoder;
  Bytes stream = {0x00, 0x13, 0xFF, 0x55, 0x7E};
  append(stream, frames(0, 3));
  const Fed fed = feed(decoder, stream);
  ASSERT_EQ(fed.frames.size(), 3u);
  EXPECT_EQ(fed.frames[0], clean_frame(0));
  BotaDecoderCounters expected = counters(stream.size(), 3);
  expected.bytes_skipped = 5;
  expected.resyncs = 1;
  EXPECT_EQ(decoder.counters(), expected);
}

TEST(BotaFrameDecoder, GarbageWithFalseHeadersBetweenFramesCostsNoFrame) {
  BotaFrameDecoder decoder;
  Bytes stream = frames(0, 2);
  // Three false headers, the last one 10 bytes before the real frame: its candidate swallows
  // the real frame's first 27 bytes, fails the CRC, and the search restarts inside it.
  const Bytes garbage = {0x01, 0xAA, 0x02, 0x03, 0xAA, 0xAA, 0x10, 0x11, 0x12, 0x13, 0x14, 0x15, 0x16, 0x17, 0x18};
  append(stream, garbage);
  append(stream, frames(2, 3));
  const Fed fed = feed(decoder, stream);
  ASSERT_EQ(fed.frames.size(), 5u);
  for (std::size_t i = 0; i < 5; ++i) EXPECT_EQ(fed.frames[i], clean_frame(static_cast<int>(i)));
  BotaDecoderCounters expected = counters(stream.size(), 5);
  expected.crc_errors = 3;
  expected.bytes_skipped = garbage.size();
  expected.resyncs = 1;
  EXPECT_EQ(decoder.counters(), expected);
}

// One damaged frame between good ones: it is dropped, its neighbours are not, and the counters
// say exactly what happened.
struct DamageCase {
  const char* name;
  Bytes (*damage)(Bytes frame);
  std::uint64_t skipped;
};

const DamageCase kDamageCases[] = {
    {"corrupt_crc", [](Bytes f) { f[35] ^= 0x01; return f; }, kFrameBytes},
    {"flipped_data_byte", [](Bytes f) { f[12] ^= 0x10; return f; }, kFrameBytes},
    {"flipped_header", [](Bytes f) { f[0] = 0xAB; return f; }, kFrameBytes},
    {"dropped_byte", [](Bytes f) { f.erase(f.begin() + 20); return f; }, kFrameBytes - 1},
    {"truncated_after_header", [](Bytes f) { f.resize(1); return f; }, 1},
    {"truncated_mid_frame", [](Bytes f) { f.resize(19); return f; }, 19},
    {"truncated_before_crc", [](Bytes f) { f.resize(35); return f; }, 35},
};

class BotaDamagedFrame : public ::testing::TestWithParam<DamageCase> {};

TEST_P(BotaDamagedFrame, IsDroppedAloneWithExactCounters) {
  const DamageCase& c = GetParam();
  BotaFrameDecoder decoder;
  Bytes stream = frames(0, 2);
  const Bytes damaged = c.damage(encode(clean_frame(2)));
  ASSERT_EQ(std::count(damaged.begin() + 1, damaged.end(), 0xAA), 0);
  append(stream, damaged);
  append(stream, frames(3, 3));
  const Fed fed = feed(decoder, stream);
  const std::vector<int> delivered = {0, 1, 3, 4, 5};
  ASSERT_EQ(fed.frames.size(), delivered.size());
  for (std::size_t i = 0; i < delivered.size(); ++i) EXPECT_EQ(fed.frames[i], clean_frame(delivered[i]));
  // The frame after the damage is held until the next header confirms it.
  EXPECT_EQ(fed.at[2], 2 * kFrameBytes + damaged.size() + kFrameBytes);
  BotaDecoderCounters expected = counters(stream.size(), 5);
  expected.crc_errors = damaged[0] == 0xAA ? 1 : 0;  // a damaged header is only skipped, never a candidate
  expected.bytes_skipped = c.skipped;
  expected.resyncs = 1;
  EXPECT_EQ(decoder.counters(), expected);
}

INSTANTIATE_TEST_SUITE_P(Faults, BotaDamagedFrame, ::testing::ValuesIn(kDamageCases),
                         [](const auto& info) { return std::string(info.param.name); });

TEST(BotaFrameDecoder, RejectsNonFiniteAndAbsurdValuesWithAGoodCrcAndStaysInSync) {
  const float nan = std::numeric_limits<float>::quiet_NaN();
  const float inf = std::numeric_limits<float>::infinity();
  std::vector<BotaFrame> bad(5, clean_frame(2));
  bad[0].wrench[0] = nan;
  bad[1].wrench[5] = inf;
  bad[2].wrench[2] = -inf;
  bad[3].temperature = nan;
  bad[4].wrench[3] = 1e30f;
  BotaFrameDecoder decoder;
  Bytes stream = frames(0, 2);
  for (const BotaFrame& f : bad) append(stream, encode(f));
  append(stream, frames(3, 1));
  const Fed fed = feed(decoder, stream);
  ASSERT_EQ(fed.frames.size(), 3u);
  EXPECT_EQ(fed.frames[2], clean_frame(3));
  EXPECT_EQ(fed.at[2], stream.size() - 1);  // still in sync: delivered with its last byte
  for (const BotaFrame& f : fed.frames)
    for (float v : f.wrench) EXPECT_TRUE(std::isfinite(v));
  BotaDecoderCounters expected = counters(stream.size(), 3);
  expected.invalid_values = 5;
  EXPECT_EQ(decoder.counters(), expected);
}

TEST(BotaFrameDecoder, RejectsFramesWithStatusBitsInTheMaskAndTheMaskIsConfigurable) {
  Bytes stream = frames(0, 1);
  for (int bit = 0; bit < 16; ++bit) {
    BotaFrame f = clean_frame(1 + bit);
    f.status = static_cast<std::uint16_t>(1u << bit);
    append(stream, encode(f));
  }
  append(stream, frames(17, 1));

  BotaFrameDecoder strict;  // default: any set bit is an error
  EXPECT_EQ(feed(strict, stream).frames.size(), 2u);
  EXPECT_EQ(strict.counters().status_errors, 16u);

  BotaFrameDecoder lenient(BotaDecoderSettings{.status_error_mask = 0x0000});
  EXPECT_EQ(feed(lenient, stream).frames.size(), 18u);

  BotaFrameDecoder some(BotaDecoderSettings{.status_error_mask = 0x00F0});
  const Fed fed = feed(some, stream);
  EXPECT_EQ(fed.frames.size(), 14u);
  EXPECT_EQ(some.counters().status_errors, 4u);
  for (const BotaFrame& f : fed.frames) EXPECT_EQ(f.status & 0x00F0, 0);
}

TEST(BotaFrameDecoder, AFrameAfterAResyncNotFollowedByAHeaderIsNeverDelivered) {
  BotaFrameDecoder decoder;
  Bytes stream = {0x42};             // lost sync
  append(stream, frames(0, 1));      // CRC good, but unconfirmed...
  stream.push_back(0x00);            // ...followed by garbage
  append(stream, frames(1, 2));
  const Fed fed = feed(decoder, stream);
  ASSERT_EQ(fed.frames.size(), 2u);
  EXPECT_EQ(fed.frames[0], clean_frame(1));
  BotaDecoderCounters expected = counters(stream.size(), 2);
  expected.unconfirmed = 1;
  expected.bytes_skipped = 1 + kFrameBytes + 1;
  expected.resyncs = 1;  // one run of skipped bytes
  EXPECT_EQ(decoder.counters(), expected);
}

TEST(BotaFrameDecoder, BackToBackBurstsAndSplitChunksDecodeTheSame) {
  const Bytes stream = frames(0, 200);
  BotaFrameDecoder decoder;
  const Fed fed = feed(decoder, stream);
  ASSERT_EQ(fed.frames.size(), 200u);
  for (std::size_t i = 0; i < 200; ++i) ASSERT_EQ(fed.frames[i], clean_frame(static_cast<int>(i)));
  EXPECT_EQ(decoder.counters(), counters(stream.size(), 200));
}

TEST(BotaFrameDecoder, ResetDropsAPartialFrameAndCountsItsBytes) {
  BotaFrameDecoder decoder;
  Bytes stream = frames(0, 2);
  const Bytes next = encode(clean_frame(2));
  stream.insert(stream.end(), next.begin(), next.begin() + 10);
  feed(decoder, stream);
  EXPECT_EQ(decoder.buffered(), 10u);
  decoder.reset();
  EXPECT_EQ(decoder.buffered(), 0u);
  const Fed after = feed(decoder, frames(3, 2));
  ASSERT_EQ(after.frames.size(), 2u);  // out of sync after the reset: the first is confirmed by the second's header
  EXPECT_EQ(after.frames[0], clean_frame(3));
  EXPECT_EQ(decoder.counters().bytes_skipped, 10u);
}

// Random frames (0xAA allowed anywhere in them) mixed with every fault at random: whatever the
// decoder delivers is a good frame that was sent, in order, and most good frames get through.
TEST(BotaFrameDecoder, FuzzNeverDeliversAFrameThatWasNotSentIntact) {
  for (std::uint32_t seed : {1u, 2u, 3u, 4u, 5u}) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> value(-200.0f, 200.0f);
    std::uniform_int_distribution<int> byte(0, 255), fault(0, 9), position(0, 36);
    std::vector<BotaFrame> good;
    Bytes stream;
    for (int k = 0; k < 3000; ++k) {
      BotaFrame f;
      for (float& v : f.wrench) v = value(rng);
      f.timestamp = static_cast<std::uint32_t>(k);
      f.temperature = value(rng);
      Bytes b = encode(f);
      switch (fault(rng)) {
        case 0: b[static_cast<std::size_t>(position(rng))] ^= static_cast<std::uint8_t>(1 + byte(rng) % 255); break;
        case 1: b.erase(b.begin() + position(rng)); break;
        case 2: b.resize(static_cast<std::size_t>(position(rng))); break;
        case 3:  // garbage with false headers, then the frame intact
          for (int i = 0; i < 1 + byte(rng); ++i) stream.push_back(static_cast<std::uint8_t>(i % 7 == 0 ? 0xAA : byte(rng)));
          good.push_back(f);
          break;
        case 4: f.wrench[0] = std::numeric_limits<float>::quiet_NaN(); b = encode(f); break;
        case 5: f.status = 0x0008; b = encode(f); break;
        default: good.push_back(f); break;
      }
      append(stream, b);
    }
    BotaFrameDecoder decoder;
    const Fed fed = feed(decoder, stream);
    std::size_t g = 0;
    for (const BotaFrame& f : fed.frames) {
      while (g < good.size() && !(good[g] == f)) ++g;
      ASSERT_LT(g, good.size()) << "seed " << seed << ": a frame was delivered that was not sent intact (timestamp "
                                << f.timestamp << ")";
      ++g;
    }
    EXPECT_GT(fed.frames.size(), good.size() * 8 / 10) << "seed " << seed;
  }
}

TEST(BotaFrameDecoder, AllocatesNothing) {
  const Bytes stream = frames(0, 50);
  BotaFrameDecoder decoder;
  int delivered = 0;
  phri::test::AllocationCounter count;
  for (std::uint8_t b : stream) delivered += decoder.push(b) ? 1 : 0;
  EXPECT_EQ(count.allocations(), 0u);
  EXPECT_EQ(delivered, 50);
}

}  // namespace
